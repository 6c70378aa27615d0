// SPDX-License-Identifier: MIT
// walkers_sim.h: the random-walk crowd of the `walkers` sample, header-only so
// the sample and its test run the very same simulation.
//
// Agents are ellipsoid bodies that each walk in a random direction, picking a
// new one every 0.5 to 2 s, at a fixed speed, under gravity; all of them are
// advanced together with bspf::stepBodies (so they also push each other
// apart). Everything is deterministic for a given seed: the random numbers
// come from splitmix64 streams, not from <random>'s distributions (whose
// output differs between standard libraries).
//
// Start positions come from a spawn file (startsFromSpawns) or are chosen on
// walkable floor (placeOnFloor). countInsideSolid checks centres against the
// level's brushes (brushes.h, the bspf::brushes library). Only the runtime is
// used: no compiler.
#pragma once

#include <bspf/movement.h>
#include <bspf/query.h>
#include <bspf/scene_query.h>
#include <bspf/thread_pool.h>
#include <bspf/world.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "brushes.h"

namespace bspf::walkers {

/// What to simulate. Defaults: the sample's defaults.
struct Options {
  int agents = 64;
  int frames = 600;
  float speed = 6.0f;       ///< walking speed, m/s
  float dt = 1.0f / 60.0f;  ///< seconds per frame
  EllipsoidRadii radii{0.45f, 0.85f};
  /// Narrow phase: the article's planes (default) or the exact sweep.
  CollisionMethod method = CollisionMethod::Planes;
  /// MovementSettings::maxStepHeight, metres: 0 (off) by default.
  float stepHeight = 0.0f;
  /// MovementSettings::maxStepDown, metres (ground snapping): its default.
  float stepDown = MovementSettings{}.maxStepDown;
  std::uint64_t seed = 1;
  /// Threads stepping the crowd (a bspf::ThreadPool); the trajectories are
  /// the same for any number.
  int threads = 1;
  /// Each of those threads on a CPU of its own (ThreadPool::Affinity::
  /// PinWorkers, and the calling thread pinned to the first CPU): the
  /// trajectories are the same either way.
  bool pinThreads = false;
  /// ThreadPool's spinBeforeSleep, microseconds: 5 ms, longer than the
  /// gap between two frames here (they are stepped back to back), so the
  /// workers stay awake, and on their CPUs, from frame to frame. With the
  /// pool's 50 µs default they slept now and then, and on the project's
  /// 2-core VM woke on the main thread's CPU: 2 threads ran no faster than
  /// one.
  int spinMicroseconds = 5000;
};

/// An empty string when `options` can run, else what is wrong with them.
inline std::string validate(const Options& o) {
  auto text = [](float v) {
    std::ostringstream out;
    out << v;
    return out.str();
  };
  auto positive = [](float v) { return std::isfinite(v) && v > 0; };
  if (o.agents < 1 || o.agents > 1000000)
    return "--agents must be 1 to 1000000 (got " + std::to_string(o.agents) + ")";
  if (o.frames < 1) return "--frames must be >= 1 (got " + std::to_string(o.frames) + ")";
  if (!positive(o.speed) || o.speed > 10000)
    return "--speed must be > 0 and at most 10000 m/s (got " + text(o.speed) + ")";
  if (!positive(o.dt) || o.dt > 1)
    return "--dt must be > 0 and at most 1 s (got " + text(o.dt) + ")";
  if (!positive(o.radii.xz) || o.radii.xz > 100)
    return "--radius-xz must be > 0 and at most 100 m (got " + text(o.radii.xz) + ")";
  if (!positive(o.radii.y) || o.radii.y > 100)
    return "--radius-y must be > 0 and at most 100 m (got " + text(o.radii.y) + ")";
  if (o.threads < 1 || o.threads > 256)
    return "--threads must be 1 to 256 (got " + std::to_string(o.threads) + ")";
  if (o.spinMicroseconds < 0 || o.spinMicroseconds > 1000000)
    return "--spin-us must be 0 to 1000000 (got " + std::to_string(o.spinMicroseconds) + ")";
  if (!std::isfinite(o.stepHeight) || o.stepHeight < 0 || o.stepHeight > 2 * o.radii.y)
    return "--step-height must be 0 to twice --radius-y (got " + text(o.stepHeight) + ")";
  if (!std::isfinite(o.stepDown) || o.stepDown < 0 || o.stepDown > kMaxBodyRadius)
    return "--step-down must be 0 to " + text(kMaxBodyRadius) + " m (got " + text(o.stepDown) + ")";
  return {};
}

/// splitmix64: a tiny, portable, seedable generator.
class Random {
 public:
  explicit Random(std::uint64_t seed = 0) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1), 24 random bits.
  float uniform() { return static_cast<float>(next() >> 40) * 0x1p-24f; }
  float uniform(float lo, float hi) { return lo + (hi - lo) * uniform(); }

