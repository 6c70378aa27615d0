// SPDX-License-Identifier: MIT
// The body phase's scans of things sorted along x: the sorted sweep's pair
// scan (BodyGrid::sweepPairsBySorting: boxes sorted by their low x, each
// tested against those after it that start before it ends along x), and
// the neighbour search's (BodyGrid::findNeighboursBySorting: centres sorted
// by x, each against those after it within reach), with the test of whether
// the bodies stayed near enough where that search last listed its pairs
// and the measure of the pairs it finds (how far apart, how much overlap);
// and the pass over a crowd that opens each build (its cell size, whether
// any body moved fast). Private to the runtime.
#pragma once

#include <bspf/movement.h>

#include <algorithm>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "workspace.h"  // BSPF_SSE_MASKS, and the SSE2 header where it is set

namespace bspf::detail {

/// Boxes after the last one in SortedBoxes's arrays: they start at x
/// +infinity and meet nothing, so the scan reads whole runs of this many.
inline constexpr std::uint32_t kBoxRun = 4;

/// Boxes sorted by low x, as arrays of `count + kBoxRun` entries: the last
/// kBoxRun low bounds +infinity, high bounds -infinity, not fast.
struct SortedBoxes {
  const float *lowX, *highX, *lowY, *highY, *lowZ, *highZ;
  const std::uint32_t* body;  ///< the box's body index
  const std::uint32_t* fast;  ///< all ones for a fast body's box, else 0
  std::uint32_t count;
};

/// Appends `a << 32 | b` (a < b, body indices) to `pairs` for each pair of
/// the boxes that meet (closed intervals along each axis) and hold a fast
/// body, in the order of their first box, then their second. With SSE2,
/// four boxes at a time (one branch each, where one per box mispredicted at
/// the end of most runs: 6% of a 40 m/s walker step's cycles on oa_dm5);
/// the same pairs as appendMeetingPairsOneByOne.
void appendMeetingPairs(const SortedBoxes& boxes, std::vector<std::uint64_t>& pairs);

/// The reference: the same scan one box at a time.
void appendMeetingPairsOneByOne(const SortedBoxes& boxes, std::vector<std::uint64_t>& pairs);

/// Centres after the last one of a sorted array of SortedCentre: at x
/// +infinity, beyond every reach, so the scan reads whole runs of this many.
inline constexpr std::uint32_t kCentreRun = 4;

/// Calls `pair(self, other)` (pointers into `centres`, self before other)
/// for each pair of centres less than `reach` apart along x and along z and
/// less than `reachY` along y (the differences' magnitudes), in the order of
/// self, then other. `centres`: `count` centres sorted by x, all finite,
/// then kCentreRun at x +infinity. The reference, one centre at a time.
template <typename Pair>
void forNearCentresOneByOne(const SortedCentre* centres, std::uint32_t count, float reach,
                            float reachY, Pair&& pair) {
  for (const SortedCentre* self = centres; self != centres + count; ++self)
    // Sorted by x: once one is out of reach along x, so is every later one
    // (the centres at +infinity end the last runs).
    for (const SortedCentre* other = self + 1; other->x - self->x < reach; ++other)
      if (std::abs(self->z - other->z) < reach && std::abs(self->y - other->y) < reachY)
        pair(self, other);
}

/// forNearCentresOneByOne's pairs, in its order. With SSE2, four centres at
/// a time: one at a time, the scan took a mispredicted branch for most of
/// its pairs and at the end of most runs (walkers, 64 agents: 1.3 to 2.3
/// ns a body-step of the 12 to 15 of BodyGrid::build on oa_dm4, fan and
/// oa_dm1). Inline, calling `pair` in place: collecting the pairs for a
/// second pass cost most of that again.
template <typename Pair>
void forNearCentres(const SortedCentre* centres, std::uint32_t count, float reach, float reachY,
                    Pair&& pair) {
#ifdef BSPF_SSE_MASKS
  static_assert(sizeof(SortedCentre) == 16 && kCentreRun == 4);
  const __m128 reachLanes = _mm_set1_ps(reach), reachYLanes = _mm_set1_ps(reachY);
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  for (const SortedCentre* self = centres; self != centres + count; ++self) {
    const __m128 x = _mm_set1_ps(self->x), y = _mm_set1_ps(self->y), z = _mm_set1_ps(self->z);
    for (const SortedCentre* group = self + 1;; group += 4) {
      // Four centres, transposed: their x, y, z (and index) in four lanes.
      __m128 xs = _mm_loadu_ps(&group[0].x), ys = _mm_loadu_ps(&group[1].x),
             zs = _mm_loadu_ps(&group[2].x), rest = _mm_loadu_ps(&group[3].x);
      _MM_TRANSPOSE4_PS(xs, ys, zs, rest);
      // The reference's differences, in its order, their sign bit cleared.
      const __m128 withinX = _mm_cmplt_ps(_mm_sub_ps(xs, x), reachLanes);
      const __m128 near = _mm_and_ps(
          withinX, _mm_and_ps(_mm_cmplt_ps(_mm_and_ps(_mm_sub_ps(z, zs), magnitude), reachLanes),
                              _mm_cmplt_ps(_mm_and_ps(_mm_sub_ps(y, ys), magnitude), reachYLanes)));
      for (unsigned bits = unsigned(_mm_movemask_ps(near)); bits != 0; bits &= bits - 1)
        pair(self, group + std::countr_zero(bits));
      // A run that leaves reach ends there: the later ones are further
      // along x.
      if (_mm_movemask_ps(withinX) != 15) break;
    }
  }
#else
  forNearCentresOneByOne(centres, count, reach, reachY, pair);
#endif
}

/// Whether every record of `now` lies within `slack` (>= 0) of the record of
/// `then` at its index (as long) along x and z of its `position` (a Vec3)
/// and in its `radii.xz` (a changed radius counts as a move), and within
/// `slackY` (>= 0) along y, with nothing there that is not finite, the y
/// radius (`radii.y`) included. `then` must hold finite values. The
/// reference, one record at a time.
template <typename Record>
bool movedWithinOneByOne(std::span<const Record> now, std::span<const Record> then, float slack,
                         float slackY) {
  float farthest = 0, farthestY = 0, notFinite = 0;
  for (std::size_t i = 0; i < now.size(); ++i) {
    const Record &e = now[i], &l = then[i];
    const float dx = e.position.x() - l.position.x(), dy = e.position.y() - l.position.y(),
                dz = e.position.z() - l.position.z(), dr = e.radii.xz - l.radii.xz;
    // x - x is NaN for an infinity too, and a NaN stays in the sum.
    notFinite += (dx - dx) + (dy - dy) + (dz - dz) + (dr - dr) + (e.radii.y - e.radii.y);
    farthest = std::max(std::max(farthest, std::abs(dr)), std::max(std::abs(dx), std::abs(dz)));
    farthestY = std::max(farthestY, std::abs(dy));
  }
  return !std::isnan(notFinite) && farthest <= slack && farthestY <= slackY;
}

/// movedWithinOneByOne's answer. With SSE2, a record's centre and xz radius
/// in one 4-lane difference (its first 16 bytes: `position` then
/// `radii.xz`), each lane's largest against its own slack: the pass over a
/// crowd's every body that a build with a listed neighbour search pays
/// (BodyGrid::findNeighboursBySorting). Two records a round, each into its
/// own largest, and the y radius tested apart: one running largest and a
/// running sum of the y radii made each record wait for the last one's
/// maximum and addition (4 cycles each), 11% of the search's time (perf,
/// walkers, 64 agents, oa_dm4).
template <typename Record>
bool movedWithin(std::span<const Record> now, std::span<const Record> then, float slack,
                 float slackY) {
#ifdef BSPF_SSE_MASKS
  static_assert(offsetof(Record, position) == 0 && offsetof(Record, radii) == 12 &&
                sizeof(Record) >= 16);
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  __m128 farthest0 = _mm_setzero_ps(), farthest1 = _mm_setzero_ps(), nan = _mm_setzero_ps();
  // A lane's difference, its magnitude into `farthest` (an infinite one
  // fails the bound), and a NaN one flagged; an infinite or NaN y radius
  // makes a NaN in its own difference.
  auto add = [&](const Record& record, const Record& last, __m128& farthest) {
    const __m128 d =
        _mm_sub_ps(_mm_loadu_ps(&record.position.x()), _mm_loadu_ps(&last.position.x()));
    const __m128 radiusY = _mm_load_ss(&record.radii.y);
    farthest = _mm_max_ps(farthest, _mm_and_ps(d, magnitude));
    nan = _mm_or_ps(nan, _mm_or_ps(_mm_cmpunord_ps(d, d),
                                   _mm_cmpunord_ss(_mm_sub_ss(radiusY, radiusY), radiusY)));
  };
  std::size_t i = 0;
  for (; i + 2 <= now.size(); i += 2) {
    add(now[i], then[i], farthest0);
    add(now[i + 1], then[i + 1], farthest1);
  }
  if (i < now.size()) add(now[i], then[i], farthest0);
  const __m128 within =
      _mm_cmple_ps(_mm_max_ps(farthest0, farthest1), _mm_setr_ps(slack, slackY, slack, slack));
  return _mm_movemask_ps(nan) == 0 && _mm_movemask_ps(within) == 15;
#else
  return movedWithinOneByOne(now, then, slack, slackY);
#endif
}

// The distance between two bodies' centres `apart` (one's minus the
// other's) apart, as a push measures it, and whether it gives a direction.
inline float centreDistance(float ax, float ay, float az) {
  return std::sqrt(ax * ax + (ay * ay + az * az));  // as Eigen does
}
inline bool apartKnown(float distance) { return distance > 1e-6f; }

// How far two bodies with `selfRadii` and `otherRadii` overlap along the
// line between their centres, `apart` (ax, ay, az) and `distance` apart
// (centreDistance). The same value for the pair either way round: the
// direction's components change sign only, effectiveRadius squares them,
// and the two extents' sum commutes.
inline float pairOverlap(float ax, float ay, float az, float distance, EllipsoidRadii selfRadii,
                         EllipsoidRadii otherRadii) {
  // At one point they part horizontally (tieBreakDirection).
  if (!apartKnown(distance)) return selfRadii.xz + otherRadii.xz;
  const Vec3 direction(ax / distance, ay / distance, az / distance);
  return effectiveRadius(direction, selfRadii) + effectiveRadius(direction, otherRadii) - distance;
}

/// Of the first `count` of `pairs` (each one's `pair` is a << 32 | b,
/// indices into `records`), keeps those whose bodies overlap (pairOverlap
/// > 0), in their order, at the front of `pairs`, each with the `distance`
/// (centreDistance) and `overlap` (pairOverlap) of its centres, the first's
/// minus the second's; returns how many it kept. The reference, one pair
/// at a time.
template <typename Record, typename Pair>
std::size_t keepOverlappingOneByOne(const Record* records, Pair* pairs, std::size_t count) {
  std::size_t kept = 0;
  for (std::size_t k = 0; k < count; ++k) {
    const std::uint64_t pair = pairs[k].pair;
    const Record &p = records[pair >> 32], &q = records[std::uint32_t(pair)];
    const float ax = p.position.x() - q.position.x(), ay = p.position.y() - q.position.y(),
                az = p.position.z() - q.position.z();
    const float distance = centreDistance(ax, ay, az);
    const float overlap = pairOverlap(ax, ay, az, distance, p.radii, q.radii);
    pairs[kept] = {pair, distance, overlap};
    kept += overlap > 0;
  }
  return kept;
}

/// keepOverlappingOneByOne's answer, the same floats. With SSE2, four pairs
/// at a time: each pair's three square roots and three divisions are
/// four-lane ones, in the reference's order of operations (SSE rounds each
/// as the scalar one does). One pair at a time they were most of the
/// listed neighbour search's time (walkers, 64 agents, oa_dm4: 11 pairs a
/// build whose boxes overlap, 66 roots and divisions).
template <typename Record, typename Pair>
std::size_t keepOverlapping(const Record* records, Pair* pairs, std::size_t count) {
#ifdef BSPF_SSE_MASKS
  static_assert(offsetof(Record, position) == 0 && offsetof(Record, radii) == 12 &&
                sizeof(Record) >= 20);
  std::size_t kept = 0;
  for (std::size_t k = 0; k < count; k += 4) {
    // The group's pairs (past the end, the first again), read before any
    // is overwritten: the kept ones go to places at or before their own.
    const std::size_t lanes = std::min<std::size_t>(4, count - k);
    std::uint64_t group[4];
    for (std::size_t j = 0; j < 4; ++j) group[j] = pairs[k + (j < lanes ? j : 0)].pair;
    auto record = [&](std::size_t j, bool second) -> const Record& {
      return records[second ? std::uint32_t(group[j]) : std::uint32_t(group[j] >> 32)];
    };
    // Each side's x, y, z and xz radius, transposed, and its y radius.
    auto side = [&](bool second, __m128& x, __m128& y, __m128& z, __m128& xz, __m128& radiusY) {
      x = _mm_loadu_ps(&record(0, second).position.x());
      y = _mm_loadu_ps(&record(1, second).position.x());
      z = _mm_loadu_ps(&record(2, second).position.x());
      xz = _mm_loadu_ps(&record(3, second).position.x());
      _MM_TRANSPOSE4_PS(x, y, z, xz);
      radiusY = _mm_setr_ps(record(0, second).radii.y, record(1, second).radii.y,
                            record(2, second).radii.y, record(3, second).radii.y);
    };
    __m128 px, py, pz, pXZ, pY, qx, qy, qz, qXZ, qY;
    side(false, px, py, pz, pXZ, pY);
    side(true, qx, qy, qz, qXZ, qY);
    const __m128 ax = _mm_sub_ps(px, qx), ay = _mm_sub_ps(py, qy), az = _mm_sub_ps(pz, qz);
    const __m128 distance = _mm_sqrt_ps(
        _mm_add_ps(_mm_mul_ps(ax, ax), _mm_add_ps(_mm_mul_ps(ay, ay), _mm_mul_ps(az, az))));
    const __m128 dx = _mm_div_ps(ax, distance), dy = _mm_div_ps(ay, distance),
                 dz = _mm_div_ps(az, distance);
    auto effective = [&](__m128 radiusXZ, __m128 radiusY) {
      const __m128 x = _mm_mul_ps(radiusXZ, dx), y = _mm_mul_ps(radiusY, dy),
                   z = _mm_mul_ps(radiusXZ, dz);
      return _mm_sqrt_ps(
          _mm_add_ps(_mm_add_ps(_mm_mul_ps(x, x), _mm_mul_ps(y, y)), _mm_mul_ps(z, z)));
    };
    const __m128 apart = _mm_sub_ps(_mm_add_ps(effective(pXZ, pY), effective(qXZ, qY)), distance);
    // Centres not apart (apartKnown false, NaN too): the xz radii's sum.
    const __m128 known = _mm_cmpgt_ps(distance, _mm_set1_ps(1e-6f));
    const __m128 overlap =
        _mm_or_ps(_mm_and_ps(known, apart), _mm_andnot_ps(known, _mm_add_ps(pXZ, qXZ)));
    alignas(16) float distances[4], overlaps[4];
    _mm_store_ps(distances, distance);
    _mm_store_ps(overlaps, overlap);
    for (std::size_t j = 0; j < lanes; ++j) {
      pairs[kept] = {group[j], distances[j], overlaps[j]};
      kept += overlaps[j] > 0;
    }
  }
  return kept;
#else
  return keepOverlappingOneByOne(records, pairs, count);
#endif
}

/// Bit i set where `heads[i]` is not `none`: which of at most 64 bodies
/// have a link (BodyGrid::nearHead_). The reference, one at a time.
inline std::uint64_t linkedBitsOneByOne(std::span<const std::uint32_t> heads, std::uint32_t none) {
  assert(heads.size() <= 64);
  std::uint64_t bits = 0;
  for (std::size_t i = 0; i < heads.size(); ++i) bits |= std::uint64_t(heads[i] != none) << i;
  return bits;
}

/// linkedBitsOneByOne's answer; with SSE2, four heads a comparison.
inline std::uint64_t linkedBits(std::span<const std::uint32_t> heads, std::uint32_t none) {
#ifdef BSPF_SSE_MASKS
  assert(heads.size() <= 64);
  const __m128i noneLanes = _mm_set1_epi32(int(none));
  std::uint64_t unlinked = 0;
  std::size_t i = 0;
  for (; i + 4 <= heads.size(); i += 4) {
    const __m128i h = _mm_loadu_si128(reinterpret_cast<const __m128i*>(heads.data() + i));
    unlinked |= std::uint64_t(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(h, noneLanes))))
                << i;
  }
  for (; i < heads.size(); ++i) unlinked |= std::uint64_t(heads[i] == none) << i;
  const std::uint64_t all =
      heads.size() == 64 ? ~std::uint64_t(0) : (std::uint64_t(1) << heads.size()) - 1;
  return ~unlinked & all;
