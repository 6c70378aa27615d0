// SPDX-License-Identifier: MIT
// bspf_crowd_bench: how the body-against-body phase scales. Bodies stand on
// a flat floor at constant density (one per 1.5 m square, touching
// neighbours now and then as they walk), 64 to 16,384 of them; each frame's
// two phases are timed apart (the level phase, stepBodiesAgainstLevel; the
// body phase, BodyGrid::build plus pushBodiesApart), so the body phase's
// share of the step shows. A linear body phase keeps its time per body flat.
// Then the same crowd running at 40 m/s (the sweep's case: every body is
// fast). Then the pile: 10,000 bodies dropped at one point, the worst case of the
// body phase, timed per frame (stepBodies whole). Then the crowd of 1,024 on
// 1 to `--threads` threads (default 2): stepBodies with a ThreadPool.
// With `--level LEVEL.bspf --spawns FILE`, also the walkers crowd (64 and
// 1,024 agents from the spawn points, samples/walkers_sim.h) on that level,
// its two phases timed apart as above.
// Prints one JSON object per case; times are medians over frames. `--case NAME`
// runs one case alone (walkers, crowd, pile or threads), for a profiler.
#include <bspf/movement.h>
#include <bspf/thread_pool.h>

#include <algorithm>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "support/cli.h"
#include "support/median.h"
#include "support/mesh_blob.h"
#include "walkers_sim.h"

namespace {

using bspf::bench::median;

using Clock = std::chrono::steady_clock;

double nanoseconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double, std::nano>(to - from).count();
}

// `side` x `side` walkers on a 1.5 m grid, each walking its own way (at
// up to `speed` m/s: 6 walks, 40 runs, and every body's move is then long
// enough for the body phase's sweep).
void walkingCrowd(int side, std::vector<bspf::Body>& bodies, std::vector<bspf::Vec3>& forces,
                  float speed = 6) {
  const int n = side * side;
  bodies.assign(n, {});
  forces.resize(n);
  for (int i = 0; i < n; ++i) {
    bodies[i].position = bspf::Vec3(1.5f * (i % side), 0.851f, 1.5f * (i / side));
    bodies[i].radii = {0.45f, 0.85f};
    bodies[i].settings.maxHorizontalSpeed = speed;
    const float angle = 2.399963f * i;  // golden angle: directions spread evenly
    forces[i] = bspf::Vec3(std::cos(angle), 0, std::sin(angle)) * (20.0f * speed / 6);
  }
}

// One frame's two phases, timed apart; adds ns per body to the lists.
void timePhases(const bspf::World& world, std::vector<bspf::Body>& bodies,
                const std::vector<bspf::Vec3>& forces, float dt, bspf::StepScratch& scratch,
                std::vector<bspf::StepReport>& reports, std::vector<double>& levelNs,
                std::vector<double>& bodyNs) {
  const double n = double(bodies.size());
  const auto start = Clock::now();
  bspf::stepBodiesAgainstLevel(world, bodies, forces, dt, scratch, reports);
  const auto levelDone = Clock::now();
  scratch.bodyGrid.build(bodies);
  bspf::pushBodiesApart(world, scratch.bodyGrid, bodies, 0, bodies.size(), scratch, reports);
  const auto stop = Clock::now();
  levelNs.push_back(nanoseconds(start, levelDone) / n);
  bodyNs.push_back(nanoseconds(levelDone, stop) / n);
}

constexpr float kDt = 1.0f / 60;
constexpr int kFrames = 120;