 private:
  std::uint64_t state_;
};

/// A seed for stream `stream` of run seed `seed` (streams are independent).
inline std::uint64_t streamSeed(std::uint64_t seed, std::uint64_t stream) {
  Random mix(seed ^ (0x5851f42d4c957f2dull * (stream + 1)));
  return mix.next();
}

/// Spawn points or start centres, or why there are none.
struct Points {
  std::vector<Vec3> points;
  std::string error;  ///< empty on success; else names the file or the level
  explicit operator bool() const { return error.empty(); }
};

/// Reads a spawn file: one `x y z` a line (blank lines and lines starting
/// with '#' skipped). Fails on an unreadable file, a line that is not three
/// finite numbers, or no point at all.
inline Points loadSpawns(const std::filesystem::path& path) {
  Points result;
  std::ifstream in(path);
  if (!in) {
    result.error = path.string() + ": cannot open the spawn file";
    return result;
  }
  std::string line;
  for (int lineNumber = 1; std::getline(in, line); ++lineNumber) {
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    double x, y, z;
    std::string rest;
    if (!(fields >> x >> y >> z) || (fields >> rest) || !std::isfinite(x) || !std::isfinite(y) ||
        !std::isfinite(z)) {
      result.error = path.string() + ": line " + std::to_string(lineNumber) +
                     ": expected three numbers 'x y z'";
      return result;
    }
    result.points.emplace_back(float(x), float(y), float(z));
  }
  if (in.bad())
    result.error = path.string() + ": read error";
  else if (result.points.empty())
    result.error = path.string() + ": no spawn point in the file";
  return result;
}

/// How far above a spawn point (a player origin) an agent's centre starts.
inline constexpr float kSpawnLift = 0.3f;

/// Start centres for `agents` agents: kSpawnLift above the spawn points,
/// round robin. Precondition: spawns not empty.
inline std::vector<Vec3> startsFromSpawns(std::span<const Vec3> spawns, int agents) {
  std::vector<Vec3> starts;
  starts.reserve(agents);
  for (int i = 0; i < agents; ++i)
    starts.push_back(spawns[std::size_t(i) % spawns.size()] + Vec3(0, kSpawnLift, 0));
  return starts;
}

namespace detail {

inline void triangleVertices(const World& world, std::uint32_t t, Vec3& a, Vec3& b, Vec3& c) {
  const schema::Triangle& tri = world.triangles()[t];
  a = toVec3(world.vertices()[tri.v0()]);
  b = toVec3(world.vertices()[tri.v1()]);
  c = toVec3(world.vertices()[tri.v2()]);
}

// Whether an ellipsoid with `radii` at `centre` is clear of every triangle of
// the level (the check is done in the space where it is the unit sphere).
inline bool bodyClear(const World& world, const Vec3& centre, EllipsoidRadii radii,
                      SweepScratch& scratch, std::vector<std::uint32_t>& candidates) {
  collectCandidateTriangles(world, centre, centre, radii, scratch, candidates);
  const Vec3 scale(1 / radii.xz, 1 / radii.y, 1 / radii.xz);
  const Vec3 p = centre.cwiseProduct(scale);
  for (const std::uint32_t t : candidates) {
    Vec3 a, b, c;
    triangleVertices(world, t, a, b, c);
    const Vec3 q = closestPointOnTriangle<Vec3>(p, a.cwiseProduct(scale), b.cwiseProduct(scale),
                                                c.cwiseProduct(scale));
    if ((q - p).squaredNorm() <= 1.0f) return false;
  }
  return true;
}

// What the ray from `origin` along `direction` (up to `length`) meets
// first: nothing, the front of a triangle, or the back of one (the origin is
// then inside a closed solid). At equal distances (within 10 um) a back face
// wins: the ray leaves a solid where another touches it. (A two-sided
// surface, a back-to-back pair, then counts as a back too: a false "inside"
// that only costs a placement attempt.)
enum class RayHit { Nothing, Front, Back };

inline RayHit firstRayHit(const World& world, const Vec3& origin, const Vec3& direction,
                          float length) {
  const std::optional<bspf::RayHit> front =
      castRay(world, origin, direction, length, RayFaces::Front);
  const float backReach = front ? front->distance + 1e-5f : length;
  if (castRay(world, origin, direction, backReach, RayFaces::Back)) return RayHit::Back;
  return front ? RayHit::Front : RayHit::Nothing;
}

}  // namespace detail

