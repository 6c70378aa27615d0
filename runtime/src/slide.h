// The narrow phases of the movement step: each moves a body's centre from
// `start` towards `desiredEnd` against the level's triangles, sliding along
// what it meets. Private to the runtime.
#pragma once

#include <bspf/movement.h>

#include <array>
#include <cmath>
#include <numbers>

namespace bspf {

struct Contact {
  Vec3 normal;  ///< unit, world space, pointing out of the surface
  bool walkable = false;
  /// Met on a triangle's edge or corner, not its face (the exact sweep's
  /// rounded contacts; the planes method meets faces only).
  bool edge = false;
};

struct SlideResult {
  Vec3 end;
  int iterations = 0;
  bool refused = false;
  int contactCount = 0;
  std::array<Contact, kMaxReportedContacts> contacts;
};

/// The article's method (CollisionMethod::Planes), defects fixed.
SlideResult slideWithPlanes(const World& world, const Vec3& start, const Vec3& desiredEnd,
                            EllipsoidRadii radii, const MovementSettings& settings,
                            float walkableNormalY, StepScratch& scratch);

/// Exact continuous collision in unit-sphere space (CollisionMethod::ExactSweep).
SlideResult slideExact(const World& world, const Vec3& start, const Vec3& desiredEnd,
                       EllipsoidRadii radii, const MovementSettings& settings,
                       float walkableNormalY, StepScratch& scratch);

/// Added to a slide's first tree query on every side, metres, on top of the
/// move's length, so the iterations of a slide rarely query again.
inline constexpr float kNearbyPadMetres = 0.05f;

/// The narrow phase `settings.method` names.
SlideResult slideAgainstLevel(const World& world, const Vec3& start, const Vec3& desiredEnd,
                              EllipsoidRadii radii, const MovementSettings& settings,
                              float walkableNormalY, StepScratch& scratch);

/// The least normal y of a walkable contact: cos(walkableSlopeDegrees).
inline float walkableNormalY(const MovementSettings& s) {
  return std::cos(s.walkableSlopeDegrees * std::numbers::pi_v<float> / 180.0f);
}

/// Adds a slide's figures to `report` (if any). Pushes between bodies add
/// their contacts but not their iterations or refusals: those describe the
/// body's own move.
void recordSlide(StepReport* report, const SlideResult& slide, bool ownMove);

}  // namespace bspf
