// The narrow phases of the movement step: each moves a body's centre from
// `start` towards `desiredEnd` against the level's triangles, sliding along
// what it meets. Private to the runtime.
#pragma once

#include <bspf/movement.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "workspace.h"

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

/// How far, metres, a slide's tree query reaches past the box it needs on
/// every side: enough for its iterations (which move the end by about the
/// move's length at most) and for the next few frames of travel, so most
/// steps query nothing. Larger pads query less often but list more triangles.
inline float nearbyPad(float moveLength) { return 2.0f * moveLength + 0.1f; }

/// The triangles one slide's iterations test: the body's nearby triangles
/// (StepScratch::nearby) whose box overlaps a local box around the slide,
/// each made into a `Candidate` (its tests precomputed for the body) in
/// `list`, a short array every iteration scans. Made again only when an
/// iteration's swept box leaves the local box (a slide moves the end by
/// about the move's length at most).
template <typename Candidate, typename Make>
class LocalCandidates {
 public:
  LocalCandidates(std::vector<Candidate>& list, Make make) : list_(list), make_(make) {}

  /// Candidates whose box may overlap `swept` (filter by it: the list holds
  /// more). `moveLength`, metres, sizes the local box and the tree query.
  std::span<Candidate> around(const World& world, const Bounds& swept, float moveLength,
                              StepScratch& scratch) {
    if (!valid_ || !(swept.low.array() >= local_.low.array()).all() ||
        !(swept.high.array() <= local_.high.array()).all()) {
      valid_ = true;
      const Vec3 grow = Vec3::Constant(0.25f * moveLength + kLocalGrowMetres);
      local_ = {swept.low - grow, swept.high + grow};
      scratch.nearby.cover(world, local_.low, local_.high, nearbyPad(moveLength), scratch.sweep);
      list_.clear();
      for (const CandidateTriangle& c : scratch.nearby.list())
        if (boxesOverlap(c.low, c.high, local_.low, local_.high)) list_.push_back(make_(c));
      // In triangle order, whatever order the query listed them in (which
      // depends on the box it was made for): ties in the narrow phases then
      // resolve the same with a fresh query as with a body's older one.
      std::sort(list_.begin(), list_.end(),
                [](const Candidate& a, const Candidate& b) { return a.triangle < b.triangle; });
      scratch.workspace().lastCount = list_.size();
    }
    return list_;
  }

 private:
  static constexpr float kLocalGrowMetres = 0.02f;
  std::vector<Candidate>& list_;
  Make make_;
  Bounds local_;
  bool valid_ = false;
};

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