#else
  return linkedBitsOneByOne(heads, none);
#endif
}

/// Whether sweptFast(b) is surely false because body `b`'s move (from
/// lastStepStart to position) is at most kSweepMinMove times its smaller
/// radius, less 1% for rounding (a carried push only makes a move less
/// fast): the cheap test asked of every body every frame, before the full
/// one (the body phase's movedFast), for nearly every body of nearly every
/// frame. False for a NaN move or radius (the full test then decides).
inline bool movedSurelySlow(const Body& b) {
  constexpr float kSlowSquared = 0.99f * kSweepMinMove * kSweepMinMove;
  const Vec3 move = b.position - b.lastStepStart;
  const float radius = std::min(b.radii.xz, b.radii.y);
  return move.squaredNorm() <= kSlowSquared * (radius * radius);
}

/// What a build first asks of a crowd: the cell's width and height (4
/// times the largest xz radius and y radius, metres; a NaN radius passed
/// over, as std::max passes it; 0 for no bodies) and whether any body's
/// move is swept (!movedSurelySlow(b) && movedFast(b)).
struct CrowdScan {
  float width = 0, height = 0;
  bool anyFast = false;
};

/// Adds body `b` to `scan`: its radii to the cell size and, unless a body
/// before it was fast, whether it is (movedFast asked only where the move
/// is not surely slow).
template <typename MovedFast>
void scanBody(CrowdScan& scan, const Body& b, MovedFast& movedFast) {
  scan.width = std::max(scan.width, 4 * b.radii.xz);
  scan.height = std::max(scan.height, 4 * b.radii.y);
  scan.anyFast = scan.anyFast || (!movedSurelySlow(b) && movedFast(b));
}

