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
/// (StepScratch::nearby), made into `Candidate`s for its radii once per tree
/// query (kept with the body between frames, their tests precomputed), of
/// which those whose box overlaps a local box around the slide are listed,
/// by index, in a short list every iteration scans. Listed again only when
/// an iteration's swept box leaves the local box (a slide moves the end by
/// about the move's length at most).
template <typename Candidate, typename Make>
class LocalCandidates {
 public:
  LocalCandidates(detail::MadeCandidates<Candidate>& made, std::vector<std::uint32_t>& listed,
                  Make make)
      : made_(made), listed_(listed), make_(make) {}

  /// Indices (for operator[]) of candidates whose box may overlap `swept`,
  /// in triangle order (filter by `swept`: the list holds more).
  /// `moveLength`, metres, sizes the local box and the tree query.
  std::span<const std::uint32_t> around(const World& world, const Bounds& swept, float moveLength,
                                        EllipsoidRadii radii, StepScratch& scratch) {
    if (valid_ && (swept.low.array() >= local_.low.array()).all() &&
        (swept.high.array() <= local_.high.array()).all())
      return listed_;
    valid_ = true;
    const Vec3 grow = Vec3::Constant(0.05f * moveLength + kLocalGrowMetres);
    local_ = {swept.low - grow, swept.high + grow};
    scratch.nearby.cover(world, local_.low, local_.high, nearbyPad(moveLength), scratch.sweep);
    if (made_.query != scratch.nearby.queryId() || made_.radii.xz != radii.xz ||
        made_.radii.y != radii.y) {
      made_.list.clear();
      for (const CandidateTriangle& c : scratch.nearby.list()) made_.list.push_back(make_(c));
      // In triangle order, whatever order the query listed them in (which
      // depends on the box it was made for): ties in the narrow phases then
      // resolve the same with a fresh query as with a body's older one.
      std::sort(made_.list.begin(), made_.list.end(),
                [](const Candidate& a, const Candidate& b) { return a.triangle < b.triangle; });
      made_.query = scratch.nearby.queryId();
      made_.radii = radii;
    }
    listed_.clear();
    for (std::uint32_t i = 0; i < made_.list.size(); ++i)
      if (boxesOverlap(made_.list[i].low, made_.list[i].high, local_.low, local_.high))
        listed_.push_back(i);
    scratch.workspace().lastCount = listed_.size();
    return listed_;
  }

  Candidate& operator[](std::uint32_t index) { return made_.list[index]; }

 private:
  static constexpr float kLocalGrowMetres = 0.02f;
  detail::MadeCandidates<Candidate>& made_;
  std::vector<std::uint32_t>& listed_;
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
