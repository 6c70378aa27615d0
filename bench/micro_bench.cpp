// SPDX-License-Identifier: MIT
// bspf_micro_bench: Google Benchmark microbenchmarks of the collision
// primitives, one call per iteration (so the time is ns per call):
//   PreCheck            the planes method's side-value pre-check of one
//                       candidate on its stored face plane;
//   InsideGrownTriangle its six-plane test of one point;
//   EarliestImpact      the exact sweep of the unit sphere against one
//                       sphere-space triangle, and ExactPerTriangle the same
//                       with the triangle scaled into sphere space first (as
//                       slideExact does for every candidate);
//   CandidateTriangles  collectCandidateTriangles for one frame's move;
//   StoredBoxes64       64 leaf entries' stored boxes tested against a move's
//                       box, with the SSE test the tree query uses and with
//                       the plain one;
//   PlanesMask          the planes method's box test and pre-check of one
//                       block of 8 candidates (workspace.h), on each path the
//                       CPU runs: one lane at a time, SSE, AVX;
//   StepBody            a whole stepBody, for each method;
//   BodyGridBuild       the body phase's broad phase (BodyGrid::build: the
//                       sweep, then the neighbour pairs) for one frame of the
//                       crowd at 6 and at 40 m/s, as the level phase left it
//                       (64 bodies: the time over 64 is per body);
//   MeetingPairs        the sorted sweep's pair scan (box_pairs.h) over one
//                       frame's 64 swept boxes at 40 m/s, four boxes at a
//                       time (SSE2) and one by one.
// The inputs are realistic and deterministic: the states of the `walkers`
// crowd (samples/walkers_sim.h: 64 agents walking at 6 m/s, dt 1/60, radii
// 0.45/0.85) on samples/arena.obj, compiled in memory, and on
// ../shared/levels/oa_dm5.obj when present, with the candidates and points
// each narrow phase meets. Thousands of them are cycled through, in the order
// the crowd met them, so branch prediction sees a realistic mix.
#include <benchmark/benchmark.h>
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspf/movement.h>
#include <bspf/query.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "box_pairs.h"
#include "narrow_phase.h"
#include "stored_box.h"
#include "support/mesh_blob.h"
#include "walkers_sim.h"
#include "workspace.h"