/// The reference: one body at a time (scanBody).
template <typename MovedFast>
CrowdScan scanCrowdOneByOne(std::span<const Body> bodies, MovedFast&& movedFast) {
  CrowdScan scan;
  for (const Body& b : bodies) scanBody(scan, b, movedFast);
  return scan;
}

/// scanCrowdOneByOne's answer (the same floats, and movedFast asked of the
/// same bodies). With SSE2, four bodies at a time: their radii in two
/// loads, each move in one four-lane difference (position and lastStepStart
/// with the lane after each: velocity.x, and the start's lane cleared), its
/// square summed as Eigen's squaredNorm sums it ((x + y) + z, so the same
/// float as movedSurelySlow's; were a build to round otherwise, say with
/// FMA, a body that one calls surely slow and the other not lies within 1%
/// of the bound, where movedFast is false: anyFast is the same either way).
/// One body at a time it was 23 instructions a body-step, a tenth of the
/// body phase's (walkers, 64 agents, fan).
template <typename MovedFast>
CrowdScan scanCrowd(std::span<const Body> bodies, MovedFast&& movedFast) {
#ifdef BSPF_SSE_MASKS
  static_assert(offsetof(Body, position) + 16 <= sizeof(Body) &&
                offsetof(Body, lastStepStart) + 16 <= sizeof(Body) &&
                offsetof(EllipsoidRadii, y) == offsetof(EllipsoidRadii, xz) + 4);
  const __m128 four = _mm_set1_ps(4), xyzLanes = _mm_castsi128_ps(_mm_setr_epi32(-1, -1, -1, 0));
  const __m128 slowSquared = _mm_set1_ps(0.99f * kSweepMinMove * kSweepMinMove);
  __m128 widest = _mm_setzero_ps(), tallest = _mm_setzero_ps();
  bool anyFast = false;
  std::size_t i = 0;
  for (; i + 4 <= bodies.size(); i += 4) {
    const Body* b = bodies.data() + i;
    auto radii = [&](int k) { return reinterpret_cast<const __m64*>(&b[k].radii.xz); };
    const __m128 radii01 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), radii(0)), radii(1)),
                 radii23 = _mm_loadh_pi(_mm_loadl_pi(_mm_setzero_ps(), radii(2)), radii(3));
    const __m128 xz = _mm_shuffle_ps(radii01, radii23, _MM_SHUFFLE(2, 0, 2, 0)),
                 y = _mm_shuffle_ps(radii01, radii23, _MM_SHUFFLE(3, 1, 3, 1));
    // std::max(widest, r) is r only where widest < r: r > widest here.
    widest = _mm_max_ps(_mm_mul_ps(four, xz), widest);
    tallest = _mm_max_ps(_mm_mul_ps(four, y), tallest);
    if (anyFast) continue;
    // The start's fourth lane (a ground triangle's index) cleared: read as
    // a float it is subnormal, which some CPUs compute slowly.
    auto square = [&](int k) {
      const __m128 move = _mm_sub_ps(_mm_loadu_ps(&b[k].position.x()),
                                     _mm_and_ps(xyzLanes, _mm_loadu_ps(&b[k].lastStepStart.x())));
      return _mm_mul_ps(move, move);
    };
    __m128 s0 = square(0), s1 = square(1), s2 = square(2), s3 = square(3);
    _MM_TRANSPOSE4_PS(s0, s1, s2, s3);
    const __m128 squaredNorm = _mm_add_ps(_mm_add_ps(s0, s1), s2);
    // std::min(xz, y) is y only where y < xz, as _mm_min_ps(y, xz).
    const __m128 radius = _mm_min_ps(y, xz);
    const unsigned slow = unsigned(_mm_movemask_ps(
        _mm_cmple_ps(squaredNorm, _mm_mul_ps(slowSquared, _mm_mul_ps(radius, radius)))));
    for (unsigned notSlow = ~slow & 15; notSlow != 0 && !anyFast; notSlow &= notSlow - 1)
      anyFast = movedFast(b[std::countr_zero(notSlow)]);
  }
  alignas(16) float wide[4], tall[4];
  _mm_store_ps(wide, widest);
  _mm_store_ps(tall, tallest);
  CrowdScan scan;
  for (int lane = 0; lane < 4; ++lane) {
    scan.width = std::max(scan.width, wide[lane]);
    scan.height = std::max(scan.height, tall[lane]);
  }
  scan.anyFast = anyFast;
  for (; i < bodies.size(); ++i) scanBody(scan, bodies[i], movedFast);
  return scan;
#else
  return scanCrowdOneByOne(bodies, movedFast);
#endif
}

}  // namespace bspf::detail
