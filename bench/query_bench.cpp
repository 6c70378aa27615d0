// SPDX-License-Identifier: MIT
// bspf_query_bench: nanoseconds per call of each scene query
// (bspf/scene_query.h) on one compiled level, beside Bullet's ray test and
// convex cast of the same rays and paths in the same run (when built with
// Bullet: libbullet-dev). Each figure is the median over --repeats timed
// passes of the whole query set, in the thread's CPU time (POSIX). Queries start near the level's
// surfaces, on their front side, where a game's eyes, bullets and bodies are (fixed seed). Also
// prints how often Bullet's closest hit agrees with castRay (both faces) and castEllipsoid: the
// same fraction within 1e-3 of the path. Prints one JSON object.
//
//   bspf_query_bench LEVEL.bspf [--queries N] [--repeats R] [--ray-length M]
#include <bspf/scene_query.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <random>
#include <string>
#include <vector>

#include "support/cli.h"
#ifdef BSPF_HAVE_BULLET
#include "bullet_peer.h"
#endif

namespace {

using bspf::Vec3;

// This thread's CPU time, nanoseconds: on a machine shared with other work
// it counts only the time the queries ran, not the time they waited.
double threadCpuNs() {
  timespec now{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &now);
  return double(now.tv_sec) * 1e9 + double(now.tv_nsec);
}

// The median nanoseconds (thread CPU time) per query of `repeats` timed
// passes of `pass`, which runs `count` queries.
template <typename Pass>
double medianNs(int repeats, std::size_t count, Pass&& pass) {
  std::vector<double> perCall;
  for (int r = 0; r < repeats; ++r) {
    const double start = threadCpuNs();
    pass();
    perCall.push_back((threadCpuNs() - start) / double(count));
  }
  std::sort(perCall.begin(), perCall.end());
  return perCall[perCall.size() / 2];
}

// Keeps a result alive so the timed loops are not optimised away.
volatile float gSink = 0;

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "bspf_query_bench: nanoseconds per call of each scene query (castRay, castRays, "
      "castEllipsoid, overlapsEllipsoid, closestPoint) on one compiled level, beside Bullet's "
      "ray test and convex cast from the same run. Prints one JSON object.\n\nExample:\n"
      "  bspf_query_bench out/oa_dm4.bspf --queries 20000 --repeats 5",
      "bspf_query_bench"};
  std::string levelPath;
  int queries = 20000, repeats = 5;
  float rayLength = 50, travel = 0.7f, reach = 1;
  app.add_option("level", levelPath, "The compiled level (.bspf)")->required();
  app.add_option("--queries", queries, "Random queries of each kind")
      ->check(CLI::Range(1, 10000000))
      ->capture_default_str();
  app.add_option("--repeats", repeats, "Timed passes over the queries (the median is kept)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--ray-length", rayLength, "Rays' maxDistance, metres")
      ->check(CLI::Range(0.0f, 1e5f))
      ->capture_default_str();
  app.add_option("--travel", travel, "Length of each ellipsoid cast, metres")
      ->check(CLI::Range(0.0f, 1000.0f))
      ->capture_default_str();
  app.add_option("--reach", reach, "closestPoint's maxDistance, metres")
      ->check(CLI::Range(0.0f, 1000.0f))
      ->capture_default_str();
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;
  const bspf::OpenResult opened = bspf::openWorld(levelPath);
  if (!opened) {
    std::fprintf(stderr, "bspf_query_bench: error: %s\n", opened.message.c_str());
    return 1;
  }
  const bspf::World& world = *opened.world;
  if (world.triangles().empty()) {
    std::fprintf(stderr, "bspf_query_bench: error: %s: the level has no triangles\n",
                 levelPath.c_str());
    return 1;
  }
  const bspf::EllipsoidRadii radii{0.45f, 0.85f};

  // Starts 0.05 to 2 m in front of a random point of a random triangle,
  // random directions.
  std::mt19937 rng(4242);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::normal_distribution<float> gauss;
  std::uniform_int_distribution<std::size_t> pick(0, world.triangles().size() - 1);
  std::vector<bspf::Ray> rays;
  for (int i = 0; i < queries; ++i) {
    // Uniform over the triangle's area: the square root of one number
    // spreads the point from the first corner to the opposite edge.
    const std::size_t t = pick(rng);
    const float spread = std::sqrt(unit(rng)), along = unit(rng);
    const auto corner = [&](std::uint32_t k) { return bspf::toVec3(world.vertices()[k]); };
    const auto& tri = world.triangles()[t];
    const Vec3 onTriangle = (1 - spread) * corner(tri.v0()) +
                            spread * ((1 - along) * corner(tri.v1()) + along * corner(tri.v2()));
    const Vec3 n = bspf::toVec3(world.trianglePlanes()[t].face().normal());
    const Vec3 start = onTriangle + n * (0.05f + 1.95f * unit(rng));
    rays.push_back({start, Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized(), rayLength});
  }
  const std::size_t count = rays.size();
  std::vector<std::optional<bspf::RayHit>> hits(count);
  bspf::QueryScratch scratch;

  const double rayNs = medianNs(repeats, count, [&] {
    for (std::size_t i = 0; i < count; ++i)
      hits[i] = bspf::castRay(world, rays[i].origin, rays[i].direction, rays[i].maxDistance);
  });
  const double rayBothNs = medianNs(repeats, count, [&] {
    for (std::size_t i = 0; i < count; ++i)
      hits[i] = bspf::castRay(world, rays[i].origin, rays[i].direction, rays[i].maxDistance,
                              bspf::RayFaces::Both);
  });
  const std::size_t rayHits =
      std::count_if(hits.begin(), hits.end(), [](const auto& h) { return h.has_value(); });
  const double batchNs =
      medianNs(repeats, count, [&] { bspf::castRays(world, rays, hits, bspf::RayFaces::Both); });
  std::vector<float> castFractions(count, -1);
  const double castNs = medianNs(repeats, count, [&] {
    for (std::size_t i = 0; i < count; ++i) {
      const Vec3& from = rays[i].origin;
      const auto hit =
          bspf::castEllipsoid(world, from, from + rays[i].direction * travel, radii, scratch);
      castFractions[i] = hit ? hit->fraction : -1.0f;
    }
  });
  std::size_t overlapping = 0;
  const double overlapNs = medianNs(repeats, count, [&] {
    overlapping = 0;
    for (std::size_t i = 0; i < count; ++i)
      overlapping += bspf::overlapsEllipsoid(world, rays[i].origin, radii, scratch);
  });
  std::size_t closestFound = 0;
  const double closestNs = medianNs(repeats, count, [&] {
    closestFound = 0;
    for (std::size_t i = 0; i < count; ++i) {
      const auto found = bspf::closestPoint(world, rays[i].origin, reach, scratch);
      closestFound += found.has_value();
      if (found) gSink = found->distance;
    }
  });

  std::printf(
      "{\"level\": \"%s\", \"triangles\": %zu, \"queries\": %zu, \"repeats\": %d, "
      "\"ray_length_m\": %g, \"travel_m\": %g, \"reach_m\": %g,\n"
      " \"castRay_ns\": %.1f, \"castRay_both_ns\": %.1f, \"castRays_both_ns_per_ray\": %.1f, "
      "\"ray_hits\": %zu,\n"
      " \"castEllipsoid_ns\": %.1f, \"overlapsEllipsoid_ns\": %.1f, \"overlapping\": %zu, "
      "\"closestPoint_ns\": %.1f, \"closest_found\": %zu",
      levelPath.c_str(), world.triangles().size(), count, repeats, rayLength, travel, reach, rayNs,
      rayBothNs, batchNs, rayHits, castNs, overlapNs, overlapping, closestNs, closestFound);
