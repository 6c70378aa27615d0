// SPDX-License-Identifier: MIT
// bspf_level_bench: what a compiled level costs the runtime.
// - open: the median time of openWorld (map and verify) over repeats;
// - query: for random swept ellipsoids near the level's surfaces (fixed seed),
//   the mean leaves visited, mean candidate triangles, and the median time
//   per query over repeats (used to choose bspc's tree defaults).
// Prints one JSON object.
//
//   bspf_level_bench LEVEL.bspf [--queries N] [--repeats R] [--travel M]
#include <bspf/query.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "support/cli.h"

int main(int argc, char** argv) {
  CLI::App app{
      "bspf_level_bench: what a compiled level costs the runtime: open (map and verify) time, "
      "and leaves, candidate triangles and time per swept-ellipsoid query. Prints one JSON "
      "object.\n\nExample:\n  bspf_level_bench out/arena.bspf --queries 5000",
      "bspf_level_bench"};
  std::string levelPath;
  int queries = 20000, repeats = 5;
  float travel = 0.7f;  // metres: one frame at 40 m/s is 0.67 m
  app.add_option("level", levelPath, "The compiled level (.bspf)")->required();
  app.add_option("--queries", queries, "Random swept ellipsoids near the level's surfaces")
      ->check(CLI::Range(1, 100000000))
      ->capture_default_str();
  app.add_option("--repeats", repeats, "Timed passes over the queries (the median is kept)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--travel", travel, "Length of each sweep, metres")
      ->check(CLI::Range(0.0f, 1000.0f))
      ->capture_default_str();
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;
  std::vector<double> openMs;
  for (int r = 0; r < std::max(repeats, 5); ++r) {
    const auto start = std::chrono::steady_clock::now();
    const bspf::OpenResult opened = bspf::openWorld(levelPath);
    const auto stop = std::chrono::steady_clock::now();
    if (!opened) break;
    openMs.push_back(std::chrono::duration<double, std::milli>(stop - start).count());
  }
  std::sort(openMs.begin(), openMs.end());
  const bspf::OpenResult opened = bspf::openWorld(levelPath);
  if (!opened) {
    std::fprintf(stderr, "bspf_level_bench: error: %s\n", opened.message.c_str());
    return 1;
  }
  const bspf::World& world = *opened.world;
  const bspf::EllipsoidRadii radii{0.45f, 0.85f};

  std::mt19937 rng(12345);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::normal_distribution<float> gauss;
  std::vector<std::pair<bspf::Vec3, bspf::Vec3>> sweeps(queries);
  // Bodies live near surfaces: start 0.2 to 1.5 m in front of a random point
  // of a random triangle.
  std::uniform_int_distribution<std::size_t> pickTriangle(0, world.triangles().size() - 1);
  for (auto& [from, to] : sweeps) {
    const std::size_t t = pickTriangle(rng);
    const bspf::schema::Triangle& tri = world.triangles()[t];
    float u = unit(rng), v = unit(rng);
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const bspf::Vec3 a = bspf::toVec3(world.vertices()[tri.v0()]);
    const bspf::Vec3 b = bspf::toVec3(world.vertices()[tri.v1()]);
    const bspf::Vec3 c = bspf::toVec3(world.vertices()[tri.v2()]);
    const bspf::Vec3 n = bspf::toVec3(world.trianglePlanes()[t].face().normal());
    from = a + u * (b - a) + v * (c - a) + n * (0.2f + 1.3f * unit(rng));
    bspf::Vec3 dir(gauss(rng), gauss(rng), gauss(rng));
    to = from + dir.normalized() * travel * unit(rng);
  }

  bspf::SweepScratch scratch;
  std::vector<std::uint32_t> candidates;
  double leafSum = 0, candidateSum = 0;
  std::vector<double> nsPerQuery;
  for (int r = 0; r < repeats; ++r) {
    leafSum = candidateSum = 0;
    const auto start = std::chrono::steady_clock::now();
    for (const auto& [from, to] : sweeps) {
      bspf::collectCandidateTriangles(world, from, to, radii, scratch, candidates);
      leafSum += scratch.leaves.size();
      candidateSum += candidates.size();
    }
    const auto stop = std::chrono::steady_clock::now();
    nsPerQuery.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / queries);
  }
  std::sort(nsPerQuery.begin(), nsPerQuery.end());
  std::printf(
      "{\"open_ms_median\":%.3f,\"queries\":%d,\"leaves_mean\":%.2f,\"candidates_mean\":%.2f,\"ns_"
      "per_query_median\":%.1f}\n",
      openMs[openMs.size() / 2], queries, leafSum / queries, candidateSum / queries,
      nsPerQuery[nsPerQuery.size() / 2]);
  return 0;
}
