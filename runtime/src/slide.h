// SPDX-License-Identifier: MIT
// The narrow phases of the movement step: each moves a body's centre from
// `start` towards `desiredEnd` against the level's triangles, sliding along
// what it meets. Private to the runtime.
#pragma once

#include <bspf/movement.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <numbers>
#include <optional>
#include <utility>

#include "workspace.h"

namespace bspf {

struct Contact {
  Vec3 normal;  ///< unit, world space, pointing out of the surface
  bool walkable = false;
  /// Met on a triangle's edge or corner, not its face (the exact sweep's
  /// rounded contacts; the planes method meets faces only).
  bool edge = false;
  /// Where the body touched (StepReport::contactPoints), metres, world.
  Vec3 point;
  /// The triangle met (StepReport::contactTriangles).
  std::uint32_t triangle;
};

/// The point of the ellipsoid at `centre` whose outward normal is -normal:
/// where it touches a surface of unit normal `normal` (the planes method's
/// contact point; the exact sweep's is the same point, found in sphere
/// space). `reach` is effectiveRadius(normal, radii).
inline Vec3 touchingPoint(const Vec3& centre, const Vec3& normal, float reach,
                          EllipsoidRadii radii) {
  const Vec3 squared(radii.xz * radii.xz, radii.y * radii.y, radii.xz * radii.xz);
  return centre - squared.cwiseProduct(normal) * (1 / reach);
}

struct SlideResult {
  Vec3 end;
  int iterations = 0;
  bool refused = false;
  int contactCount = 0;
  std::array<Contact, kMaxReportedContacts> contacts;
};

/// The article's method (CollisionMethod::Planes), defects fixed.
/// `hints`: triangles to test before scanning the candidates, each met
/// first if it blocks (the body's Body::groundTriangles; kNoTriangle
/// entries are skipped). At most 32.
SlideResult slideWithPlanes(const World& world, const Vec3& start, const Vec3& desiredEnd,
                            EllipsoidRadii radii, const MovementSettings& settings,
                            float walkableNormalY, StepScratch& scratch,
                            std::span<const std::uint32_t> hints = {});

/// Exact continuous collision in unit-sphere space (CollisionMethod::ExactSweep).
/// `hints`: the walkable triangles the body stood on last step
/// (Body::groundTriangles), `wallHints` the walls it met
/// (Body::wallTriangles); kNoTriangle entries are skipped. A body resting on
/// one of them at the skin's gap, its move pressing into it, slides along it
/// from the start, where a sweep would only have met it.
SlideResult slideExact(const World& world, const Vec3& start, const Vec3& desiredEnd,
                       EllipsoidRadii radii, const MovementSettings& settings,
                       float walkableNormalY, StepScratch& scratch,
                       std::span<const std::uint32_t> hints = {},
                       std::span<const std::uint32_t> wallHints = {});

/// How far, metres, a slide's tree query reaches past the box it needs on
/// every side: enough for its iterations (which move the end by about the
/// move's length at most) and for a walker's next frames, so most steps
/// query nothing. Larger pads query less often but list more triangles for
/// every scan. Measured on walkers (callgrind, instructions per step, oa_dm1,
/// oa_dm5, oacmpctf3, both methods) once a grounded body's scans stopped
/// listing its floor (Body::groundTriangles): against move + 0.15 m, half the
/// move + 0.3 m was 2 to 5% cheaper at 6 m/s and within 2% at 40 m/s; move +
/// 0.25 and move + 0.35 were as cheap at 6 m/s but 3 and 6% dearer at 40.
/// Tuned again beside NearbyTriangles::cover's reuse rule: 0.4 of the move +
/// 0.35 m (with that rule at 8 pads more, against half the move + 0.3 and 4
/// pads): 0.3 to 1.1% fewer instructions a step on the shared levels at
/// 6 m/s, 0.3 to 1.5% at 40, both methods; 0.4 + 0.4 and 0.45 + 0.35 were
/// dearer at 40 (callgrind, 64 walkers, 300 frames).
inline float nearbyPad(float moveLength) { return 0.4f * moveLength + 0.35f; }

/// The triangles one slide's iterations test: the body's nearby triangles
/// (StepScratch::nearby, or the body's cache in use), made into candidates for its radii once per
/// tree query (kept with the body between frames, their tests precomputed) in CandidateBlocks, of
/// which those whose box overlaps a local box around the slide are listed for every iteration to
/// scan (all of them when they are few). Listed again only when an iteration's swept box leaves the
/// local box (a slide moves the end by about the move's length at most).
/// `Make(std::uint32_t triangle)` returns the triangle's FaceTest for the
/// body; `Cold` holds the rest, made by the narrow phase on first use in a
/// making (generation()), and says whether the candidates are kept in
/// triangle order (Cold::kInTriangleOrder).
template <typename Cold, typename Make>
class LocalCandidates {
 public:
  LocalCandidates(detail::MadeCandidates<Cold>& made,
                  detail::UnzeroedVector<const detail::CandidateBlock*>& listed,
                  detail::UnzeroedVector<std::uint64_t>& sorted, Make make)
      : made_(made), listed_(listed), sorted_(sorted), make_(make) {}