#ifdef BSPF_HAVE_BULLET
  const bspf::bench::BulletPeer bullet(world, radii);
  std::vector<float> bulletRay(count), bulletCast(count);
  const double bulletRayNs = medianNs(repeats, count, [&] {
    for (std::size_t i = 0; i < count; ++i)
      bulletRay[i] = bullet.rayFraction(rays[i].origin,
                                        rays[i].origin + rays[i].direction * rays[i].maxDistance);
  });
  const double bulletCastNs = medianNs(repeats, count, [&] {
    for (std::size_t i = 0; i < count; ++i)
      bulletCast[i] =
          bullet.castFraction(rays[i].origin, rays[i].origin + rays[i].direction * travel);
  });
  // Agreement: both miss, or both hit at the same fraction within 1e-3.
  std::size_t rayAgree = 0, castAgree = 0;
  for (std::size_t i = 0; i < count; ++i) {
    const float ours = hits[i] ? hits[i]->distance / rays[i].maxDistance : -1.0f;
    rayAgree += std::abs(ours - bulletRay[i]) <= 1e-3f;
    castAgree += std::abs(castFractions[i] - bulletCast[i]) <= 1e-3f;
  }
  std::printf(
      ",\n \"bullet_rayTest_ns\": %.1f, \"bullet_convexSweepTest_ns\": %.1f, "
      "\"bullet_ray_agree\": %zu, \"bullet_cast_agree\": %zu",
      bulletRayNs, bulletCastNs, rayAgree, castAgree);
#endif
  std::printf("}\n");
  return 0;
}