// The walking crowd of `side` x `side` bodies at up to `speed` m/s on
// `world`, 120 frames: prints its case line.
void crowdCase(const bspf::World& world, int side, float speed) {
  std::vector<bspf::Body> bodies;
  std::vector<bspf::Vec3> forces;
  walkingCrowd(side, bodies, forces, speed);
  const std::size_t n = bodies.size();
  bspf::StepScratch scratch;
  std::vector<bspf::StepReport> reports(n);
  std::vector<double> levelNs, bodyNs, stepNs;
  double contacts = 0, stopped = 0;
  for (int frame = 0; frame < kFrames; ++frame) {
    timePhases(world, bodies, forces, kDt, scratch, reports, levelNs, bodyNs);
    stepNs.push_back(levelNs.back() + bodyNs.back());
    for (const auto& r : reports) contacts += r.bodyContacts, stopped += r.stoppedByBody;
  }
  const double steps = double(kFrames) * double(n);
  std::printf(
      "{\"case\":\"%s crowd\",\"bodies\":%zu,\"speed\":%.0f,\"ns_per_body_step\":%.0f,"
      "\"level_phase_ns\":%.0f,\"body_phase_ns\":%.0f,\"body_phase_share\":%.3f,"
      "\"body_contacts_per_step\":%.3f,\"stopped_by_body_per_step\":%.4f}\n",
      speed > 6 ? "running" : "walking", n, speed, median(stepNs), median(levelNs), median(bodyNs),
      median(bodyNs) / median(stepNs), contacts / steps, stopped / steps);
}