/// The steepest floor agents are placed on, degrees from horizontal.
inline constexpr float kPlacementSlopeDegrees = 45.0f;

/// Start centres on walkable floor, deterministic for `seed`: random points
/// (area-weighted) on the level's upward-facing triangles (normal within 45
/// degrees of +Y), the centre kSpawnLift + radii.y above the point. A point is
/// kept when the body there touches no triangle; when no ray from the centre
/// (up, and eight directions around the horizon) first meets the back of a
/// triangle, so the centre is not inside a closed solid; when every horizontal
/// ray meets the front of one, so the centre is enclosed, not out in the void
/// on the outside of the level's hull (the upward ray may escape: open sky);
/// and, while attempts last, when the body clears the agents already placed.
/// Fails, naming `levelName`, when too few points pass.
inline Points placeOnFloor(const World& world, int agents, EllipsoidRadii radii, std::uint64_t seed,
                           const std::string& levelName) {
  Points result;
  const float walkableY = std::cos(kPlacementSlopeDegrees * std::numbers::pi_v<float> / 180);
  std::vector<std::uint32_t> floors;
  std::vector<double> cumulativeArea;
  double total = 0;
  for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
    if (world.trianglePlanes()[t].face().normal().y() < walkableY) continue;
    Vec3 a, b, c;
    detail::triangleVertices(world, t, a, b, c);
    const double area = 0.5 * double((b - a).cross(c - a).norm());
    if (!(area > 1e-6)) continue;
    total += area;
    floors.push_back(t);
    cumulativeArea.push_back(total);
  }
  if (floors.empty()) {
    result.error = levelName + ": no upward-facing floor to place agents on (give --spawns)";
    return result;
  }
  const schema::World& blob = world.blob();
  const Vec3 low = toVec3(*blob.bounds_min()), high = toVec3(*blob.bounds_max());
  const float rayLength = (high - low).norm() + 1;
  // Up first, then around the horizon (between the axes, so rays do not run
  // along the faces of axis-aligned walls).
  std::vector<Vec3> rays{Vec3::UnitY()};
  for (int k = 0; k < 8; ++k) {
    const float angle = (float(k) + 0.5f) * std::numbers::pi_v<float> / 4;
    rays.emplace_back(std::cos(angle), 0.0f, std::sin(angle));
  }
  // The body is checked a little larger than it is, so it starts with room.
  const EllipsoidRadii grown{radii.xz + 0.05f, radii.y + 0.05f};

  Random rng(streamSeed(seed, 0xf100f));
  SweepScratch scratch;
  std::vector<std::uint32_t> candidates;
  const long long attempts = 1000 + 400LL * agents;
  for (long long attempt = 0; attempt < attempts && int(result.points.size()) < agents; ++attempt) {
    const double pick = double(rng.uniform()) * total;
    const std::size_t k =
        std::min<std::size_t>(std::upper_bound(cumulativeArea.begin(), cumulativeArea.end(), pick) -
                                  cumulativeArea.begin(),
                              floors.size() - 1);
    Vec3 a, b, c;
    detail::triangleVertices(world, floors[k], a, b, c);
    float u = rng.uniform(), v = rng.uniform();
    if (u + v > 1) u = 1 - u, v = 1 - v;
    const Vec3 centre = a + u * (b - a) + v * (c - a) + Vec3(0, kSpawnLift + radii.y, 0);
    // Keep agents apart during the first half of the attempts.
    if (attempt < attempts / 2) {
      bool crowded = false;
      for (const Vec3& other : result.points) {
        const Vec3 d = other - centre;
        if (std::hypot(d.x(), d.z()) < 2 * grown.xz && std::abs(d.y()) < 2 * grown.y) {
          crowded = true;
          break;
        }
      }
      if (crowded) continue;
    }
    if (!detail::bodyClear(world, centre, grown, scratch, candidates)) continue;
    bool open = true;
    for (std::size_t r = 0; r < rays.size() && open; ++r) {
      const detail::RayHit hit = detail::firstRayHit(world, centre, rays[r], rayLength);
      open = hit == detail::RayHit::Front || (r == 0 && hit == detail::RayHit::Nothing);
    }
    if (open) result.points.push_back(centre);
  }
  if (int(result.points.size()) < agents)
    result.error = levelName + ": found open floor for only " +
                   std::to_string(result.points.size()) + " of " + std::to_string(agents) +
                   " agents (give --spawns)";
  return result;
}