  /// Blocks holding (at least) the candidates whose box may overlap
  /// `swept`, in triangle order lane by lane (filter by `swept`: the blocks
  /// hold more). `moveLength`, metres, sizes the local box and the tree
  /// query; `move` (the slide's whole move, metres) stretches the query
  /// ahead of the body, where its next frames go: up to 4 moves, at most
  /// 0.8 m (callgrind on walkers, planes, oa_dm1, oa_dm5, oacmpctf3: 5 to 8%
  /// fewer instructions per step at 6 m/s and 2% at 40 m/s than none. Tuned
  /// while walls were hints too: then 8 moves or no cap were as good at
  /// 6 m/s and worse at 40, 0.5 m and 1.2 m 2% worse at 40).
  detail::BlockList around(const World& world, const Bounds& swept, float moveLength,
                           EllipsoidRadii radii, StepScratch& scratch,
                           const Vec3& move = Vec3::Zero()) {
    if (valid_ && (swept.low.array() >= local_.low.array()).all() &&
        (swept.high.array() <= local_.high.array()).all())
      return current_;
    valid_ = true;
    const Vec3 grow = Vec3::Constant(0.05f * moveLength + kLocalGrowMetres);
    local_ = {swept.low - grow, swept.high + grow};
    NearbyTriangles& nearby = detail::activeNearby(scratch);
    nearby.cover(world, local_.low, local_.high, nearbyPad(moveLength), scratch.sweep,
                 std::min(kAheadMoves, kAheadMetres / std::max(moveLength, 1e-6f)) * move);
    if (!made_.madeFrom(nearby, radii)) remake(nearby, radii);
    // A short list is scanned whole (up to 6 blocks, 48 candidates: when
    // packing copied the blocks, 3 took 1 to 4% more instructions per step
    // on the walkers, 5 and 8 the same; listed by address, 3, 4 and 6 are
    // within 0.3%). Of a long one (fast bodies, dense geometry), the blocks
    // whose box overlaps the local box, in order.
    detail::StepWorkspace& workspace = scratch.workspace();
    workspace.lastLocal = local_;
    // Room for every block, kept between slides (growing it writes nothing:
    // UnzeroedVector).
    if (listed_.size() < made_.blocks.size())
      detail::resizeForRewrite(listed_, made_.blocks.size());
    std::size_t count = 0;
    if (made_.blocks.size() <= kScanWholeBlocks) {
      for (const detail::CandidateBlock& block : made_.blocks) listed_[count++] = &block;
      workspace.lastScanned = made_.cold.size();
    } else {
      for (const detail::CandidateBlock& block : made_.blocks)
        if (boxesOverlap(block.low, block.high, local_.low, local_.high)) listed_[count++] = &block;
      workspace.lastScanned = count * detail::kBlockLanes;
    }
    return keep(workspace, count);
  }

  Cold& operator[](std::uint32_t slot) { return made_.cold[slot]; }
  /// The triangle of candidate `slot`.
  std::uint32_t triangle(std::uint32_t slot) const { return made_.triangles[slot]; }
  /// MadeCandidates::generation of the candidates made last.
  std::uint64_t generation() const { return made_.generation; }

  /// Where triangle `t` is among the candidates (made by the last around()):
  /// its block and lane, or nothing when it is not a candidate. Candidates
  /// in triangle order are found by a binary search, others by a scan of
  /// their triangles (a few dozen, and each body asks for the same few
  /// between makings: the answers are kept).
  std::optional<std::pair<const detail::CandidateBlock*, int>> laneOf(std::uint32_t t) {
    auto& [triangle, slot] = made_.lookups[t % made_.lookups.size()];
    if (triangle != t) {
      const auto begin = made_.triangles.begin(), end = made_.triangles.end();
      auto it = end;
      if constexpr (Cold::kInTriangleOrder) {
        it = std::lower_bound(begin, end, t);
        if (it != end && *it != t) it = end;
      } else {
        it = std::find(begin, end, t);
      }
      triangle = t;
      slot = it != end ? std::uint32_t(it - begin) : detail::MadeCandidates<Cold>::kNotListed;
    }
    if (slot == detail::MadeCandidates<Cold>::kNotListed) return std::nullopt;
    return std::pair{&made_.blocks[slot / detail::kBlockLanes], int(slot % detail::kBlockLanes)};
  }

