// SPDX-License-Identifier: MIT
// The failure cases: small scenes, each built where collision methods are
// known to fail (thin walls, acute creases, outer corners, seams, slopes at the
// walkable limit, stairs, far from the origin, crowds, slivers), run for a
// method and measured with the accuracy oracle. Shared by `bspf_stability`
// (which writes the table of docs/stability.md) and the tests, so the table
// and the tests measure the very same runs.
//
// Every scene is generated in code from closed, outward-facing solids, so the
// winding-number inside test (oracle::insideClosedMesh) applies. Units:
// metres, seconds; bodies are 0.45 x 0.85 m ellipsoids unless a scene says
// otherwise; 60 frames per second.
#pragma once

#include <bspc/mesh.h>
#include <bspf/movement.h>

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace bspf::stability {

/// Positions of every body at every frame: trajectory[frame][body], frame 0
/// being the start.
using Trajectory = std::vector<std::vector<Vec3>>;

/// Whether a run met its scene's goal, and the measured figures that decided.
struct GoalResult {
  bool met = false;
  std::string detail;  ///< e.g. "max deviation from the open-floor run 0.31 m"
  /// The figures the detail prints, in its order and units, unrounded: what
  /// the tests bound for the cases documented as failing.
  std::vector<double> figures;
};

struct Scene {
  std::string name;
  /// The behaviour a correct method shows, in words (the table's "goal").
  std::string goal;
  bspc::Mesh level;
  /// Start states; the runner sets each body's settings.method.
  std::vector<Body> bodies;
  /// Input force of body `body` at frame `frame`, m/s^2 (xz only).
  std::function<Vec3(std::size_t body, int frame)> force;
  int frames = 180;
  float dt = 1.0f / 60.0f;
  /// When set, the same bodies and forces are also run in this level (same
  /// method), and the goal compares the two runs: an ideal level without the
  /// feature under test, or the same scene elsewhere.
  std::optional<bspc::Mesh> referenceLevel;
  /// Added to the reference run's start positions (and subtracted from its
  /// trajectory before the goal sees it).
  Vec3 referenceOffset = Vec3::Zero();
  /// Decides the goal from the run and, when referenceLevel is set, the
  /// reference run (else nullptr).
  std::function<GoalResult(const Trajectory& run, const Trajectory* reference)> checkGoal;
};

/// The tolerances every case must also meet, whatever its goal.
struct Tolerances {
  /// Deepest allowed penetration, as a fraction of the body's size
  /// (oracle::penetration). 0.01: a centimetre on a 1 m body.
  double penetrationMax = 0.01;
  /// Agent-frames with the centre inside a solid.
  long long insideSolid = 0;
};

/// What one scene measured with one method.
struct CaseResult {
  std::string scene;
  CollisionMethod method = CollisionMethod::Planes;
  double penetrationMax = 0;  ///< fraction of the body's size, over all bodies and frames
  double penetrationP99 = 0;
  long long insideSolid = 0;   ///< body-frames whose centre is inside a solid
  long long refusedMoves = 0;  ///< steps refused (StepReport::refused)
  /// Body-frames with an input force in which the body moved less than 1 mm
  /// horizontally: stuck (expected in a corner, a failure in the open).
  long long framesStuck = 0;
  /// Metres: over the last 30 frames, the largest distance of a body from the
  /// straight line fitted through its positions (0 for a body at rest or
  /// moving steadily; jitter and bumps show up here).
  double jitter = 0;
  GoalResult goal;
  bool safe = false;  ///< penetration and inside-solid within Tolerances
  bool pass() const { return safe && goal.met; }
};

/// The failure-case scenes, in the order of docs/stability.md.
std::vector<Scene> failureScenes();

/// Compiles `scene`'s level (and reference), runs every body with `method`
/// (stepBodies, so bodies also push each other), and measures.
CaseResult runScene(const Scene& scene, CollisionMethod method, const Tolerances& tolerances = {});

/// "planes" or "exact".
const char* methodName(CollisionMethod method);

}  // namespace bspf::stability