/// Start centres for options.agents agents: from the spawn file `spawnsPath`
/// (startsFromSpawns) or, when it is empty, on open walkable floor
/// (placeOnFloor, named `levelName` in errors).
inline Points placeAgents(const World& world, const Options& options, const std::string& spawnsPath,
                          const std::string& levelName) {
  if (spawnsPath.empty())
    return placeOnFloor(world, options.agents, options.radii, options.seed, levelName);
  Points spawns = loadSpawns(spawnsPath);
  if (spawns) spawns.points = startsFromSpawns(spawns.points, options.agents);
  return spawns;
}

/// How deep, metres, a centre must be inside a solid to count as inside: a
/// body resting on a face is within float noise of it, not inside.
inline constexpr float kInsideMargin = 1e-3f;

/// How many of `bodies` have their centre inside some solid of `brushes` by
/// more than kInsideMargin.
inline int countInsideSolid(const BrushSet& brushes, std::span<const Body> bodies) {
  int inside = 0;
  for (const Body& b : bodies) inside += brushes.insideAnySolid(b.position, kInsideMargin);
  return inside;
}

/// One agent's random walk: a new direction, uniformly random in the xz
/// plane, every 0.5 to 2 s. Deterministic for its seed.
class RandomWalk {
 public:
  explicit RandomWalk(std::uint64_t seed = 0) : rng_(seed) {}

  /// The input force, m/s^2, for the next frame of `dt` seconds at walking
  /// speed `speed` (m/s): 10 * speed along the current direction, which
  /// reaches the speed within 0.1 s.
  Vec3 nextForce(float speed, float dt) {
    if (turnIn_ <= 0) {
      const float angle = rng_.uniform(0, 2 * std::numbers::pi_v<float>);
      direction_ = Vec3(std::cos(angle), 0, std::sin(angle));
      turnIn_ = rng_.uniform(0.5f, 2.0f);
    }
    turnIn_ -= dt;
    return direction_ * (10 * speed);
  }

 private:
  Random rng_;
  Vec3 direction_ = Vec3::Zero();
  float turnIn_ = 0;  ///< seconds until the next turn
};

/// Figures of a run so far.
struct Summary {
  long long steps = 0;          ///< agents * frames stepped
  double nsPerStep = 0;         ///< median over frames of (frame's stepBodies time / agents)
  long long refusedMoves = 0;   ///< steps whose move was refused
  double iterationsMean = 0;    ///< mean slides per step
  int iterationsMax = 0;        ///< most slides in one step
  double groundedFraction = 0;  ///< steps ending grounded / steps
  double bodyContactsMean = 0;  ///< mean bodies pushed apart from, per step
};