 private:
  // Makes the first `count` blocks listed the list around() returns until
  // the slide leaves its local box, and the workspace's last list. Each span
  // is made from the pointer and count, not copied from the other: GCC
  // copied a span just stored as two 8-byte words with one 16-byte load,
  // which waited for the stores (a failed store forward: 4% of the slide's
  // samples at walking speed).
  detail::BlockList keep(detail::StepWorkspace& workspace, std::size_t count) {
    const detail::CandidateBlock* const* first = listed_.data();
    current_ = {first, count};
    workspace.lastBlocks = {first, count};
    return {first, count};
  }

  // Makes the candidates of the nearby triangles: in the order the query
  // listed them, or (Cold::kInTriangleOrder) in triangle order whatever
  // order the query listed them in (which depends on the box it was made
  // for), where a narrow phase's ties would otherwise resolve differently
  // with a fresh query than with a body's older one.
  void remake(const NearbyTriangles& nearby, EllipsoidRadii radii) {
    const std::span<const CandidateTriangle> list = nearby.list();
    const std::size_t count = list.size();
    if constexpr (Cold::kInTriangleOrder) {
      // Sorted as keys (triangle, then its place in the list) rather than
      // as the 28-byte entries: a third of a query's cost at 40 m/s went to
      // swapping those.
      detail::resizeForRewrite(sorted_, count);
      for (std::size_t i = 0; i < count; ++i)
        sorted_[i] = std::uint64_t(list[i].triangle) << 32 | std::uint32_t(i);
      std::sort(sorted_.begin(), sorted_.end());
    }
    detail::resizeForRewrite(made_.blocks, (count + detail::kBlockLanes - 1) / detail::kBlockLanes);
    detail::resizeForRewrite(made_.cold, count);
    detail::resizeForRewrite(made_.triangles, count);
    made_.lookups.fill({kNoTriangle, detail::MadeCandidates<Cold>::kNotListed});
    for (std::uint32_t slot = 0; slot < count; ++slot) {
      const CandidateTriangle& c =
          list[Cold::kInTriangleOrder ? std::uint32_t(sorted_[slot]) : slot];
      detail::setLane(made_.blocks[slot / detail::kBlockLanes], int(slot % detail::kBlockLanes),
                      c.low, c.high, make_(c.triangle), slot);
      made_.triangles[slot] = c.triangle;
    }
    detail::finishBlocks(made_.blocks, count);
    made_.query = nearby.queryId();
    made_.radii = radii;
    ++made_.generation;
  }

  static constexpr float kLocalGrowMetres = 0.02f;
  static constexpr float kAheadMoves = 4.0f;
  static constexpr float kAheadMetres = 0.8f;
  static constexpr std::size_t kScanWholeBlocks = 6;
  detail::MadeCandidates<Cold>& made_;
  detail::UnzeroedVector<const detail::CandidateBlock*>& listed_;
  detail::UnzeroedVector<std::uint64_t>& sorted_;
  Make make_;
  Bounds local_;
  bool valid_ = false;
  /// What the last call returned (in listed_).
  detail::BlockList current_;
};

/// The narrow phase `settings.method` names. `hints`: see slideWithPlanes
/// and slideExact; `wallHints`: see slideExact (the planes method ignores
/// them).
SlideResult slideAgainstLevel(const World& world, const Vec3& start, const Vec3& desiredEnd,
                              EllipsoidRadii radii, const MovementSettings& settings,
                              float walkableNormalY, StepScratch& scratch,
                              std::span<const std::uint32_t> hints = {},
                              std::span<const std::uint32_t> wallHints = {});

/// The least normal y of a walkable contact: cos(walkableSlopeDegrees).
/// The last slope's value is kept per thread: the cosine took 1.6% of a
/// walking step's cycles, and most bodies share one slope.
inline float walkableNormalY(const MovementSettings& s) {
  thread_local float lastDegrees = -1, lastCosine = 0;
  if (s.walkableSlopeDegrees != lastDegrees) {
    lastCosine = std::cos(s.walkableSlopeDegrees * std::numbers::pi_v<float> / 180.0f);
    lastDegrees = s.walkableSlopeDegrees;
  }
  return lastCosine;
}

/// Adds a slide's figures to `report` (if any). Pushes between bodies add
/// their contacts but not their iterations or refusals: those describe the
/// body's own move.
inline void recordSlide(const World& world, StepReport* report, const SlideResult& slide,
                        bool ownMove) {
  if (!report) return;
  if (ownMove) {
    report->iterations += slide.iterations;
    report->refused = report->refused || slide.refused;
  }
  for (int i = 0; i < slide.contactCount && report->contactCount < kMaxReportedContacts; ++i) {
    const Contact& contact = slide.contacts[i];
    const int k = report->contactCount++;
    report->contactNormals[k] = contact.normal;
    report->contactPoints[k] = contact.point;
    report->contactTriangles[k] = contact.triangle;
    report->contactSurfaces[k] = world.triangleSurfaces()[contact.triangle];
  }
}

}  // namespace bspf
