// SPDX-License-Identifier: MIT
// CollisionMethod::Planes: the article's six-plane narrow phase and its
// slide, with the defects fixed that docs/algorithm.md lists.
#include <Eigen/LU>
#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <limits>

#include "narrow_phase.h"
#include "rounded_edges.h"
#include "slide.h"

namespace bspf {

namespace {

// The blocking triangle findBlockingTriangle chose, with its face plane
// (from the candidate's block: the blob's copy is likely out of cache).
// A plain struct, not std::optional: the optional's flag, written as a byte
// and read back as a word, stalled every scan on a failed store forward.
struct Hit {
  static constexpr std::uint32_t kNone = ~std::uint32_t(0);
  std::uint32_t triangle = kNone;
  // normal · the move (not its direction: the order is the same, and no
  // square root sits on the scan's path).
  float facing = 0;
  Vec3 normal = Vec3::Zero();
  float distance = 0;
  float reach = 0;  // effectiveRadius(normal, radii), from the candidate's block
  bool found() const { return triangle != kNone; }
};

// One move's values that every candidate's test reads.
struct Move {
  Vec3 start, end, step;  // step = end - start
  EllipsoidRadii radii;
  float walkableNormalY;
};

Move makeMove(const Vec3& start, const Vec3& end, EllipsoidRadii radii, float walkableNormalY) {
  return {start, end, end - start, radii, walkableNormalY};
}

// Offers the candidate in `lane` of `block` to `best` if it blocks the move.
// Precondition: the lane passed the planes method's mask (its box overlaps
// the swept box, endSide < reach, startSide >= 0), whose side values (the
// start's and end's signed distances to the face plane) are passed in.
// Inlined into the scan: it runs for about 3 lanes a scan, and the call's
// register saves and argument passing were a fifth of its instructions.
[[gnu::always_inline]] inline void offerLane(const World& world,
                                             const detail::CandidateBlock& block, int lane,
                                             float startSide, float endSide, const Move& move,
                                             auto& local, Hit& best) {
  const std::uint32_t slot = block.slot[lane];
  // Only a lane that would replace `best` is worth its six planes: one
  // facing the move less, or as much with a higher triangle, loses to it
  // whether it blocks or not. The order is the comparison's at the end,
  // made first. (At 40 m/s a scan that finds a blocking triangle found 4 on
  // average, most of them the floor's coplanar pieces under the body's end:
  // walkers on oa_dm5, planes.)
  const Vec3 normal(block.normalX[lane], block.normalY[lane], block.normalZ[lane]);
  const float facing = normal.dot(move.step);
  const std::uint32_t t = local.triangle(slot);
  if (best.found() && !(facing < best.facing || (facing == best.facing && t < best.triangle)))
    return;
  detail::PlanesCold& candidate = local[slot];
  const float reach = block.reach[lane];
  if (candidate.grownIn != local.generation()) {
    candidate.triangle = t;
    detail::growPlanes(world, candidate.triangle, move.radii, candidate.grown);
    candidate.grownIn = local.generation();
  }
  // Test the six planes where the centre crosses the offset plane (the
  // article leaves this position unspecified: testing the end lets fast
  // bodies skip small triangles). A body already within it is tested at
  // its start and at its end.
  // `point`: where the planes were met.
  Vec3 point = move.end;
  bool inside;
  if (startSide >= reach) {
    const float f = (startSide - reach) / (startSide - endSide);
    point = move.start + f * move.step;
    inside = candidate.grown.inside(point);
  } else if (candidate.grown.inside(move.start)) {
    point = move.start;
    inside = true;
  } else {
    inside = candidate.grown.inside(move.end);
  }
  if (!inside) return;
  // A steep face's squared-off edge that a rounded body rides over (a lip's
  // top edge) does not block: the walkable face behind it holds the body
  // (rounded_edges.h).
  if (normal.y() < move.walkableNormalY &&
      detail::ridesOverEdge(world, candidate.triangle, candidate.grown.highestY, point, move.start,
                            move.end, move.radii, move.walkableNormalY))
    return;
  best = Hit{t, facing, normal, block.distance[lane], reach};
}

// Offers every candidate of `blocks` in the way of the move to `best`,
// which then holds the one with the lowest facing value, if any (else
// !found()). Filled in place: the slide's one Hit, never copied back.
// `planesMask`: detail::planesMaskFunction(), asked once per slide.
void findBlockingTriangle(const World& world, const Move& move, const Bounds& swept, auto& local,
                          detail::BlockList blocks, detail::PlanesMaskFunction planesMask,
                          Hit& best) {
  detail::LaneSides sides;
  const detail::BlockBoxTest boxTest(swept);
  for (const detail::CandidateBlock* const listed : blocks) {
    const detail::CandidateBlock& block = *listed;
    if (!boxTest.meets(block)) continue;
    // The cheap tests for the whole block at once (the box, then the
    // pre-check's two dot products, whose values it keeps); the six planes
    // only for the few lanes that pass (about 4 a scan on the shared
    // levels, most of them beside the triangle the body touches).
    for (std::uint32_t bits = planesMask(block, swept, move.start, move.end, sides); bits != 0;
         bits &= bits - 1) {
      const int lane = std::countr_zero(bits);
      offerLane(world, block, lane, sides.start[lane], sides.end[lane], move, local, best);
    }
  }
}

// Offers triangle `t` to `best` if it is a candidate and blocks the move:
// the test findBlockingTriangle makes of each candidate, for this one alone.
void offerTriangle(const World& world, std::uint32_t t, const Move& move, const Bounds& swept,
                   auto& local, Hit& best) {
  const auto lane = local.laneOf(t);
  if (!lane) return;
  const detail::CandidateBlock& block = *lane->first;
  const int i = lane->second;
  // planesMask's test, for this lane alone.
  if (!detail::laneBoxOverlaps(block, i, swept)) return;
  const float startSide = detail::laneSide(block, i, move.start),
              endSide = detail::laneSide(block, i, move.end);
  if (endSide < block.reach[i] && startSide >= 0)
    offerLane(world, block, i, startSide, endSide, move, local, best);
}

// A surface the end was moved out of this step: the end must keep
// dot(normal, end) >= target, and is moved along `push` to get there.
struct Constraint {
  Vec3 normal;
  float target;
  Vec3 push;
};

float violation(const Constraint& c, const Vec3& end) { return c.target - c.normal.dot(end); }

// Moves `end` along the push directions of `set` (2 or 3 constraints) so it
// lies on all of them at once: the crease or corner they form. Returns false
// (and leaves `end`) when they are too close to parallel to meet, or when
// meeting them would pull the end into any of them.
template <int N>
bool meetConstraints(const std::array<const Constraint*, N>& set, float maxShift, Vec3& end) {
  Eigen::Matrix<float, N, N> m;
  Eigen::Matrix<float, N, 1> need;
  for (int r = 0; r < N; ++r) {
    for (int c = 0; c < N; ++c) m(r, c) = set[r]->normal.dot(set[c]->push);
    need(r) = violation(*set[r], end);
  }
  const Eigen::FullPivLU<Eigen::Matrix<float, N, N>> lu(m);
  if (!lu.isInvertible() || std::abs(lu.determinant()) < 1e-3f) return false;
  const Eigen::Matrix<float, N, 1> amount = lu.solve(need);
  if ((amount.array() < -1e-4f).any()) return false;
  Vec3 shift = Vec3::Zero();
  for (int c = 0; c < N; ++c) shift += amount(c) * set[c]->push;
  // Nearly parallel surfaces meet far away: going there would teleport the
  // body. Such a crease is left to the ordinary slides.
  if (!(shift.norm() <= maxShift)) return false;
  end += shift;
  return true;
}

// Moves the end out of blocking triangles until none blocks, or refuses the
// move after maxIterations slides. Walkable contacts push the end straight
// up rather than along the normal, so a body standing on a slope does not
// creep down it. When moving out of one surface puts the end back into a
// surface of an earlier slide (a crease, or a corner of three), the end goes
// to where they meet at once instead of bouncing between them, which would
// use up the iterations and refuse the move.
}  // namespace

namespace detail {

void growPlanes(const World& world, std::uint32_t triangle, EllipsoidRadii radii,
                GrownTriangle& grown) {
  const schema::TrianglePlanes& planes = world.trianglePlanes()[triangle];
  // Each perpendicular plane pushed out by the body's extent along its own
  // normal (a local offset; the stored plane is never modified, the
  // article's second defect).
  auto grow = [&](const schema::Plane& plane, int k) {
    const Vec3 n = toVec3(plane.normal());
    grown.set(k, n, plane.distance() - effectiveRadius(n, radii));
  };
  for (int k = 0; k < 3; ++k) {
    grow(*planes.edges()->Get(k), 2 * k);
    grow(*planes.caps()->Get(k), 2 * k + 1);
  }
  // A plane the blob marks as never met (TrianglePlanes::meetable) always
  // holds, like lanes 6 and 7: the face blocks beyond it too. bspc keeps
  // every plane (docs/algorithm.md), so this is one test per triangle.
  constexpr float kAlways = -std::numeric_limits<float>::infinity();
  constexpr unsigned kAllMeetable = 0b111111;
  if (const unsigned meetable = planes.meetable(); meetable != kAllMeetable) [[unlikely]] {
    for (int k = 0; k < 6; ++k) {
      const unsigned bit = k % 2 == 0 ? 1u << (k / 2) : 8u << (k / 2);
      if (!(meetable & bit)) grown.set(k, Vec3::Zero(), kAlways);
    }
  }
  for (int k = 6; k < 8; ++k) grown.set(k, Vec3::Zero(), kAlways);
  grown.highestY = highestCornerY(world, triangle);
}

}  // namespace detail

SlideResult slideWithPlanes(const World& world, const Vec3& start, const Vec3& desiredEnd,
                            EllipsoidRadii radii, const MovementSettings& settings,
                            float walkableNormalY, StepScratch& scratch,
                            std::span<const std::uint32_t> hints) {
  SlideResult result;
  result.end = desiredEnd;
  std::array<Constraint, kMaxReportedContacts> constraints;
  int constraintCount = 0;
  // A crease solution may move the end at most this far: a frame's travel
  // plus the body's size.
  const float moveLength = (desiredEnd - start).norm();
  const float maxShift = moveLength + std::max(radii.xz, radii.y);
  detail::StepWorkspace& workspace = scratch.workspace();
  LocalCandidates local(
      detail::activePlanes(workspace), workspace.listed, workspace.sorted,
      [&](std::uint32_t triangle) { return detail::planesFaceTest(world, triangle, radii); });
  assert(hints.size() <= 32);
  // Bit k: hints[k] is a triangle not tested yet. Set once, so an
  // iteration skips the spent and empty entries without reading them.
  std::uint32_t hintsLeft = 0;
  std::size_t k = 0;
#ifdef BSPF_SSE_MASKS
  // Four at a time (a body's kGroundTriangles at once): the loop a hint at a
  // time took 32 instructions a slide.
  static_assert(kNoTriangle == 0xFFFFFFFFu);
  for (; k + 4 <= hints.size(); k += 4) {
    const __m128i empty = _mm_cmpeq_epi32(
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(hints.data() + k)), _mm_set1_epi32(-1));
    hintsLeft |= (~std::uint32_t(_mm_movemask_ps(_mm_castsi128_ps(empty))) & 15u) << k;
  }
#endif
  for (; k < hints.size(); ++k) hintsLeft |= std::uint32_t(hints[k] != kNoTriangle) << k;
  const detail::PlanesMaskFunction planesMask = detail::planesMaskFunction();
  for (int iteration = 0;; ++iteration) {
    const Bounds swept = detail::slideSweptBounds(start, result.end, radii);
    const Move move = makeMove(start, result.end, radii, walkableNormalY);
    const detail::BlockList blocks =
        local.around(world, swept, moveLength, radii, scratch, desiredEnd - start);
    // The triangles the body met last step (its ground, the wall it walks
    // into) are most often what blocks it again: tested alone, each is met
    // without the scan that would find it among the candidates (and that,
    // before a body's ground is met, finds every floor triangle under it in
    // reach). Any blocking triangle may be met first: the slide ends only
    // when a whole scan finds none, so a stale hint costs one test, never
    // safety. Each hint is tested once, in order, until one blocks: one
    // that did not block, or was met, seldom blocks later in the slide
    // (each slide moves the end out of what it met).
    Hit hit;
    for (; hintsLeft != 0 && !hit.found(); hintsLeft &= hintsLeft - 1)
      offerTriangle(world, hints[std::countr_zero(hintsLeft)], move, swept, local, hit);
    if (!hit.found()) findBlockingTriangle(world, move, swept, local, blocks, planesMask, hit);
    if (!hit.found()) return result;
    if (iteration == settings.maxIterations) {
      // The six planes found no place for the end (a body held between
      // squared-off edges that push it back and forth): the exact sweep,
      // whose rounded contacts have no such traps, makes the move from the
      // same start instead (docs/algorithm.md, "Ghost edges"); it refuses
      // only what it cannot place either.
      // (Assigned to `result`, so every path returns it: one result,
      // never copied on return.)
      const int iterations = result.iterations;
      result = slideExact(world, start, desiredEnd, radii, settings, walkableNormalY, scratch);
      result.iterations += iterations;
      return result;
    }
    const Vec3& normal = hit.normal;
    const bool walkable = normal.y() >= walkableNormalY;
    const Constraint added{normal, hit.distance + hit.reach + settings.skin,
                           walkable ? Vec3::UnitY() : normal};
    result.end += added.push * (violation(added, result.end) / normal.dot(added.push));

    // The most recent earlier surfaces the end is back inside, if any.
    const Constraint* back[2] = {nullptr, nullptr};
    for (int i = constraintCount - 1; i >= 0 && !back[1]; --i) {
      if (violation(constraints[i], result.end) <= 1e-5f) continue;
      if (constraints[i].normal.dot(normal) > 0.9999f) continue;  // the same surface
      (back[0] ? back[1] : back[0]) = &constraints[i];
    }
    if (back[0]) {
      Vec3 meet = result.end;
      if (meetConstraints<2>({&added, back[0]}, maxShift, meet)) {
        result.end = meet;
        if (back[1] && violation(*back[1], meet) > 1e-5f &&
            meetConstraints<3>({&added, back[0], back[1]}, maxShift, meet))
          result.end = meet;
      }
    }
    if (constraintCount < kMaxReportedContacts) constraints[constraintCount++] = added;
    ++result.iterations;
    if (result.contactCount < kMaxReportedContacts)
      result.contacts[result.contactCount++] = {normal, walkable, false,
                                                touchingPoint(result.end, normal, hit.reach, radii),
                                                hit.triangle};
  }
}

}  // namespace bspf