/// The crowd: one body per start centre, each walking at options.speed.
class Simulation {
 public:
  /// Precondition: validate(options) is empty and starts.size() == agents.
  Simulation(const World& world, std::span<const Vec3> starts, const Options& options)
      : world_(&world),
        options_(options),
        pool_(std::make_unique<ThreadPool>(
            options.threads,
            options.pinThreads ? ThreadPool::Affinity::PinWorkers : ThreadPool::Affinity::None,
            std::chrono::microseconds(options.spinMicroseconds))),
        scratches_(std::size_t(options.threads)) {
    // After the pool: its workers were placed from the process's CPUs.
    if (options.pinThreads) ThreadPool::pinThisThreadToFirstCpu();
    bodies_.resize(starts.size());
    agents_.resize(starts.size());
    forces_.assign(starts.size(), Vec3::Zero());
    reports_.resize(starts.size());
    for (std::size_t i = 0; i < starts.size(); ++i) {
      Body& body = bodies_[i];
      body.position = starts[i];
      body.radii = options.radii;
      body.settings.method = options.method;
      body.settings.maxStepHeight = options.stepHeight;
      body.settings.maxStepDown = options.stepDown;
      body.settings.maxHorizontalSpeed = options.speed;
      agents_[i] = RandomWalk(streamSeed(options.seed, i + 1));
    }
  }

  /// Advances every agent by one frame: turns the agents whose walk is up,
  /// then one stepBodies call (on options.threads threads), the only part
  /// timed.
  /// `beforeStep`, when given, sees the bodies and their forces just before
  /// the timed stepBodies call (for measurements from the same state).
  void step(
      const std::function<void(std::span<const Body>, std::span<const Vec3>)>& beforeStep = {}) {
    for (std::size_t i = 0; i < agents_.size(); ++i)
      forces_[i] = agents_[i].nextForce(options_.speed, options_.dt);
    if (beforeStep) beforeStep(bodies_, forces_);
    const auto start = std::chrono::steady_clock::now();
    stepBodies(*world_, bodies_, forces_, options_.dt, *pool_, scratches_, reports_);
    const auto stop = std::chrono::steady_clock::now();
    frameNsPerStep_.push_back(std::chrono::duration<double, std::nano>(stop - start).count() /
                              double(bodies_.size()));
    for (const StepReport& r : reports_) {
      ++steps_;
      refused_ += r.refused;
      iterations_ += r.iterations;
      iterationsMax_ = std::max(iterationsMax_, r.iterations);
      grounded_ += r.grounded;
      bodyContacts_ += r.bodyContacts;
    }
    ++frame_;
  }

  int frame() const { return frame_; }
  /// ThreadPool::sleeps of the pool stepping the crowd.
  unsigned long long poolSleeps() const { return pool_->sleeps(); }
  std::span<const Body> bodies() const { return bodies_; }
  std::span<const StepReport> reports() const { return reports_; }

  Summary summary() const {
    Summary s;
    s.steps = steps_;
    if (steps_ == 0) return s;
    std::vector<double> times = frameNsPerStep_;
    const std::size_t mid = times.size() / 2;
    std::nth_element(times.begin(), times.begin() + mid, times.end());
    s.nsPerStep = times[mid];
    if (times.size() % 2 == 0) {
      const double below = *std::max_element(times.begin(), times.begin() + mid);
      s.nsPerStep = 0.5 * (s.nsPerStep + below);
    }
    s.refusedMoves = refused_;
    s.iterationsMean = double(iterations_) / double(steps_);
    s.iterationsMax = iterationsMax_;
    s.groundedFraction = double(grounded_) / double(steps_);
    s.bodyContactsMean = double(bodyContacts_) / double(steps_);
    return s;
  }

 private:
  const World* world_;
  Options options_;
  std::vector<Body> bodies_;
  std::vector<RandomWalk> agents_;
  std::vector<Vec3> forces_;
  std::vector<StepReport> reports_;
  std::unique_ptr<ThreadPool> pool_;    // created once, reused every frame
  std::vector<StepScratch> scratches_;  // one per pool thread
  std::vector<double> frameNsPerStep_;
  int frame_ = 0;
  long long steps_ = 0, refused_ = 0, iterations_ = 0, grounded_ = 0, bodyContacts_ = 0;
  int iterationsMax_ = 0;
};

}  // namespace bspf::walkers