// The walkers crowd on a real level: agents from its spawn points.
void walkersOnLevel(const char* levelPath, const char* spawnsPath) {
  const bspf::OpenResult opened = bspf::openWorld(levelPath);
  const bspf::walkers::Points spawns = bspf::walkers::loadSpawns(spawnsPath);
  if (!opened || !spawns) {
    std::fprintf(stderr, "bspf_crowd_bench: cannot open %s or %s\n", levelPath, spawnsPath);
    return;
  }
  for (const int agents : {64, 1024}) {
    const bspf::walkers::Options options;
    std::vector<bspf::Body> bodies(agents);
    std::vector<bspf::walkers::RandomWalk> walks;
    const auto starts = bspf::walkers::startsFromSpawns(spawns.points, agents);
    for (int i = 0; i < agents; ++i) {
      bodies[i].position = starts[i];
      bodies[i].radii = options.radii;
      bodies[i].settings.maxHorizontalSpeed = options.speed;
      walks.emplace_back(bspf::walkers::streamSeed(options.seed, i + 1));
    }
    std::vector<bspf::Vec3> forces(agents);
    std::vector<bspf::StepReport> reports(agents);
    bspf::StepScratch scratch;
    std::vector<double> levelNs, bodyNs;
    for (int frame = 0; frame < 600; ++frame) {
      for (int i = 0; i < agents; ++i) forces[i] = walks[i].nextForce(options.speed, options.dt);
      timePhases(*opened.world, bodies, forces, options.dt, scratch, reports, levelNs, bodyNs);
    }
    std::printf(
        "{\"case\":\"walkers\",\"level\":\"%s\",\"bodies\":%d,\"level_phase_ns\":%.1f,"
        "\"body_phase_ns\":%.1f,\"body_phase_share\":%.3f}\n",
        levelPath, agents, median(levelNs), median(bodyNs),
        median(bodyNs) / (median(levelNs) + median(bodyNs)));
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "bspf_crowd_bench: how the body-against-body phase scales: a walking crowd of 64 to "
      "16,384 bodies on a flat floor (level and body phases timed apart), a 10,000-body pile, "
      "and 1,024 bodies on 1 to --threads threads. Prints one JSON object per case.\n\n"
      "Example:\n  bspf_crowd_bench --threads 2 --level out/arena.bspf --spawns "
      "samples/arena.spawns.txt",
      "bspf_crowd_bench"};
  int maxThreads = 2;
  std::string levelPath, spawnsPath;
  app.add_option("--threads", maxThreads, "Most threads for the thread-scaling case")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  auto* level = app.add_option("--level", levelPath,
                               "Also the walkers crowd on this compiled level (needs --spawns)");
  app.add_option("--spawns", spawnsPath, "Spawn points of --level, one 'x y z' a line")
      ->needs(level);
  level->needs(app.get_option("--spawns"));
  std::string only;
  app.add_option("--case", only,
                 "Run only this case: walkers (needs --level), crowd, pile or threads; "
                 "default: all (for a profiler, one case alone)")
      ->check(CLI::IsMember({"walkers", "crowd", "pile", "threads"}));
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;
  if (only == "walkers" && levelPath.empty()) {
    std::fprintf(stderr, "bspf_crowd_bench: --case walkers needs --level and --spawns\n");
    return 2;
  }
  auto runs = [&](const char* name) { return only.empty() || only == name; };
  if (!levelPath.empty() && runs("walkers")) walkersOnLevel(levelPath.c_str(), spawnsPath.c_str());
  if (!runs("crowd") && !runs("pile") && !runs("threads")) return 0;
  // A 400 m square floor slab, compiled in memory.
  const bspf::bench::CompiledLevel floor(bspf::bench::floorMesh(200.0), {}, "floor");
  const bspf::World& world = floor.world();

  if (runs("crowd")) {
    for (const int side : {8, 16, 32, 64, 128}) crowdCase(world, side, 6);
    // The crowd running at 40 m/s: every body is swept against the others.
    for (const int side : {32, 128}) crowdCase(world, side, 40);
  }

  if (runs("pile")) {
    const int n = 10000;
    const bspf::Vec3 point(0, 0.86f, 0);
    std::vector<bspf::Body> bodies(n);
    for (bspf::Body& b : bodies) b.position = point;
    const std::vector<bspf::Vec3> forces(n, bspf::Vec3::Zero());
    std::vector<bspf::StepReport> reports(n);
    bspf::StepScratch scratch;
    std::vector<double> frameMs;
    for (int frame = 0; frame < 60; ++frame) {
      const auto start = Clock::now();
      bspf::stepBodies(world, bodies, forces, kDt, scratch, reports);
      frameMs.push_back(nanoseconds(start, Clock::now()) * 1e-6);
    }
    float spread = 0;
    // A digest of every final position's bits (FNV-1a), so that two builds'
    // piles can be compared for the same trajectories.
    std::uint64_t digest = 0xcbf29ce484222325ull;
    for (const bspf::Body& b : bodies) {
      spread = std::max(spread, std::hypot(b.position.x(), b.position.z()));
      for (int axis = 0; axis < 3; ++axis)
        digest = (digest ^ std::bit_cast<std::uint32_t>(b.position[axis])) * 0x100000001b3ull;
    }
    std::printf(
        "{\"case\":\"pile at one point\",\"bodies\":%d,\"first_frame_ms\":%.2f,"
        "\"median_frame_ms\":%.2f,\"max_frame_ms\":%.2f,\"spread_after_60_frames_m\":%.1f,"
        "\"positions_digest\":\"%016llx\"}\n",
        n, frameMs.front(), median(frameMs), *std::max_element(frameMs.begin(), frameMs.end()),
        spread, static_cast<unsigned long long>(digest));
  }

  for (int threads = 1; runs("threads") && threads <= maxThreads; ++threads) {
    std::vector<bspf::Body> bodies;
    std::vector<bspf::Vec3> forces;
    walkingCrowd(32, bodies, forces);
    bspf::ThreadPool pool(threads);
    std::vector<bspf::StepScratch> scratches(threads);
    std::vector<bspf::StepReport> reports(bodies.size());
    std::vector<double> stepNs;
    for (int frame = 0; frame < kFrames; ++frame) {
      const auto start = Clock::now();
      bspf::stepBodies(world, bodies, forces, kDt, pool, scratches, reports);
      stepNs.push_back(nanoseconds(start, Clock::now()) / double(bodies.size()));
    }
    std::printf(
        "{\"case\":\"thread pool\",\"bodies\":%zu,\"threads\":%d,\"ns_per_body_step\":%.0f}\n",
        bodies.size(), threads, median(stepNs));
  }
  return 0;
}
