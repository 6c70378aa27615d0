// SPDX-License-Identifier: MIT
// bspf_replay_bench: the movement step on one compiled level, replayed from a
// recorded crowd, with the broad phase's work per step beside its time.
//
//   bspf_replay_bench LEVEL.bspf [--spawns FILE] [--agents N] [--frames F]
//                     [--speed M_PER_S] [--method planes|exact|both] [--repeats R]
//                     [--brute-force-budget N] [--json] [--no-header]
//
// For each method, the walkers crowd (samples/walkers_sim.h: from the spawns,
// or placed on walkable floor without them) runs once, recording every body's
// state and input force just before each frame's stepBodies. Those steps are
// then replayed against the level alone (no body-against-body pushes), from
// copies of the recorded states:
//   - timed: every recorded frame in order with stepBodiesAgainstLevel (each
//     agent keeps its caches from frame to frame, as in stepBodies),
//     --repeats times; the median of the repeats' ns per step;
//   - measured, untimed, in one more replay: tree queries per step
//     (NearbyTriangles::queries: most steps reuse the agent's last query), the
//     candidates the narrow phase tested in the step's last slide
//     (StepScratch::lastSlideCandidates after the step; the lanes its scans went
//     through, a short list whole: lastSlideScannedLanes; multi_query_steps is the
//     fraction of steps that queried the tree more than once), and, by brute force over every
//     triangle's bounding box, the triangles whose box overlaps the unpadded box of the ellipsoid
//     swept from the step's start to its desired end (position + the velocity of the runtime's own
//     velocity model times dt: the move the step asks of the level before any slide; the end the
//     step reached would leave out the surfaces it rests on, which keep it a skin away). The brute
//     force runs on every k-th step, k chosen so that at most
//     --brute-force-budget box tests are made; the ratio candidates /
//     overlapping is over those steps.
// Prints a Markdown table (a row per method) or, with --json, one JSON object.
#include <bspf/movement.h>
#include <bspf/query.h>
#include <bspf/world.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "support/cli.h"
#include "support/median.h"
#include "velocity.h"  // the runtime's private velocity model: the desired end
#include "walkers_sim.h"

namespace {

using bspf::bench::median;

using bspf::Body;
using bspf::Vec3;
using bspf::World;

struct RecordedStep {
  Body body;
  Vec3 force;
};

struct Recording {
  std::vector<RecordedStep> steps;  // frame by frame, agents in order
  std::size_t agents = 0;
  long long refusedMoves = 0;  // in the recorded crowd run
};

Recording recordCrowd(const World& world, std::span<const Vec3> starts,
                      const bspf::walkers::Options& options) {
  Recording recording;
  recording.agents = starts.size();
  recording.steps.reserve(std::size_t(options.agents) * std::size_t(options.frames));
  bspf::walkers::Simulation crowd(world, starts, options);
  for (int frame = 0; frame < options.frames; ++frame)
    crowd.step([&](std::span<const Body> bodies, std::span<const Vec3> forces) {
      for (std::size_t i = 0; i < bodies.size(); ++i)
        recording.steps.push_back({bodies[i], forces[i]});
    });
  recording.refusedMoves = crowd.summary().refusedMoves;
  return recording;
}

// Replays recorded step `i` with stepBody, the agent's own nearby triangles
// swapped into the scratch (what a step derived from them is made again).
void replayStep(const World& world, const Recording& recording, std::size_t i, float dt, Body& body,
                bspf::StepScratch& scratch, std::vector<bspf::NearbyTriangles>& agentNearby) {
  bspf::NearbyTriangles& own = agentNearby[i % recording.agents];
  std::swap(scratch.nearby, own);
  bspf::stepBody(world, body, recording.steps[i].force, dt, scratch);
  std::swap(scratch.nearby, own);
}

// The median over `repeats` replays of every recorded frame's level phase
// (stepBodiesAgainstLevel on the frame's recorded bodies, which keeps each
// agent's caches by index, as stepBodies does), ns per step.
double timeReplay(const World& world, const Recording& recording, float dt, int repeats) {
  const std::size_t agents = recording.agents;
  std::vector<Body> bodies(recording.steps.size());
  std::vector<Vec3> forces(recording.steps.size());
  for (std::size_t i = 0; i < bodies.size(); ++i) forces[i] = recording.steps[i].force;
  std::vector<double> nsPerStep;
  for (int repeat = 0; repeat < repeats; ++repeat) {
    for (std::size_t i = 0; i < bodies.size(); ++i) bodies[i] = recording.steps[i].body;
    bspf::StepScratch scratch;
    const auto start = std::chrono::steady_clock::now();
    for (std::size_t first = 0; first < bodies.size(); first += agents)
      bspf::stepBodiesAgainstLevel(world, std::span(bodies).subspan(first, agents),
                                   std::span<const Vec3>(forces).subspan(first, agents), dt,
                                   scratch);
    const auto stop = std::chrono::steady_clock::now();
    nsPerStep.push_back(std::chrono::duration<double, std::nano>(stop - start).count() /
                        double(bodies.size()));
  }
  return median(nsPerStep);
}

// Every triangle's bounding box, one array per bound, for the brute force.
struct TriangleBoxes {
  std::vector<float> low[3], high[3];