namespace {

using bspf::Body;
using bspf::CollisionMethod;
using bspf::Vec3;
using bspf::World;

constexpr float kDt = 1.0f / 60;
constexpr bspf::EllipsoidRadii kRadii{0.45f, 0.85f};
// Each input list holds at most this many entries.
constexpr std::size_t kMaxInputs = 1 << 15;

struct BodyState {
  Body body;
  Vec3 force;
};

struct PreCheckInput {
  const bspf::schema::Plane* face;
  Vec3 start, end;
};

struct PointInput {
  bspf::detail::GrownTriangle grown;  // the six planes grown for kRadii
  Vec3 point;
};

struct SweepInput {
  bspf::detail::Triangle triangle;  // sphere space
  std::uint32_t index;              // in the world
  Vec3 p, v;                        // sphere space
};

struct Move {
  Vec3 from, to;
};

struct Level {
  std::string name;
  std::optional<bspf::bench::CompiledLevel> compiled;
  const World& world() const { return compiled->world(); }
  std::vector<BodyState> planesStates, exactStates;
  std::vector<Move> moves;
  std::vector<PreCheckInput> preChecks;
  std::vector<PointInput> points;
  std::vector<SweepInput> sweeps;
  /// Frames of the crowd after its level phase (stepBodiesAgainstLevel),
  /// as the body phase takes them, walking at 6 m/s and running at 40.
  std::vector<std::vector<Body>> walkingFrames, runningFrames;
};

// Every 8th body state of frames 30 to 630 of the walkers crowd (after the
// spawn drop) with `method`.
std::vector<BodyState> crowdStates(const World& world, std::span<const Vec3> spawns,
                                   CollisionMethod method) {
  bspf::walkers::Options options;
  options.method = method;
  const std::vector<Vec3> starts = bspf::walkers::startsFromSpawns(spawns, options.agents);
  bspf::walkers::Simulation crowd(world, starts, options);
  std::vector<BodyState> states;
  long long n = 0;
  for (int frame = 0; frame < 630; ++frame)
    crowd.step([&](std::span<const Body> bodies, std::span<const Vec3> forces) {
      if (frame < 30) return;
      for (std::size_t i = 0; i < bodies.size(); ++i)
        if (n++ % 8 == 0) states.push_back({bodies[i], forces[i]});
    });
  return states;
}

// Frames 30 to 330 of the walkers crowd at `speed` m/s, each after its
// level phase: the bodies as BodyGrid::build gets them.
std::vector<std::vector<Body>> crowdFrames(const World& world, std::span<const Vec3> spawns,
                                           float speed) {
  bspf::walkers::Options options;
  options.speed = speed;
  const std::vector<Vec3> starts = bspf::walkers::startsFromSpawns(spawns, options.agents);
  bspf::walkers::Simulation crowd(world, starts, options);
  std::vector<std::vector<Body>> frames;
  bspf::StepScratch scratch;
  for (int frame = 0; frame < 330; ++frame)
    crowd.step([&](std::span<const Body> bodies, std::span<const Vec3> forces) {
      if (frame < 30) return;
      std::vector<Body>& moved = frames.emplace_back(bodies.begin(), bodies.end());
      bspf::stepBodiesAgainstLevel(world, moved, forces, options.dt, scratch);
    });
  return frames;
}

// The move stepBody asks of the level in state `s`: one frame of its walk
// (futureVelocity in movement.cpp, friction left out: the force keeps the
// walkers at full speed).
Move desiredMove(const BodyState& s) {
  const bspf::MovementSettings& settings = s.body.settings;
  Vec3 v = s.body.velocity + Vec3(s.force.x(), 0, s.force.z()) * kDt;
  const float horizontal = std::hypot(v.x(), v.z());
  if (horizontal > settings.maxHorizontalSpeed) {
    v.x() *= settings.maxHorizontalSpeed / horizontal;
    v.z() *= settings.maxHorizontalSpeed / horizontal;
  }
  v.y() -= settings.gravity * kDt;
  return {s.body.position, s.body.position + v * kDt};
}

// The inputs each primitive meets in the first slide iteration of each
// state's move.
void gatherInputs(Level& level) {
  const World& world = level.world();
  bspf::SweepScratch scratch;
  std::vector<std::uint32_t> candidates;
  for (const BodyState& s : level.planesStates) {
    const Move m = desiredMove(s);
    level.moves.push_back(m);
    collectCandidateTriangles(world, m.from, m.to, kRadii, scratch, candidates);
    for (const std::uint32_t t : candidates) {
      const bspf::schema::TrianglePlanes& planes = world.trianglePlanes()[t];
      bspf::detail::GrownTriangle grown;
      bspf::detail::growPlanes(world, t, kRadii, grown);
      level.preChecks.push_back({&planes.face(), m.from, m.to});
      // The points findBlockingTriangle tests.
      const bspf::detail::SideValues sides =
          bspf::detail::sideValues(planes.face(), m.from, m.to, kRadii);
      if (!bspf::detail::passesPreCheck(sides)) continue;
      if (sides.startSide >= sides.reach) {
        const float f = (sides.startSide - sides.reach) / (sides.startSide - sides.endSide);
        level.points.push_back({grown, m.from + f * (m.to - m.from)});
      } else {
        level.points.push_back({grown, m.from});
        level.points.push_back({grown, m.to});
      }
    }
  }
  const Vec3 toSphere(1 / kRadii.xz, 1 / kRadii.y, 1 / kRadii.xz);
  for (const BodyState& s : level.exactStates) {
    const Move m = desiredMove(s);
    collectCandidateTriangles(world, m.from, m.to, kRadii, scratch, candidates);
    for (const std::uint32_t t : candidates) {
      // The candidates slideExact sweeps: those its pre-check passes.
      const bspf::schema::Plane& face = world.trianglePlanes()[t].face();
      const float reach = bspf::effectiveRadius(face.normal(), kRadii) * 1.0001f + 1e-5f;
      const float startSide = bspf::signedDistance(face, m.from);
      if (startSide < -1e-5f || std::min(startSide, bspf::signedDistance(face, m.to)) > reach)
        continue;
      level.sweeps.push_back({bspf::detail::sphereSpaceTriangle(world, t, toSphere), t,
                              m.from.cwiseProduct(toSphere),
                              (m.to - m.from).cwiseProduct(toSphere)});
    }
  }
  auto cap = [](auto& inputs) {
    if (inputs.size() > kMaxInputs) inputs.resize(kMaxInputs);
  };
  cap(level.moves);
  cap(level.preChecks);
  cap(level.points);
  cap(level.sweeps);
}

// `<base>.obj` compiled in memory with the default settings, and the crowd
// started at `<base>.spawns.txt`. Null (with a message) when it cannot.
std::unique_ptr<Level> loadLevel(const std::filesystem::path& base) {
  auto level = std::make_unique<Level>();
  level->name = base.filename().string();
  try {
    bspc::CompileSettings settings;
    level->compiled.emplace(bspc::importMesh(base.string() + ".obj", settings.import), settings,
                            level->name);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bspf_micro_bench: %s\n", e.what());
    return nullptr;
  }
  const bspf::walkers::Points spawns = bspf::walkers::loadSpawns(base.string() + ".spawns.txt");
  if (!spawns) {
    std::fprintf(stderr, "bspf_micro_bench: %s\n", spawns.error.c_str());
    return nullptr;
  }
  level->planesStates = crowdStates(level->world(), spawns.points, CollisionMethod::Planes);
  level->exactStates = crowdStates(level->world(), spawns.points, CollisionMethod::ExactSweep);
  level->walkingFrames = crowdFrames(level->world(), spawns.points, 6);
  level->runningFrames = crowdFrames(level->world(), spawns.points, 40);
  gatherInputs(*level);
  return level;
}

// Calls `call` on one input per iteration, cycling through `in`, and labels
// the row with how many inputs there are.
template <typename Input, typename Call>
void cycle(benchmark::State& state, const std::vector<Input>& in, Call call) {
  std::size_t i = 0;
  for (auto _ : state) {
    call(in[i]);
    i = i + 1 == in.size() ? 0 : i + 1;
  }
  state.SetLabel(std::to_string(in.size()) + " inputs");
}

void preCheck(benchmark::State& state, const Level& level) {
  cycle(state, level.preChecks, [](const PreCheckInput& x) {
    bool passes =
        bspf::detail::passesPreCheck(bspf::detail::sideValues(*x.face, x.start, x.end, kRadii));
    benchmark::DoNotOptimize(passes);
  });
}

void insideGrownTriangle(benchmark::State& state, const Level& level) {
  cycle(state, level.points, [](const PointInput& x) {
    bool inside = x.grown.inside(x.point);
    benchmark::DoNotOptimize(inside);
  });
}

void earliestImpact(benchmark::State& state, const Level& level) {
  cycle(state, level.sweeps, [](const SweepInput& x) {
    bspf::detail::Impact impact;
    bool penetrating = false;
    bspf::detail::earliestImpact(x.triangle, x.p, x.v, impact, penetrating);
    benchmark::DoNotOptimize(impact);
    benchmark::DoNotOptimize(penetrating);
  });
}

// earliestImpact with the triangle scaled into sphere space first, as
// slideExact does for each candidate.
void exactPerTriangle(benchmark::State& state, const Level& level) {
  const Vec3 toSphere(1 / kRadii.xz, 1 / kRadii.y, 1 / kRadii.xz);
  cycle(state, level.sweeps, [&](const SweepInput& x) {
    bspf::detail::Impact impact;
    bool penetrating = false;
    bspf::detail::earliestImpact(
        bspf::detail::sphereSpaceTriangle(level.world(), x.index, toSphere), x.p, x.v, impact,
        penetrating);
    benchmark::DoNotOptimize(impact);
    benchmark::DoNotOptimize(penetrating);
  });
}

// The face stage alone (faceImpact) on the sweeps whose start is within reach
// of the triangle's plane, where it measures the distance to the triangle:
// with the distance each measured from the sweep's start beforehand (the
// measure a body's candidates keep from sweep to sweep, ExactCold::
// measured), which settles those out of reach for the whole move without
// measuring again, or without.
void faceStageWithinReach(benchmark::State& state, const Level& level, bool measured) {
  struct Prepared {
    bspf::detail::TriangleD triangle;
    bspf::detail::SpherePath path;
    bspf::detail::MeasuredDistance distance;
  };
  std::vector<Prepared> prepared;
  for (const SweepInput& x : level.sweeps) {
    if (x.triangle.normal.dot(x.p - x.triangle.a) >= 1) continue;
    Prepared in{bspf::detail::TriangleD(x.triangle), bspf::detail::SpherePath(x.p, x.v), {}};
    bspf::detail::Impact impact;
    bool penetrating = false;
    bspf::detail::faceImpact(in.triangle, in.path, impact, penetrating, &in.distance);
    prepared.push_back(in);
  }
  cycle(state, prepared, [&](const Prepared& x) {
    bspf::detail::Impact impact;
    bool penetrating = false;
    bspf::detail::MeasuredDistance distance = x.distance;
    const double earliest = bspf::detail::faceImpact(x.triangle, x.path, impact, penetrating,
                                                     measured ? &distance : nullptr);
    benchmark::DoNotOptimize(earliest);
    benchmark::DoNotOptimize(penetrating);
  });
}

void candidateTriangles(benchmark::State& state, const Level& level) {
  bspf::SweepScratch scratch;
  std::vector<std::uint32_t> candidates;
  std::size_t total = 0;
  cycle(state, level.moves, [&](const Move& m) {
    collectCandidateTriangles(level.world(), m.from, m.to, kRadii, scratch, candidates);
    benchmark::DoNotOptimize(candidates.data());
    benchmark::ClobberMemory();
    total += candidates.size();
  });
  state.counters["candidates"] = benchmark::Counter(double(total) / double(state.iterations()));
}

// The tree query's test of leaf entries' stored boxes (stored_box.h): 64
// consecutive entries, from a rotating place in the blob, against the box
// of one frame's move; `vectorised` picks the SSE test or the plain one.
void storedBoxes(benchmark::State& state, const Level& level, bool vectorised) {
  const std::span<const bspf::schema::Box> boxes = level.world().leafTriangleBounds();
  constexpr std::size_t kPerCall = 64;
  std::size_t first = 0, overlapping = 0;
  cycle(state, level.moves, [&](const Move& m) {
    const bspf::Bounds swept = bspf::sweptBounds(m.from, m.to, kRadii);
    const bspf::detail::StoredBoxTest test(swept.low, swept.high);
    std::size_t count = 0;
    for (std::size_t k = 0; k < kPerCall; ++k) {
      const bspf::schema::Box& box = boxes[(first + k) % boxes.size()];
      count += vectorised ? test.overlaps(box)
                          : bspf::detail::storedBoxOverlapsScalar(box, swept.low, swept.high);
    }
    benchmark::DoNotOptimize(count);
    overlapping += count;
    first = (first + kPerCall) % boxes.size();
  });
  state.counters["overlapping"] =
      benchmark::Counter(double(overlapping) / double(state.iterations()));
}

// planesMask on `path`: blocks of 8 consecutive pre-check inputs' face
// planes (boxes around everything, so the side values decide), each tested
// for the move of its first input.
void planesMask(benchmark::State& state, const Level& level, bspf::detail::MaskPath path) {
  struct BlockInput {
    bspf::detail::CandidateBlock block;
    Vec3 start, end;
  };
  std::vector<BlockInput> blocks;
  for (std::size_t first = 0; first + 8 <= level.preChecks.size(); first += 8) {
    BlockInput& in = blocks.emplace_back();
    for (int lane = 0; lane < 8; ++lane) {
      const bspf::schema::Plane& face = *level.preChecks[first + lane].face;
      const Vec3 normal = bspf::toVec3(face.normal());
      bspf::detail::setLane(in.block, lane, Vec3::Constant(-1e6f), Vec3::Constant(1e6f),
                            {normal, face.distance(), bspf::effectiveRadius(normal, kRadii)},
                            std::uint32_t(lane));
    }
    bspf::detail::sealBlock(in.block);
    in.start = level.preChecks[first].start;
    in.end = level.preChecks[first].end;
  }
  cycle(state, blocks, [path](const BlockInput& x) {
    bspf::detail::LaneSides sides;
    const bspf::Bounds box{x.start.cwiseMin(x.end), x.start.cwiseMax(x.end)};
    std::uint32_t bits = bspf::detail::planesMaskOn(path, x.block, box, x.start, x.end, sides);
    benchmark::DoNotOptimize(bits);
    benchmark::DoNotOptimize(sides);
  });
}

void stepBody(benchmark::State& state, const Level& level, CollisionMethod method) {
  bspf::StepScratch scratch;
  cycle(state, method == CollisionMethod::Planes ? level.planesStates : level.exactStates,
        [&](const BodyState& s) {
          Body body = s.body;
          bspf::stepBody(level.world(), body, s.force, kDt, scratch);
          benchmark::DoNotOptimize(body.position);
        });
}

// BodyGrid::build on one frame per iteration; items are bodies.
void bodyGridBuild(benchmark::State& state, const std::vector<std::vector<Body>>& frames) {
  bspf::BodyGrid grid;
  std::size_t bodies = 0;
  cycle(state, frames, [&](const std::vector<Body>& frame) {
    grid.build(frame);
    benchmark::ClobberMemory();
    bodies += frame.size();
  });
  state.SetItemsProcessed(std::int64_t(bodies));
}

// The sorted sweep's pair scan on one frame's swept boxes per iteration:
// each body's box from its step's start to its end, grown by its radii and
// skin, sorted by low x, and marked fast when its move is longer than
// kSweepMinMove in its own unit-sphere space (as BodyGrid::sweep builds
// them; carried pushes left out).
void meetingPairs(benchmark::State& state, const std::vector<std::vector<Body>>& frames,
                  bool fourAtATime) {
  struct Boxes {
    std::vector<float> bounds;  // lowX, highX, lowY, highY, lowZ, highZ
    std::vector<std::uint32_t> body, fast;
    bspf::detail::SortedBoxes sorted;
  };
  std::vector<Boxes> inputs(frames.size());
  for (std::size_t f = 0; f < frames.size(); ++f) {
    const std::vector<Body>& frame = frames[f];
    const std::uint32_t n = std::uint32_t(frame.size()), stride = n + bspf::detail::kBoxRun;
    std::vector<std::uint32_t> order(n);
    for (std::uint32_t i = 0; i < n; ++i) order[i] = i;
    auto low = [&](const Body& b) {
      const float reach = b.radii.xz + b.settings.skin;
      return std::min(b.lastStepStart.x(), b.position.x()) - reach;
    };
    std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
      return std::make_pair(low(frame[a]), a) < std::make_pair(low(frame[b]), b);
    });
    Boxes& in = inputs[f];
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    in.bounds.assign(6 * std::size_t(stride), 0);
    for (std::uint32_t k = 0; k < 6; ++k)
      std::fill_n(in.bounds.begin() + k * stride + n, bspf::detail::kBoxRun,
                  k % 2 == 0 ? kInfinity : -kInfinity);
    in.body.assign(stride, 0);
    in.fast.assign(stride, 0);
    for (std::uint32_t k = 0; k < n; ++k) {
      const Body& b = frame[order[k]];
      const Vec3 reach(b.radii.xz + b.settings.skin, b.radii.y + b.settings.skin,
                       b.radii.xz + b.settings.skin);
      const Vec3 lo = b.lastStepStart.cwiseMin(b.position) - reach,
                 hi = b.lastStepStart.cwiseMax(b.position) + reach;
      for (int axis = 0; axis < 3; ++axis) {
        in.bounds[(2 * axis) * stride + k] = lo[axis];
        in.bounds[(2 * axis + 1) * stride + k] = hi[axis];
      }
      const Vec3 move =
          (b.position - b.lastStepStart).cwiseQuotient(Vec3(b.radii.xz, b.radii.y, b.radii.xz));
      in.body[k] = order[k];
      in.fast[k] = move.norm() > bspf::kSweepMinMove ? ~0u : 0u;
    }
    const float* bounds = in.bounds.data();
    in.sorted = {bounds,
                 bounds + stride,
                 bounds + 2 * stride,
                 bounds + 3 * stride,
                 bounds + 4 * stride,
                 bounds + 5 * stride,
                 in.body.data(),
                 in.fast.data(),
                 n};
  }
  std::vector<std::uint64_t> pairs;
  std::size_t found = 0;
  cycle(state, inputs, [&](const Boxes& in) {
    pairs.clear();
    if (fourAtATime)
      bspf::detail::appendMeetingPairs(in.sorted, pairs);
    else
      bspf::detail::appendMeetingPairsOneByOne(in.sorted, pairs);
    benchmark::DoNotOptimize(pairs.data());
    found += pairs.size();
  });
  state.counters["pairs"] = benchmark::Counter(double(found) / double(state.iterations()));
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
  const std::filesystem::path source = BSPF_SOURCE_DIR;
  std::vector<std::filesystem::path> bases{source / "samples/arena"};
  if (std::filesystem::exists(source / "../shared/levels/oa_dm5.obj"))
    bases.push_back(source / "../shared/levels/oa_dm5");
  std::vector<std::unique_ptr<Level>> levels;
  for (const auto& base : bases) {
    std::unique_ptr<Level> level = loadLevel(base);
    if (!level) return 1;
    levels.push_back(std::move(level));
  }
  for (const auto& owned : levels) {
    const Level& level = *owned;
    const std::string suffix = "/" + level.name;
    benchmark::RegisterBenchmark(("PreCheck" + suffix).c_str(), preCheck, std::cref(level));
    benchmark::RegisterBenchmark(("InsideGrownTriangle" + suffix).c_str(), insideGrownTriangle,
                                 std::cref(level));
    benchmark::RegisterBenchmark(("EarliestImpact" + suffix).c_str(), earliestImpact,
                                 std::cref(level));
    benchmark::RegisterBenchmark(("ExactPerTriangle" + suffix).c_str(), exactPerTriangle,
                                 std::cref(level));
    benchmark::RegisterBenchmark(("FaceStageWithinReach/measured" + suffix).c_str(),
                                 faceStageWithinReach, std::cref(level), true);
    benchmark::RegisterBenchmark(("FaceStageWithinReach/closest" + suffix).c_str(),
                                 faceStageWithinReach, std::cref(level), false);
    benchmark::RegisterBenchmark(("CandidateTriangles" + suffix).c_str(), candidateTriangles,
                                 std::cref(level));
    benchmark::RegisterBenchmark(("StoredBoxes64/sse" + suffix).c_str(), storedBoxes,
                                 std::cref(level), true);
    benchmark::RegisterBenchmark(("StoredBoxes64/plain" + suffix).c_str(), storedBoxes,
                                 std::cref(level), false);
    for (const bspf::detail::MaskPath path : bspf::detail::availableMaskPaths()) {
      const char* name = path == bspf::detail::MaskPath::Avx   ? "avx"
                         : path == bspf::detail::MaskPath::Sse ? "sse"
                                                               : "scalar";
      benchmark::RegisterBenchmark(("PlanesMask/" + std::string(name) + suffix).c_str(), planesMask,
                                   std::cref(level), path);
    }
    benchmark::RegisterBenchmark(("StepBody/planes" + suffix).c_str(), stepBody, std::cref(level),
                                 CollisionMethod::Planes);
    benchmark::RegisterBenchmark(("StepBody/exact" + suffix).c_str(), stepBody, std::cref(level),
                                 CollisionMethod::ExactSweep);
    benchmark::RegisterBenchmark(("BodyGridBuild/6ms" + suffix).c_str(), bodyGridBuild,
                                 std::cref(level.walkingFrames));
    benchmark::RegisterBenchmark(("BodyGridBuild/40ms" + suffix).c_str(), bodyGridBuild,
                                 std::cref(level.runningFrames));
    benchmark::RegisterBenchmark(("MeetingPairs/sse" + suffix).c_str(), meetingPairs,
                                 std::cref(level.runningFrames), true);
    benchmark::RegisterBenchmark(("MeetingPairs/one_by_one" + suffix).c_str(), meetingPairs,
                                 std::cref(level.runningFrames), false);
  }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