  explicit TriangleBoxes(const World& world) {
    for (const bspf::schema::Triangle& t : world.triangles()) {
      const Vec3 a = bspf::toVec3(world.vertices()[t.v0()]);
      const Vec3 b = bspf::toVec3(world.vertices()[t.v1()]);
      const Vec3 c = bspf::toVec3(world.vertices()[t.v2()]);
      for (int k = 0; k < 3; ++k) {
        low[k].push_back(std::min({a[k], b[k], c[k]}));
        high[k].push_back(std::max({a[k], b[k], c[k]}));
      }
    }
  }
  std::size_t size() const { return low[0].size(); }

  std::size_t countOverlapping(const Vec3& boxLow, const Vec3& boxHigh) const {
    std::size_t count = 0;
    for (std::size_t t = 0; t < size(); ++t)
      count += low[0][t] <= boxHigh.x() && boxLow.x() <= high[0][t] && low[1][t] <= boxHigh.y() &&
               boxLow.y() <= high[1][t] && low[2][t] <= boxHigh.z() && boxLow.z() <= high[2][t];
    return count;
  }
};

struct QueryFigures {
  double queriesPerStep = 0;
  double multiQueryStepsFraction = 0;  // steps that queried the tree more than once
  double candidatesMean = 0, candidatesP90 = 0;
  double scannedMean = 0;         // lanes the last slide's scans went through (a short list whole)
  long long bruteForceEvery = 1;  // k: every k-th step was brute-forced
  long long bruteForceSteps = 0;
  double overlappingMean = 0;
  double ratioMean = 0;  // mean over brute-forced steps with an overlap of candidates/overlapping
  double ratioOfMeans = 0;       // candidates mean / overlapping mean over the brute-forced steps
  long long noOverlapSteps = 0;  // brute-forced steps that overlapped no triangle's box
};

QueryFigures measureQueries(const World& world, const Recording& recording, float dt,
                            double bruteForceBudget) {
  QueryFigures figures;
  const TriangleBoxes boxes(world);
  const long long steps = static_cast<long long>(recording.steps.size());
  figures.bruteForceEvery = std::max<long long>(
      1,
      static_cast<long long>(std::ceil(double(steps) * double(boxes.size()) / bruteForceBudget)));
  bspf::StepScratch scratch;
  std::vector<bspf::NearbyTriangles> agentNearby(recording.agents);
  std::vector<double> candidates;
  long long queries = 0, multiQuery = 0;
  double scannedSum = 0;
  double sampledCandidates = 0, sampledOverlapping = 0, ratioSum = 0;
  long long ratioCount = 0;
  for (long long i = 0; i < steps; ++i) {
    const RecordedStep& recorded = recording.steps[std::size_t(i)];
    Body body = recorded.body;
    const bspf::NearbyTriangles& own = agentNearby[std::size_t(i) % recording.agents];
    const std::uint64_t before = own.queries();
    replayStep(world, recording, std::size_t(i), dt, body, scratch, agentNearby);
    const std::uint64_t made = own.queries() - before;
    queries += static_cast<long long>(made);
    multiQuery += made > 1;
    const double listed = double(scratch.lastSlideCandidates());
    candidates.push_back(listed);
    scannedSum += double(scratch.lastSlideScannedLanes());
    if (i % figures.bruteForceEvery != 0) continue;
    Body moved = recorded.body;
    bspf::detail::futureVelocity(moved, recorded.force, dt);
    const Vec3& start = recorded.body.position;
    const Vec3 desiredEnd = start + moved.velocity * dt;
    const Vec3 radii(body.radii.xz, body.radii.y, body.radii.xz);
    const Vec3 low = start.cwiseMin(desiredEnd) - radii;
    const Vec3 high = start.cwiseMax(desiredEnd) + radii;
    const double overlapping = double(boxes.countOverlapping(low, high));
    ++figures.bruteForceSteps;
    sampledCandidates += listed;
    sampledOverlapping += overlapping;
    if (overlapping > 0) {
      ratioSum += listed / overlapping;
      ++ratioCount;
    } else {
      ++figures.noOverlapSteps;
    }
  }
  figures.queriesPerStep = double(queries) / double(std::max(1LL, steps));
  figures.multiQueryStepsFraction = double(multiQuery) / double(std::max(1LL, steps));
  if (!candidates.empty()) {
    double sum = 0;
    for (const double c : candidates) sum += c;
    figures.candidatesMean = sum / double(candidates.size());
    figures.scannedMean = scannedSum / double(candidates.size());
    const std::size_t p90 = std::min(candidates.size() - 1, candidates.size() * 9 / 10);
    std::nth_element(candidates.begin(), candidates.begin() + std::ptrdiff_t(p90),
                     candidates.end());
    figures.candidatesP90 = candidates[p90];
  }
  if (figures.bruteForceSteps > 0)
    figures.overlappingMean = sampledOverlapping / double(figures.bruteForceSteps);
  if (ratioCount > 0) figures.ratioMean = ratioSum / double(ratioCount);
  if (sampledOverlapping > 0) figures.ratioOfMeans = sampledCandidates / sampledOverlapping;
  return figures;
}

struct MethodResult {
  std::string method;
  long long steps = 0;
  long long refusedMoves = 0;
  double nsPerStep = 0;
  QueryFigures queries;
};

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", v);
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "bspf_replay_bench: the step replayed from a recorded walkers crowd, with the "
      "broad phase's work per step",
      "bspf_replay_bench"};
  bspf::walkers::Options options;
  std::string levelPath, spawnsPath, methods = "both";
  int repeats = 5;
  double bruteForceBudget = 3e8;
  bool json = false, noHeader = false;
  app.add_option("level", levelPath, "The compiled level (.bspf)")->required();
  app.add_option("--spawns", spawnsPath,
                 "Spawn points (agents start 0.3 m above them, round robin; default: random "
                 "open walkable floor)");
  app.add_option("--agents", options.agents, "Agents")->capture_default_str();
  app.add_option("--frames", options.frames, "Frames recorded")->capture_default_str();
  app.add_option("--speed", options.speed, "Walking speed, m/s")->capture_default_str();
  app.add_option("--method", methods, "planes, exact or both (each its own recorded crowd)")
      ->check(CLI::IsMember({"planes", "exact", "both"}))
      ->capture_default_str();
  app.add_option("--repeats", repeats, "Timed replays (median)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--brute-force-budget", bruteForceBudget,
                 "Most triangle-box tests of the brute-force overlap count (steps are sampled "
                 "to stay under it)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_flag("--json", json, "Print one JSON object instead of a Markdown table");
  app.add_flag("--no-header", noHeader, "Markdown rows only (to append to a table)");
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;
  if (const std::string problem = bspf::walkers::validate(options); !problem.empty()) {
    std::fprintf(stderr, "bspf_replay_bench: error: %s\n", problem.c_str());
    return 2;
  }

  const bspf::OpenResult opened = bspf::openWorld(levelPath);
  if (!opened) {
    std::fprintf(stderr, "bspf_replay_bench: error: %s\n", opened.message.c_str());
    return 1;
  }
  const World& world = *opened.world;
  const std::string level = std::filesystem::path(levelPath).stem().string();
  const bspf::TreeStats tree = bspf::computeTreeStats(world);

  std::vector<MethodResult> results;
  const std::map<std::string, bspf::CollisionMethod> byName{
      {"planes", bspf::CollisionMethod::Planes}, {"exact", bspf::CollisionMethod::ExactSweep}};
  for (const auto& [name, method] : byName) {
    if (methods != "both" && methods != name) continue;
    options.method = method;
    const bspf::walkers::Points starts =
        bspf::walkers::placeAgents(world, options, spawnsPath, levelPath);
    if (!starts) {
      std::fprintf(stderr, "bspf_replay_bench: error: %s\n", starts.error.c_str());
      return 1;
    }
    const Recording recording = recordCrowd(world, starts.points, options);
    MethodResult r;
    r.method = name;
    r.steps = static_cast<long long>(recording.steps.size());
    r.refusedMoves = recording.refusedMoves;
    r.nsPerStep = timeReplay(world, recording, options.dt, repeats);
    r.queries = measureQueries(world, recording, options.dt, bruteForceBudget);
    results.push_back(r);
  }
  // Planes first, as everywhere else.
  std::sort(results.begin(), results.end(),
            [](const MethodResult& a, const MethodResult& b) { return a.method > b.method; });

  if (json) {
    std::printf(
        "{\"level\":\"%s\",\"triangles\":%zu,\"leaves\":%u,\"references_per_triangle\":%s,"
        "\"placement\":\"%s\",\"agents\":%d,\"frames\":%d,\"speed\":%s,\"repeats\":%d,"
        "\"methods\":[",
        level.c_str(), std::size_t(world.triangles().size()), tree.leaves,
        number(tree.referencesPerTriangle).c_str(), spawnsPath.empty() ? "floor" : "spawns",
        options.agents, options.frames, number(options.speed).c_str(), repeats);
    for (std::size_t k = 0; k < results.size(); ++k) {
      const MethodResult& r = results[k];
      const QueryFigures& q = r.queries;
      std::printf(
          "%s{\"method\":\"%s\",\"steps\":%lld,\"refused_moves\":%lld,\"ns_per_step\":%s,"
          "\"queries_per_step\":%s,\"multi_query_steps\":%s,\"candidates_mean\":%s,"
          "\"candidates_p90\":%s,\"scanned_lanes_mean\":%s,\"brute_force_every\":%lld,\"brute_"
          "force_steps\":%lld,"
          "\"overlapping_mean\":%s,\"ratio_mean\":%s,\"ratio_of_means\":%s,"
          "\"no_overlap_steps\":%lld}",
          k ? "," : "", r.method.c_str(), r.steps, r.refusedMoves, number(r.nsPerStep).c_str(),
          number(q.queriesPerStep).c_str(), number(q.multiQueryStepsFraction).c_str(),
          number(q.candidatesMean).c_str(), number(q.candidatesP90).c_str(),
          number(q.scannedMean).c_str(), q.bruteForceEvery, q.bruteForceSteps,
          number(q.overlappingMean).c_str(), number(q.ratioMean).c_str(),
          number(q.ratioOfMeans).c_str(), q.noOverlapSteps);
    }
    std::printf("]}\n");
    return 0;
  }
  if (!noHeader) {
    std::printf(
        "| level | method | triangles | leaves | refs/tri | ns/step | queries/step | "
        "candidates mean | candidates p90 | lanes scanned mean | overlapping mean | ratio mean | "
        "ratio of means | brute force every | refused |\n");
    std::printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
  }
  for (const MethodResult& r : results) {
    const QueryFigures& q = r.queries;
    std::printf(
        "| %s | %s | %zu | %u | %.2f | %.0f | %.2f | %.1f | %.0f | %.1f | %.1f | %.2f | %.2f | "
        "%lld | %lld |\n",
        level.c_str(), r.method.c_str(), std::size_t(world.triangles().size()), tree.leaves,
        tree.referencesPerTriangle, r.nsPerStep, q.queriesPerStep, q.candidatesMean,
        q.candidatesP90, q.scannedMean, q.overlappingMean, q.ratioMean, q.ratioOfMeans,
        q.bruteForceEvery, r.refusedMoves);
  }
  return 0;
}
