// SPDX-License-Identifier: MIT
// The body-against-body phase of stepBodies: a sweep of the fast bodies'
// moves against the bodies near their paths (each stopped where it first
// meets another), a hashed grid of the bodies' positions after the level
// phase and the sweep (for a small crowd, the pairs its cells would give,
// found by sorting along x), then, for each body independently, the sum of the
// pushes from its nearest overlapping bodies (no longer than the largest of
// them), applied as one move against the level: a slide only when the move
// comes near a triangle.
#include <bspf/movement.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "box_pairs.h"
#include "slide.h"

namespace bspf {

namespace {

// The horizontal direction along which bodies `self` and `other` part when
// their centres give none (the same point, or one right above the other):
// fixed by the pair, opposite for the two, and spread around the circle over
// pairs so that a pile at one point spreads out in every direction. One of
// 256 directions, from a table: a pile's first frame needs millions.
Vec3 tieBreakDirection(std::uint32_t self, std::uint32_t other) {
  static const std::array<Vec3, 256> directions = [] {
    std::array<Vec3, 256> table;
    for (int k = 0; k < 256; ++k) {
      const float angle = float(k) * 2 * std::numbers::pi_v<float> / 256;
      table[k] = Vec3(std::cos(angle), 0, std::sin(angle));
    }
    return table;
  }();
  const std::uint32_t low = std::min(self, other), high = std::max(self, other);
  std::uint64_t z = (std::uint64_t(low) << 32 | high) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return (self == low ? 1.0f : -1.0f) * directions[(z ^ (z >> 31)) >> 56];
}

struct Pusher {
  std::uint32_t body;
  bool apartKnown;  ///< the centres are apart, so `apart` gives a direction
  Vec3 apart;       ///< from the pusher's centre to this body's
  float overlap;
};

using detail::apartKnown;
using detail::centreDistance;
using detail::pairOverlap;

// Keeps the kMaxBodyPushes nearest pushers, nearest first (ties: lower
// index). A pile offers up to kMaxBodyCandidates of them per body, so the
// order lives in 64-bit keys (the distance's bits above the body index: a
// non-negative float's bits order as the float does) and only keys and
// one-byte slots move, not the pushers.
class NearestPushers {
 public:
  /// Whether a pusher at `distance` (>= 0) from this body, with index
  /// `body`, is among the nearest so far; if so, offer() must follow.
  bool wants(float distance, std::uint32_t body) {
    key_ = std::uint64_t(std::bit_cast<std::uint32_t>(distance)) << 32 | body;
    return count_ < kMaxBodyPushes || key_ < keys_[count_ - 1];
  }
  /// Keeps `p` (the pusher wants() was last asked about), dropping the
  /// farthest when full.
  void offer(const Pusher& p) {
    // Not full: the next slot is free. Full: the farthest's slot is.
    int at;
    std::uint8_t slot;
    if (count_ < kMaxBodyPushes) {
      at = count_++;
      slot = std::uint8_t(at);
    } else {
      at = count_ - 1;
      slot = slots_[at];
    }
    pushers_[slot] = p;
    for (; at > 0 && key_ < keys_[at - 1]; --at) {
      keys_[at] = keys_[at - 1];
      slots_[at] = slots_[at - 1];
    }
    keys_[at] = key_;
    slots_[at] = slot;
  }
  int size() const { return count_; }
  /// The k-th nearest, 0 <= k < size().
  const Pusher& operator[](int k) const { return pushers_[slots_[k]]; }

 private:
  std::array<Pusher, kMaxBodyPushes> pushers_;
  std::array<std::uint64_t, kMaxBodyPushes> keys_;
  std::array<std::uint8_t, kMaxBodyPushes> slots_;
  std::uint64_t key_ = 0;  ///< of the pusher last asked about
  int count_ = 0;
};

// Cell coordinates are kept within +-kCellLimit, stored offset by 2^20 in 21
// bits each of a key (about 1,900 km of 0.9 m cells along each axis): a
// neighbour's coordinate, one more or less, then still fits, so the
// neighbours' keys are the key plus or minus a constant.
constexpr float kCellLimit = float((1 << 20) - 2);
constexpr std::uint64_t kCellOffset = 1 << 20;
constexpr std::uint64_t kFieldMask = (std::uint64_t(1) << 21) - 1;

// A cell's key from its offset coordinates, and back.
constexpr std::uint64_t packCell(std::uint64_t x, std::uint64_t y, std::uint64_t z) {
  return x << 42 | y << 21 | z;
}
constexpr std::array<std::uint64_t, 3> unpackCell(std::uint64_t key) {
  return {key >> 42, key >> 21 & kFieldMask, key & kFieldMask};
}

// The high 64 - `shift` bits of a cell key's Fibonacci hash: the
// golden-ratio multiplier carries the low bits that neighbouring cells
// differ in into the high bits kept.
constexpr std::uint32_t cellHash(std::uint64_t key, int shift) {
  return std::uint32_t((key * 0x9e3779b97f4a7c15ull) >> shift);
}

// The key offsets from a cell to the 7 others that may hold a body
// overlapping one in it, by the body's upper-half bits (Place::upperHalf):
// one step along x, y, z, up or down as the body lies in its cell, and
// their combinations (two's complement: a step down adds 2^64 - step).
constexpr std::array<std::array<std::uint64_t, 7>, 8> kNeighbourOffsets = [] {
  std::array<std::array<std::uint64_t, 7>, 8> table{};
  for (int upper = 0; upper < 8; ++upper) {
    std::array<std::uint64_t, 3> step{};
    for (int axis = 0; axis < 3; ++axis) {
      const std::uint64_t one = std::uint64_t(1) << (42 - 21 * axis);
      step[axis] = upper >> axis & 1 ? one : 0 - one;
    }
    for (int corner = 1; corner < 8; ++corner)
      table[upper][corner - 1] =
          (corner & 1 ? step[0] : 0) + (corner & 2 ? step[1] : 0) + (corner & 4 ? step[2] : 0);
  }
  return table;
}();

// The cell coordinate of `scaled` (a coordinate over the cell size), offset
// by kCellOffset, and whether it lies in the upper half of the cell. Far
// beyond any level (or not a number), bodies share the edge cells: still
// correct, as every pair found is tested for overlap. (std::floor is a
// library call here; offset into positive doubles, exactly, truncation is
// the floor.)
float clampToCells(float scaled) {
  const float s = scaled > -kCellLimit ? scaled : -kCellLimit;  // also NaN
  return s < kCellLimit ? s : kCellLimit;
}
std::uint64_t cellCoordinate(float scaled, bool& upperHalf) {
  const float s = clampToCells(scaled);
  const double offset = double(s) + double(kCellOffset);
  const std::int64_t cell = std::int64_t(offset);
  upperHalf = offset - double(cell) >= 0.5;
  return std::uint64_t(cell);
}

}  // namespace

namespace {

// The cells, along one axis, of the coordinates low to high (metres) in
// cells of 1 / `inverse` metres.
std::array<std::uint64_t, 2> cellRange(float low, float high, float inverse) {
  bool upper;
  return {cellCoordinate(low * inverse, upper), cellCoordinate(high * inverse, upper)};
}

// Where two spheres' centres first come within `reach` of each other, the
// centres `d` apart (one's minus the other's) at the start of a stretch and
// moving apart by `v` per unit of time over `length` of it: the offset into
// the stretch, or a negative number if they never do. Two already within
// reach meet at once only when the move would take one through the middle
// of the other (past half their distance): bodies that touch may still walk
// past each other, or apart. In double: a fast body's move is hundreds of
// times its size.
double firstMeeting(const Eigen::Vector3d& d, const Eigen::Vector3d& v, double reach,
                    double length) {
  const double dd = d.squaredNorm(), dv = d.dot(v), vv = v.squaredNorm();
  if (!(vv > 0) || dv >= 0) return -1;  // not closing
  const double gap = dd - reach * reach;
  if (gap <= 0) {
    const double s = std::min(-dv / vv, length);
    return (d + s * v).squaredNorm() < 0.25 * dd ? 0 : -1;
  }
  const double disc = dv * dv - vv * gap;
  if (disc < 0) return -1;
  // The smaller root, written without the cancellation of -dv - sqrt(disc).
  const double s = gap / (-dv + std::sqrt(disc));
  return s <= length ? s : -1;
}

bool boxesMeet(const Vec3& lowA, const Vec3& highA, const Vec3& lowB, const Vec3& highB) {
  return (lowA.array() <= highB.array()).all() && (lowB.array() <= highA.array()).all();
}

// Whether a body's move, over its radii, is longer than kSweepMinMove plus
// the push it carried (Body::lastStepPush, over its radii, in the same
// space): (x / a)^2 + (y / b)^2 + (z / a)^2 > (k + p)^2, multiplied out (no
// division or root but for a carried push: this runs for every body every
// frame, and most frames have no fast body). Not the move less the push: a
// push is carried when it presses the body into a wall, and the wall takes
// most of it back.
bool movedFast(const Body& b) {
  const Vec3 move = b.position - b.lastStepStart;
  const float a2 = b.radii.xz * b.radii.xz, b2 = b.radii.y * b.radii.y;
  float least = kSweepMinMove;
  if (b.lastStepPush != Vec3::Zero()) {
    const Vec3& p = b.lastStepPush;
    least += std::sqrt((p.x() * p.x() + p.z() * p.z()) / a2 + p.y() * p.y() / b2);
  }
  return (move.x() * move.x() + move.z() * move.z()) * b2 + move.y() * move.y() * a2 >
         least * least * a2 * b2;
}

// Whether the sweep takes body `b`'s move (movedFast), the cheap test first:
// what BodyGrid::build and the prepared inputs both ask of every body. Forced
// inline: GCC kept it out of line in the build's first pass, 10 instructions
// a body-step more (walkers, oa_dm4).
[[gnu::always_inline]] inline bool sweptFast(const Body& b) {
  return !detail::movedSurelySlow(b) && movedFast(b);
}

}  // namespace

double BodyGrid::meetTime(std::uint32_t a, std::uint32_t b, Vec3& normal) const {
  const Mover& p = movers_[a];
  const Mover& q = movers_[b];
  // The pair's space: each axis over the summed radii, where two bodies of
  // one shape touch when their centres are 1 apart. A body of another shape
  // is taken as the sphere of its largest radius there, so the pair never
  // meets later than it truly would.
  const double sumXZ = double(p.radii.xz) + q.radii.xz, sumY = double(p.radii.y) + q.radii.y;
  const Eigen::Vector3d scale(1 / sumXZ, 1 / sumY, 1 / sumXZ);
  const double reach = std::max(p.radii.xz / sumXZ, p.radii.y / sumY) +
                       std::max(q.radii.xz / sumXZ, q.radii.y / sumY) +
                       0.5 * (double(p.skin) + q.skin) / std::min(sumXZ, sumY);
  const double ta = stops_[a].time, tb = stops_[b].time;
  const Eigen::Vector3d moveA = p.move.cast<double>().cwiseProduct(scale),
                        moveB = q.move.cast<double>().cwiseProduct(scale);
  // Both move until the earlier stop time, then only the later one.
  const double first = std::min(ta, tb), second = std::max(ta, tb);
  Eigen::Vector3d d = (p.start - q.start).cast<double>().cwiseProduct(scale);
  const Eigen::Vector3d together = moveA - moveB, alone = ta > tb ? moveA : Eigen::Vector3d(-moveB);
  double begin = 0, at = -1;
  Eigen::Vector3d v = together;
  if (first > 0) at = firstMeeting(d, together, reach, first);
  if (at < 0 && second > first) {
    d += first * together;
    begin = first;
    v = alone;
    at = firstMeeting(d, alone, reach, second - first);
  }
  if (at < 0) return 2;
  // The contact normal: the gradient of the pair's sphere, back in metres.
  Eigen::Vector3d n = (d + at * v).cwiseProduct(scale);
  if (!(n.squaredNorm() > 1e-24)) n = -v.cwiseProduct(scale);
  if (!(n.squaredNorm() > 1e-24)) n = Eigen::Vector3d::UnitX();
  normal = n.normalized().cast<float>();
  return begin + at;
}

namespace {

// The hashed bits of the cells fast bodies cross, in sweepPairsByCells:
// 4,096 (512 bytes, cleared each sweep), of which the usual handful of fast
// bodies set a few.
constexpr int kFastCellBitsLog2 = 12;
constexpr std::size_t kFastCellWords = (std::size_t(1) << kFastCellBitsLog2) / 64;

}  // namespace

void BodyGrid::sweepPairsByCells() {
  const std::uint32_t n = std::uint32_t(movers_.size());
  // Each fast body's path, in pieces of at most a cell along each axis, is
  // filed under every cell a piece's box covers (at most 3 a piece along
  // each axis: the piece and a body's reach of half a cell on each side).
  sweepCells_.clear();
  oversize_.clear();
  Vec3 fastLow = Vec3::Constant(std::numeric_limits<float>::infinity()), fastHigh = -fastLow;
  const Vec3 inverse(inverseWidth_, inverseHeight_, inverseWidth_);
  for (std::uint32_t i = 0; i < n; ++i) {
    const Mover& m = movers_[i];
    if (!m.fast) continue;
    fastLow = fastLow.cwiseMin(m.low);
    fastHigh = fastHigh.cwiseMax(m.high);
    const float pieces =
        std::max(1.0f, std::ceil(m.move.cwiseAbs().cwiseProduct(inverse).maxCoeff()));
    if (!(pieces <= float(kMaxSweepPieces))) {
      oversize_.push_back(i);
      continue;
    }
    const Vec3 reach = 0.5f * (m.high - m.low - m.move.cwiseAbs());
    for (int k = 0; k < int(pieces); ++k) {
      const Vec3 from = m.start + (float(k) / pieces) * m.move,
                 to = k + 1 == int(pieces) ? Vec3(m.start + m.move)
                                           : Vec3(m.start + (float(k + 1) / pieces) * m.move);
      const Vec3 low = from.cwiseMin(to) - reach, high = from.cwiseMax(to) + reach;
      std::array<std::array<std::uint64_t, 2>, 3> range;
      for (int axis = 0; axis < 3; ++axis)
        range[axis] = cellRange(low[axis], high[axis], inverse[axis]);
      for (std::uint64_t x = range[0][0]; x <= range[0][1]; ++x)
        for (std::uint64_t y = range[1][0]; y <= range[1][1]; ++y)
          for (std::uint64_t z = range[2][0]; z <= range[2][1]; ++z)
            sweepCells_.emplace_back(packCell(x, y, z), i);
    }
  }
  std::sort(sweepCells_.begin(), sweepCells_.end());
  sweepCells_.erase(std::unique(sweepCells_.begin(), sweepCells_.end()), sweepCells_.end());

  // The pairs whose paths' boxes meet: fast bodies sharing a cell, a slow
  // body and the fast ones in the cells its box covers, an oversize move
  // and every body.
  auto consider = [&](std::uint32_t x, std::uint32_t y) {
    const std::uint32_t a = std::min(x, y), b = std::max(x, y);
    if (a != b && boxesMeet(movers_[a].low, movers_[a].high, movers_[b].low, movers_[b].high))
      sweepPairs_.push_back(std::uint64_t(a) << 32 | b);
  };
  // Which cells hold a fast body, by a hash of their keys: most cells a
  // slow body's box covers hold none, and the bit spares their binary
  // search (a bit set for another cell only costs the search).
  std::array<std::uint64_t, kFastCellWords> fastCells{};
  for (const auto& [key, body] : sweepCells_) {
    const std::uint32_t bit = cellHash(key, 64 - kFastCellBitsLog2);
    fastCells[bit >> 6] |= std::uint64_t(1) << (bit & 63);
  }
  for (std::size_t g = 0; g < sweepCells_.size();) {
    std::size_t end = g;
    while (end < sweepCells_.size() && sweepCells_[end].first == sweepCells_[g].first) ++end;
    for (std::size_t e = g; e < end; ++e)
      for (std::size_t f = e + 1; f < end && f <= e + kMaxSweepCellBodies; ++f)
        consider(sweepCells_[e].second, sweepCells_[f].second);
    g = end;
  }
  for (std::uint32_t i = 0; i < n; ++i) {
    const Mover& m = movers_[i];
    if (m.fast || !boxesMeet(m.low, m.high, fastLow, fastHigh)) continue;
    std::array<std::array<std::uint64_t, 2>, 3> range;
    for (int axis = 0; axis < 3; ++axis)
      range[axis] = cellRange(m.low[axis], m.high[axis], inverse[axis]);
    for (std::uint64_t x = range[0][0]; x <= range[0][1]; ++x)
      for (std::uint64_t y = range[1][0]; y <= range[1][1]; ++y)
        for (std::uint64_t z = range[2][0]; z <= range[2][1]; ++z) {
          const std::uint64_t key = packCell(x, y, z);
          const std::uint32_t bit = cellHash(key, 64 - kFastCellBitsLog2);
          if (!(fastCells[bit >> 6] >> (bit & 63) & 1)) continue;
          auto it = std::lower_bound(sweepCells_.begin(), sweepCells_.end(),
                                     std::pair<std::uint64_t, std::uint32_t>(key, 0));
          for (int k = 0; it != sweepCells_.end() && it->first == key && k < kMaxSweepCellBodies;
               ++it, ++k)
            consider(it->second, i);
        }
  }
  for (const std::uint32_t x : oversize_)
    for (std::uint32_t y = 0; y < n; ++y) consider(x, y);
}

void BodyGrid::sweepPairsOfFewFast() {
  // Each fast body's box against every other body's: the sorting's pairs
  // (each pair whose boxes meet, closed along each axis, and that holds a
  // fast body), for a few boxes' tests a body where the sorting copied and
  // ordered every body's box (walkers at 6 m/s: a frame in 15 has one or
  // two fast bodies, falling, and the sorted sweep cost them 15
  // instructions a body-step on oa_dm4).
  const std::uint32_t n = std::uint32_t(movers_.size());
  for (std::uint32_t i = 0; i < n; ++i) {
    const Mover& m = movers_[i];
    if (!m.fast) continue;
    for (std::uint32_t j = 0; j < n; ++j) {
      const Mover& other = movers_[j];
      // A pair of fast bodies once, from its lower index.
      if (j == i || (other.fast && j < i)) continue;
      if (boxesMeet(m.low, m.high, other.low, other.high))
        sweepPairs_.push_back(std::uint64_t(std::min(i, j)) << 32 | std::max(i, j));
    }
  }
}

void BodyGrid::sweepPairsBySorting() {
  // The boxes in order of their low x (a float's bits, sign-flipped, order
  // as the float does), each against those after it that start before it
  // ends along x: every pair whose boxes meet, with no cell filing or
  // search (walkers at 40 m/s, 64 bodies: 495 instructions per body-step in
  // the sweep through the cells, callgrind).
  const std::uint32_t n = std::uint32_t(movers_.size());
  if (sweepOrder_.size() != n) {
    sweepOrder_.resize(n);
    for (std::uint32_t i = 0; i < n; ++i) sweepOrder_[i] = i;
  }
  for (std::uint64_t& key : sweepOrder_) {
    const std::uint32_t i = std::uint32_t(key);
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(movers_[i].low.x());
    const std::uint32_t ordered = bits >> 31 ? ~bits : bits | 0x80000000u;
    key = std::uint64_t(ordered) << 32 | i;
  }
  // Insertion sort from the last sweep's order: in a run of frames with
  // fast bodies, nearly this one (std::sort took 12 instructions a body at
  // 40 m/s). The keys are distinct, so any sort gives the same order.
  for (std::uint32_t k = 1; k < n; ++k) {
    const std::uint64_t key = sweepOrder_[k];
    std::uint32_t at = k;
    for (; at > 0 && sweepOrder_[at - 1] > key; --at) sweepOrder_[at] = sweepOrder_[at - 1];
    sweepOrder_[at] = key;
  }
  // The boxes copied out in that order, as arrays (the scan reads four
  // boxes at a time from each), then kBoxRun that meet nothing.
  const std::uint32_t stride = n + detail::kBoxRun;
  sweepBounds_.resize(6 * std::size_t(stride));
  sweepBodies_.resize(2 * std::size_t(stride));
  float* const lowX = sweepBounds_.data();
  float *const highX = lowX + stride, *const lowY = highX + stride, *const highY = lowY + stride,
               *const lowZ = highY + stride, *const highZ = lowZ + stride;
  std::uint32_t *const body = sweepBodies_.data(), *const fast = body + stride;
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::uint32_t i = std::uint32_t(sweepOrder_[k]);
    const Mover& m = movers_[i];
    lowX[k] = m.low.x(), highX[k] = m.high.x(), lowY[k] = m.low.y(), highY[k] = m.high.y();
    lowZ[k] = m.low.z(), highZ[k] = m.high.z(), body[k] = i, fast[k] = m.fast ? ~0u : 0u;
  }
  constexpr float kInfinity = std::numeric_limits<float>::infinity();
  for (std::uint32_t k = n; k < stride; ++k) {
    lowX[k] = lowY[k] = lowZ[k] = kInfinity;
    highX[k] = highY[k] = highZ[k] = -kInfinity;
    body[k] = fast[k] = 0;
  }
  detail::appendMeetingPairs({lowX, highX, lowY, highY, lowZ, highZ, body, fast, n}, sweepPairs_);
}

namespace detail {

void appendMeetingPairsOneByOne(const SortedBoxes& boxes, std::vector<std::uint64_t>& pairs) {
  const SortedBoxes& b = boxes;
  for (std::uint32_t k = 0; k < b.count; ++k) {
    // Sorted by low x, each box after k starts at or beyond k's start: none
    // meets it once one starts beyond its end. The test is boxesMeet's.
    for (std::uint32_t l = k + 1; l < b.count && !(b.lowX[l] > b.highX[k]); ++l) {
      const bool meet = ((b.fast[k] | b.fast[l]) != 0) & (b.lowX[k] <= b.highX[l]) &
                        (b.lowX[l] <= b.highX[k]) & (b.lowY[k] <= b.highY[l]) &
                        (b.lowY[l] <= b.highY[k]) & (b.lowZ[k] <= b.highZ[l]) &
                        (b.lowZ[l] <= b.highZ[k]);
      if (meet)
        pairs.push_back(std::uint64_t(std::min(b.body[k], b.body[l])) << 32 |
                        std::max(b.body[k], b.body[l]));
    }
  }
}

void appendMeetingPairs(const SortedBoxes& boxes, std::vector<std::uint64_t>& pairs) {
#ifdef BSPF_SSE_MASKS
  const SortedBoxes& b = boxes;
  for (std::uint32_t k = 0; k < b.count; ++k) {
    const __m128 lowX = _mm_set1_ps(b.lowX[k]), highX = _mm_set1_ps(b.highX[k]),
                 lowY = _mm_set1_ps(b.lowY[k]), highY = _mm_set1_ps(b.highY[k]),
                 lowZ = _mm_set1_ps(b.lowZ[k]), highZ = _mm_set1_ps(b.highZ[k]);
    const __m128i fast = _mm_set1_epi32(int(b.fast[k]));
    for (std::uint32_t l = k + 1; l < b.count; l += kBoxRun) {
      // "Not greater", as the reference's test reads (true for a NaN).
      const __m128 startsWithin = _mm_cmpngt_ps(_mm_loadu_ps(b.lowX + l), highX);
      __m128 meet = _mm_castsi128_ps(
          _mm_or_si128(fast, _mm_loadu_si128(reinterpret_cast<const __m128i*>(b.fast + l))));
      meet = _mm_and_ps(meet, _mm_cmple_ps(lowX, _mm_loadu_ps(b.highX + l)));
      meet = _mm_and_ps(meet, _mm_cmple_ps(_mm_loadu_ps(b.lowX + l), highX));
      meet = _mm_and_ps(meet, _mm_cmple_ps(lowY, _mm_loadu_ps(b.highY + l)));
      meet = _mm_and_ps(meet, _mm_cmple_ps(_mm_loadu_ps(b.lowY + l), highY));
      meet = _mm_and_ps(meet, _mm_cmple_ps(lowZ, _mm_loadu_ps(b.highZ + l)));
      meet = _mm_and_ps(meet, _mm_cmple_ps(_mm_loadu_ps(b.lowZ + l), highZ));
      // A box after one that starts beyond k's end starts beyond it too (or
      // is one of the trailing boxes): none of them meets k, so the run's
      // bits need no cut at its first such box.
      for (unsigned bits = unsigned(_mm_movemask_ps(meet)); bits != 0; bits &= bits - 1) {
        const std::uint32_t other = b.body[l + std::uint32_t(std::countr_zero(bits))];
        pairs.push_back(std::uint64_t(std::min(b.body[k], other)) << 32 |
                        std::max(b.body[k], other));
      }
      if (_mm_movemask_ps(startsWithin) != (1 << kBoxRun) - 1) break;
    }
  }
#else
  appendMeetingPairsOneByOne(boxes, pairs);
#endif
}

}  // namespace detail

template <typename Inputs>
void BodyGrid::sweep(std::size_t n, const Inputs& inputs, bool anyFast) {
  stops_.clear();
  if (!anyFast) return;
  movers_.resize(n);
  std::size_t fastCount = 0;
  for (std::size_t i = 0; i < n; ++i) {
    Mover& m = movers_[i];
    const Vec3& position = inputs.position(i);
    m.start = inputs.start(i);
    m.move = position - m.start;
    m.radii = inputs.radii(i);
    m.skin = inputs.skin(i);
    const Vec3 reach(m.radii.xz + m.skin, m.radii.y + m.skin, m.radii.xz + m.skin);
    m.low = m.start.cwiseMin(position) - reach;
    m.high = m.start.cwiseMax(position) + reach;
    m.fast = inputs.fast(i);
    fastCount += m.fast;
  }

  sweepPairs_.clear();
  if (n > kSortedSweepBodies)
    sweepPairsByCells();
  else if (fastCount <= kFewFastBodies)
    sweepPairsOfFewFast();
  else
    sweepPairsBySorting();
  std::sort(sweepPairs_.begin(), sweepPairs_.end());
  sweepPairs_.erase(std::unique(sweepPairs_.begin(), sweepPairs_.end()), sweepPairs_.end());

  // The stop times: each pair that meets stops both bodies there, and the
  // earliest meeting counts. A body stopped early may be met by others that
  // passed it by before, so the pairs are passed over until nothing
  // changes. In pair order, on this thread: the result does not depend on
  // how the phases are split between threads.
  stops_.assign(n, {1.0f, Vec3::Zero()});
  for (int pass = 0; pass < kMaxSweepPasses; ++pass) {
    bool changed = false;
    for (const std::uint64_t pair : sweepPairs_) {
      const std::uint32_t a = std::uint32_t(pair >> 32), b = std::uint32_t(pair);
      Vec3 normal;
      const double meet = meetTime(a, b, normal);
      if (meet >= 1) continue;
      const float time = float(meet);
      if (time < stops_[a].time) stops_[a] = {time, normal}, changed = true;
      if (time < stops_[b].time) stops_[b] = {time, -normal}, changed = true;
    }
    if (!changed) break;
  }
}

// Inlined: called out of line, the build took 16 instructions a body-step
// more (callgrind, 1,024 walkers on oa_dm5, one thread) than with the three
// coordinates cut in place.
inline __attribute__((always_inline)) BodyGrid::CellKey BodyGrid::cellKeyOf(const Vec3& p,
                                                                            float inverseWidth,
                                                                            float inverseHeight) {
  bool upper[3];
  const std::uint64_t x = cellCoordinate(p.x() * inverseWidth, upper[0]),
                      y = cellCoordinate(p.y() * inverseHeight, upper[1]),
                      z = cellCoordinate(p.z() * inverseWidth, upper[2]);
  return {packCell(x, y, z), std::uint8_t(upper[0] | upper[1] << 1 | upper[2] << 2)};
}

std::uint32_t BodyGrid::find(std::uint64_t key) const {
  const std::uint32_t mask = std::uint32_t(cells_.size() - 1);
  std::uint32_t slot = cellHash(key, shift_);
  while (cells_[slot].key != key && cells_[slot].key != kFree) slot = (slot + 1) & mask;
  return slot;
}

void BodyGrid::build(std::span<const Body> bodies) {
  struct FromBodies {
    std::span<const Body> bodies;
    const Vec3& position(std::size_t i) const { return bodies[i].position; }
    const Vec3& start(std::size_t i) const { return bodies[i].lastStepStart; }
    EllipsoidRadii radii(std::size_t i) const { return bodies[i].radii; }
    float skin(std::size_t i) const { return bodies[i].settings.skin; }
    bool fast(std::size_t i) const { return sweptFast(bodies[i]); }
    detail::CrowdScan scan(std::size_t) const { return detail::scanCrowd(bodies, movedFast); }
    bool keyedFor(float, float) const { return false; }
    CellKey cellKey(std::size_t) const { return {}; }
    // With SSE2, a body's position in one 16-byte copy (the lane after it,
    // velocity.x, lands where the radii go next): Eigen's copy and the test
    // of the stops took 14 instructions a body-step (walkers, 64 agents,
    // fan). The same bits.
    void placeEntries(std::vector<Entry>& entries) const {
#ifdef BSPF_SSE_MASKS
      static_assert(offsetof(Body, position) + 16 <= sizeof(Body) &&
                    offsetof(Entry, position) == 0 && offsetof(Entry, radii) == 12);
      // The vector's bounds read once: the stores below could alias them.
      Entry* const out = entries.data();
      const Body* const in = bodies.data();
      for (std::size_t i = 0, n = entries.size(); i < n; ++i) {
        Entry& e = out[i];
        _mm_storeu_ps(&e.position.x(), _mm_loadu_ps(&in[i].position.x()));
        e.radii = in[i].radii;
        e.body = std::uint32_t(i);
      }
#else
      for (std::size_t i = 0; i < entries.size(); ++i)
        entries[i] = {bodies[i].position, bodies[i].radii, std::uint32_t(i)};
#endif
    }
  };
  buildFrom(bodies.size(), FromBodies{bodies});
}

template <typename Inputs>
void BodyGrid::buildFrom(std::size_t n, const Inputs& inputs) {
  // Cells twice as wide as the widest body and twice as tall as the tallest:
  // the centres of two overlapping bodies are then less than half a cell
  // apart on each axis, so a body's overlaps lie in its own cell and the
  // neighbour on the nearer side along each axis (8 cells, not 27: each
  // look-up is a likely cache miss).
  // In the same pass, whether any body moved fast (movedFast): inputs.scan,
  // four bodies at a time for the bodies themselves (detail::scanCrowd).
  const detail::CrowdScan scan = inputs.scan(n);
  const float width = scan.width, height = scan.height;
  const bool anyFast = scan.anyFast;
  inverseWidth_ = width > 0 ? 1 / width : 1;
  inverseHeight_ = height > 0 ? 1 / height : 1;
  // The sweep stops fast bodies where they first meet another; the grid
  // holds every body where it ends.
  sweep(n, inputs, anyFast);
  auto endOf = [&](std::size_t i) -> Vec3 {
    return stops_.empty() || !(stops_[i].time < 1)
               ? inputs.position(i)
               : Vec3(movers_[i].start + stops_[i].time * movers_[i].move);
  };
  // A crowd the sorting turned back (a dense one, most often) is not sorted
  // again for a while: the sorting's cost would be lost each frame. Either
  // way the pairs are the same, so this history changes no push.
  if (n <= std::size_t(kSortedNeighbourBodies) && buildsUntilSortingAgain_-- <= 0) {
    buildsUntilSortingAgain_ = 0;
    entries_.resize(n);
    inputs.placeEntries(entries_);
    for (std::size_t i = 0; i < stops_.size(); ++i)
      if (stops_[i].time < 1) entries_[i].position = endOf(i);
    sortedNeighbours_ = findNeighboursBySorting(width, height);
    if (sortedNeighbours_) return;
    buildsUntilSortingAgain_ = kBuildsBeforeSortingAgain;
  }
  sortedNeighbours_ = false;
  // At most half full, so a look-up probes few slots.
  std::size_t size = 16;
  shift_ = 60;
  while (size < 2 * n) size *= 2, --shift_;
  cells_.assign(size, {kFree, 0, 0});

  // A counting sort by cell: count, lay the cells out in table order, place
  // each body in its cell's next place.
  places_.resize(n);
  // The cells prepare() cut, where it cut them as this build does (the
  // bodies' widest and tallest did not change since the last build): they
  // are the same keys, and the work was done on every core at once.
  const bool keyed = inputs.keyedFor(inverseWidth_, inverseHeight_);
  std::array<std::uint64_t, 3> lowCell{kFieldMask, kFieldMask, kFieldMask}, highCell{};
  for (std::size_t i = 0; i < n; ++i) {
    const bool stopped = !stops_.empty() && stops_[i].time < 1;
    const CellKey c =
        keyed && !stopped ? inputs.cellKey(i) : cellKeyOf(endOf(i), inverseWidth_, inverseHeight_);
    const std::uint64_t key = c.key;
    const std::array<std::uint64_t, 3> cell = unpackCell(key);
    for (int axis = 0; axis < 3; ++axis) {
      lowCell[axis] = std::min(lowCell[axis], cell[axis]);
      highCell[axis] = std::max(highCell[axis], cell[axis]);
    }
    const std::uint32_t slot = find(key);
    cells_[slot].key = key;
    ++cells_[slot].count;
    places_[i] = {key, 0, slot, 0, c.upperHalf};
  }
  // The occupancy bits, when their box is small: a crowd on a level spans a
  // few thousand cells at most.
  occupied_.clear();
  std::array<std::uint64_t, 3> span{};
  for (int axis = 0; axis < 3; ++axis) span[axis] = n > 0 ? highCell[axis] - lowCell[axis] + 3 : 0;
  const bool bits = n > 0 && span[0] * span[1] * span[2] <= 512 * n + 4096;
  if (bits) {
    occupied_.assign((span[0] * span[1] * span[2] + 63) / 64, 0);
    const std::array<std::uint32_t, 3> stride{1, std::uint32_t(span[0]),
                                              std::uint32_t(span[0] * span[1])};
    for (int upper = 0; upper < 8; ++upper)
      for (int corner = 1; corner < 8; ++corner) {
        std::uint32_t offset = 0;
        for (int axis = 0; axis < 3; ++axis)
          if (corner >> axis & 1) offset += upper >> axis & 1 ? stride[axis] : 0 - stride[axis];
        bitOffsets_[upper][corner - 1] = offset;
      }
  }
  // Each cell's `first` at the end of its entries, then the bodies placed
  // last index first: `first` comes back to the start, and a cell's bodies
  // sit in index order.
  std::uint32_t laid = 0;
  for (Cell& c : cells_) c.first = laid += c.count;
  entries_.resize(n);
  for (std::size_t i = n; i-- > 0;) {
    Place& place = places_[i];
    place.entry = --cells_[place.cellSlot].first;
    entries_[place.entry] = {endOf(i), inputs.radii(i), std::uint32_t(i)};
    if (bits) {
      // One cell of margin, so a neighbour's bit is always in the box.
      const std::array<std::uint64_t, 3> cell = unpackCell(place.key);
      place.bit = std::uint32_t(
          cell[0] - lowCell[0] + 1 +
          span[0] * (cell[1] - lowCell[1] + 1 + span[1] * (cell[2] - lowCell[2] + 1)));
      occupied_[place.bit >> 6] |= std::uint64_t(1) << (place.bit & 63);
    }
  }
}

namespace {

// A body's grid cell (offset coordinates, as BodyGrid::build files it) and
// its upper-half bits.
struct GridCell {
  std::array<std::uint64_t, 3> coordinates;
  unsigned upperHalf;
};

}  // namespace

bool BodyGrid::findNeighboursBySorting(float width, float height) {
  const std::uint32_t n = std::uint32_t(entries_.size());
  nearHead_.assign(n, kNoNeighbour);
  nearLinks_.clear();
  // Whether the grid would examine `other` for `self` (it lies in one of
  // self's 8 cells) and their boxes overlap: then each is linked to the
  // other (pair). Measured here once for the pair's two pushes.
  const Vec3 inverse(inverseWidth_, inverseHeight_, inverseWidth_);
  auto withinHalfCell = [&](const Vec3& p, const Vec3& q) {
    for (int axis = 0; axis < 3; ++axis)
      if (!(std::abs(clampToCells(p[axis] * inverse[axis]) -
                     clampToCells(q[axis] * inverse[axis])) < 0.5f))
        return false;
    return true;
  };
  auto cellOf = [&](const Vec3& p) {
    const CellKey c = cellKeyOf(p, inverseWidth_, inverseHeight_);
    return GridCell{unpackCell(c.key), c.upperHalf};
  };
  auto examines = [](const GridCell& self, const GridCell& other) {
    for (int axis = 0; axis < 3; ++axis) {
      const std::uint64_t own = self.coordinates[axis],
                          beside = self.upperHalf >> axis & 1 ? own + 1 : own - 1;
      if (other.coordinates[axis] != own && other.coordinates[axis] != beside) return false;
    }
    return true;
  };
  auto link = [&](std::uint32_t self, std::uint32_t other, float distance, float overlap) {
    nearLinks_.push_back({other, nearHead_[self], distance, overlap});
    nearHead_[self] = std::uint32_t(nearLinks_.size() - 1);
  };
  // Whether the boxes of entries a and b overlap; with no branch (the
  // listed pairs are tested in a row, and which of them overlap is no
  // pattern: a mispredicted branch a few pairs in ten).
  auto boxesOverlapOf = [&](std::uint32_t a, std::uint32_t b) __attribute__((always_inline)) {
    const Entry &p = entries_[a], &q = entries_[b];
    const float ax = p.position.x() - q.position.x(), ay = p.position.y() - q.position.y(),
                az = p.position.z() - q.position.z();
    const float reachXZ = p.radii.xz + q.radii.xz;
    return !(int(std::abs(ax) >= reachXZ) | int(std::abs(az) >= reachXZ) |
             int(std::abs(ay) >= p.radii.y + q.radii.y));
  };
  // The distance and overlap of the pair of entries a and b, as a push
  // measures them.
  auto measure = [&](std::uint32_t a, std::uint32_t b, float& distance, float& overlap)
      __attribute__((always_inline)) {
    const Entry &p = entries_[a], &q = entries_[b];
    const float ax = p.position.x() - q.position.x(), ay = p.position.y() - q.position.y(),
                az = p.position.z() - q.position.z();
    distance = centreDistance(ax, ay, az);
    overlap = pairOverlap(ax, ay, az, distance, p.radii, q.radii);
  };
  // A pair that overlaps (overlap > 0): its links. A pair whose boxes
  // overlap but whose bodies do not pushes neither, and gets none: a push
  // offers only pushers that overlap, so every link is one, and a body
  // visited has one.
  auto linkOverlapping = [&](std::uint32_t a, std::uint32_t b, float distance, float overlap)
      __attribute__((always_inline)) {
    const Entry &p = entries_[a], &q = entries_[b];
    // The common case, tested before the cells themselves: the two lie less
    // than half a cell apart along each axis in the coordinates cells are
    // cut from (whichever half of its cell a body lies in, the neighbour on
    // that side holds all within half a cell).
    if (withinHalfCell(p.position, q.position)) {
      link(a, b, distance, overlap);
      link(b, a, distance, overlap);
      return;
    }
    const GridCell cellA = cellOf(p.position), cellB = cellOf(q.position);
    if (examines(cellA, cellB)) link(a, b, distance, overlap);
    if (examines(cellB, cellA)) link(b, a, distance, overlap);
  };
  auto pair = [&](std::uint32_t a, std::uint32_t b) __attribute__((always_inline)) {
    if (!boxesOverlapOf(a, b)) return;
    float distance, overlap;
    measure(a, b, distance, overlap);
    if (overlap > 0) linkOverlapping(a, b, distance, overlap);
  };

  // The listed pairs whose boxes overlap, gathered first, then of those the
  // ones that overlap (measured four at a time: detail::keepOverlapping),
  // then linked: each gathering with no branch (each pair written, the
  // count moved on by the test), as which pairs pass is no pattern (a
  // mispredicted branch a few pairs in ten).
  auto linkListed = [&] {
    overlappingPairs_.resize(listedPairs_.size());
    OverlappingPair* const overlapping = overlappingPairs_.data();
    std::size_t boxes = 0;
    for (const std::uint64_t p : listedPairs_) {
      overlapping[boxes].pair = p;
      boxes += boxesOverlapOf(std::uint32_t(p >> 32), std::uint32_t(p));
    }
    const std::size_t count = detail::keepOverlapping(entries_.data(), overlapping, boxes);
    for (std::size_t k = 0; k < count; ++k) {
      const OverlappingPair& o = overlapping[k];
      linkOverlapping(std::uint32_t(o.pair >> 32), std::uint32_t(o.pair), o.distance, o.overlap);
    }
  };

  // No body moved more than the slack along any axis (along y, its own)
  // since the pairs were listed: every pair whose boxes overlap now is
  // listed (they were then within reach plus twice the slack), and no body
  // can have more than kMaxBodyCandidates others in its cells (see below).
  // The list's pairs, tested as the scan tests them, give the scan's links,
  // in another order (which nothing depends on): walkers at 6 m/s list them
  // every few frames, and the sort and the scan were 37% of the body
  // phase's instructions (64 agents, oa_dm4).
  const bool comparable = listedSlack_ >= 0 && listedEntries_.size() == n &&
                          listedWidth_ == width && listedHeight_ == height;
  if (comparable &&
      detail::movedWithin<Entry>(entries_, listedEntries_, listedSlack_, listedSlackY_)) {
    ++listedBuilds_;
    linkListed();
    return true;
  }
  // A list that served no build (a body moved further than the slack in one
  // frame: running bodies) cost more than it spared (the wider scan, the
  // list, the test of the moves: 70 instructions a body-step at 40 m/s on
  // fan, oa_dm4 and oa_dm5): for a while, twice as long after each such
  // list, the pairs are found by the plain scan, with no list. Either way
  // they are the same pairs.
  if (comparable && listedBuilds_ == 0) {
    buildsUntilListingAgain_ = listingBackOff_;
    listingBackOff_ = std::min(2 * listingBackOff_, kMostBuildsBeforeListingAgain);
  } else if (listedBuilds_ > 0) {
    listingBackOff_ = kLeastBuildsBeforeListingAgain;
  }
  const bool listing = buildsUntilListingAgain_ == 0;
  if (!listing) --buildsUntilListingAgain_;
  listedSlack_ = -1;
  listedBuilds_ = 0;

  // The slack of a new list: a share of the reach (a larger one lists more
  // pairs, and the scan that lists them reads further along x), along y a
  // share of the reach along y.
  const float reach = 0.5f * width, reachY = 0.5f * height;
  const float slack = kListSlackShare * reach, slackY = kListSlackShareY * reachY;
  // The bodies, then kCentreRun places at x +infinity that end every scan
  // below (beyond any reach: no bound to test).
  if (xOrder_.size() != n + detail::kCentreRun) {
    xOrder_.resize(n + detail::kCentreRun);
    for (std::uint32_t i = 0; i < n; ++i) xOrder_[i] = {0, 0, 0, i};
    for (std::uint32_t i = n; i < n + detail::kCentreRun; ++i)
      xOrder_[i] = {std::numeric_limits<float>::infinity(), 0, 0, kNoNeighbour};
  }
  // Each centre beside its index (the scan below reads them in a row, where
  // going through the index to the entry took two dependent loads a pair),
  // taken in the last order and insertion-sorted in the same pass: the
  // bodies moved a little since the last build, so the last order is nearly
  // this one (a few swaps, not a sort's n log n). Ties along x keep their
  // last order: nothing below depends on it (every pair within reach is
  // found whichever comes first, and NearestPushers orders pushers itself).
  // The scan below needs x in order and every pair's reach at most half a
  // cell (the cell's std::max passed over a NaN radius): x - x is NaN when x
  // is not finite, the sum when a radius is NaN (or, turned back needlessly,
  // when radii are infinities of both signs), and a NaN stays in the sum.
  // Tested once, after the pass (a NaN's place in the order is then
  // unused): a branch a body cost 8 instructions a body-step.
  float notFinite = 0;
  for (std::uint32_t k = 0; k < n; ++k) {
    detail::SortedCentre place = xOrder_[k];
    const Entry& e = entries_[place.body];
    notFinite += (e.position.x() - e.position.x()) + (e.radii.xz + e.radii.y);
    place.x = e.position.x(), place.y = e.position.y(), place.z = e.position.z();
    std::uint32_t at = k;
    for (; at > 0 && place.x < xOrder_[at - 1].x; --at) xOrder_[at] = xOrder_[at - 1];
    xOrder_[at] = place;
  }
  if (std::isnan(notFinite)) return false;
  // The grid examines at most kMaxBodyCandidates bodies of a body's 8 cells,
  // in an order of its own: with more there, which pushers it finds depends
  // on that order, so the grid must find them. Those cells span 2 cells
  // along x (in the clamped coordinates cells are cut from), so 34 bodies
  // (it and 33 others) would lie within 2 cells of each other along x,
  // consecutive in x order; none lie within 4. That leaves room for a
  // list's moves: while no body moves more than the slack along x (at most
  // half a cell; clamping shortens no distance more than the move), two
  // come no more than a cell nearer, and no 34 within 3 (the slack along y
  // counts for nothing here).
  // (Testing only the runs that start at every 4th or 8th place, shorter to
  // hold any such run, turned fan's crowd back to the grid: it has runs of
  // 31 within 4 cells.)
  static_assert(kListSlackShare <= 1, "a list's moves keep no 34 bodies within 2 cells");
  constexpr std::uint32_t kRun = kMaxBodyCandidates + 2;
  for (std::uint32_t k = 0; k + kRun <= n; ++k)
    if (!(clampToCells(xOrder_[k + kRun - 1].x * inverseWidth_) -
              clampToCells(xOrder_[k].x * inverseWidth_) >
          4))
      return false;

  // Each pair less than half a cell (plus twice the slack) apart along x:
  // half a cell is twice the largest radius (exactly: the cell's size is 4
  // of them), so it is at least any pair's summed radii (the sum of two
  // floats no larger rounds to no more), and no pair reaches further. A pair
  // as far apart along z or y fails the box test, which most pairs in reach
  // along x do: tested first, on the centres in a row (forNearCentres). A
  // pair within reach now was within reach and twice the slack when listed
  // (along y, twice the slack along y; its centres' differences moved by at
  // most that; 2^-20 more covers their rounding, relative to the reach).
  const auto pairOfCentres = [&](const detail::SortedCentre* self,
                                 const detail::SortedCentre* other) {
    pair(self->body, other->body);
  };
  if (!listing) {
    detail::forNearCentres(xOrder_.data(), n, reach, reachY, pairOfCentres);
    return true;
  }
  const float grow = 1 + 0x1p-20f;
  listedPairs_.clear();
  detail::forNearCentres(xOrder_.data(), n, (reach + 2 * slack) * grow,
                         (reachY + 2 * slackY) * grow,
                         [&](const detail::SortedCentre* self, const detail::SortedCentre* other) {
                           listedPairs_.push_back(std::uint64_t(self->body) << 32 | other->body);
                         });
  // Then linked as a build the list serves links them (each pair tested in
  // the scan took a mispredicted branch for most of them).
  linkListed();
  listedEntries_ = entries_;
  listedSlack_ = slack;
  listedSlackY_ = slackY;
  listedWidth_ = width;
  listedHeight_ = height;
  return true;
}

void BodyGrid::startPreparing(std::size_t bodies) {
  prepared_.resize(bodies);
  // The cells of the last build: a crowd's widest and tallest body seldom
  // change, and a build whose cells differ cuts its own. None for a crowd
  // small enough to be sorted (most often with no cells).
  cutsCells_ = bodies > std::size_t(kSortedNeighbourBodies);
  keyedInverseWidth_ = inverseWidth_;
  keyedInverseHeight_ = inverseHeight_;
}

void BodyGrid::prepare(std::span<const Body> bodies, std::size_t first, std::size_t last) {
  assert(last <= prepared_.size() && prepared_.size() == bodies.size());
  for (std::size_t i = first; i < last; ++i) {
    const Body& b = bodies[i];
    const CellKey cell =
        cutsCells_ ? cellKeyOf(b.position, keyedInverseWidth_, keyedInverseHeight_) : CellKey{};
    prepared_[i] = {b.position, b.lastStepStart, b.radii, b.settings.skin, sweptFast(b), cell};
  }
}

void BodyGrid::buildPrepared(const BodyGrid& prepared) {
  struct FromPrepared {
    const std::vector<BodyGrid::Prepared>& prepared;
    bool cutsCells;
    float keyedInverseWidth, keyedInverseHeight;
    bool keyedFor(float inverseWidth, float inverseHeight) const {
      return cutsCells && inverseWidth == keyedInverseWidth && inverseHeight == keyedInverseHeight;
    }
    CellKey cellKey(std::size_t i) const { return prepared[i].cell; }
    const Vec3& position(std::size_t i) const { return prepared[i].position; }
    const Vec3& start(std::size_t i) const { return prepared[i].start; }
    EllipsoidRadii radii(std::size_t i) const { return prepared[i].radii; }
    float skin(std::size_t i) const { return prepared[i].skin; }
    bool fast(std::size_t i) const { return prepared[i].fast; }
    void placeEntries(std::vector<Entry>& entries) const {
      for (std::size_t i = 0; i < entries.size(); ++i)
        entries[i] = {prepared[i].position, prepared[i].radii, std::uint32_t(i)};
    }
    detail::CrowdScan scan(std::size_t n) const {
      detail::CrowdScan crowd;
      for (std::size_t i = 0; i < n; ++i) {
        crowd.width = std::max(crowd.width, 4 * prepared[i].radii.xz);
        crowd.height = std::max(crowd.height, 4 * prepared[i].radii.y);
        crowd.anyFast = crowd.anyFast || prepared[i].fast;
      }
      return crowd;
    }
  };
  buildFrom(prepared.prepared_.size(),
            FromPrepared{prepared.prepared_, prepared.cutsCells_, prepared.keyedInverseWidth_,
                         prepared.keyedInverseHeight_});
}

void pushBodiesApart(const World& world, const BodyGrid& grid, std::span<Body> bodies,
                     std::size_t first, std::size_t last, StepScratch& scratch,
                     std::span<StepReport> reports) {
  std::vector<detail::BodyCache>& caches = scratch.workspace().bodies;
  if (caches.size() < bodies.size()) caches.resize(bodies.size());
  detail::pushRange(world, grid, bodies, first, last, scratch, reports, caches);
}

void pushBodiesApart(const World& world, const BodyGrid& grid, std::span<Body> bodies,
                     std::size_t first, std::size_t last, StepScratch& scratch, BodyCaches& caches,
                     std::span<StepReport> reports) {
  assert(bodies.size() <= caches.size());
  detail::pushRange(world, grid, bodies, first, last, scratch, reports, caches.caches_);
}

namespace {

// The pad, metres, of the query a push makes when the body's own query does
// not hold the push's box (plus twice the push's length, as a slide's).
constexpr float kPushQueryPad = 0.3f;

// Whether a triangle whose box overlaps the move's from `from` to `to` keeps
// clear by more than `margin`, given its face plane and the body's extent
// along it (detail::planesFaceTest): at both ends beyond the extent in front
// of the plane, or behind it.
bool keepsClear(const detail::FaceTest& face, const Vec3& from, const Vec3& to, float margin) {
  const float fromSide = face.normal.dot(from) - face.distance,
              toSide = face.normal.dot(to) - face.distance;
  const float reach = face.reach + margin;
  return !(std::min(fromSide, toSide) < reach && std::max(fromSide, toSide) > -reach);
}

// The candidates the body's level move made from its query, for its radii:
// their boxes in blocks of 8, each block's lanes that overlap the move's
// `box` found by the lane mask (no test of the block's own box first: its
// branch mispredicted for a third of the blocks, and the mask finds no lane
// where that test would have passed the block over) and, the planes
// method's, each face plane with the body's extent along it
// (effectiveRadius, as planesFaceTest), so no triangle's record is read
// from the level. The clearance test was 40 to 50% of the pushes' cycles
// (walkers, 64 agents, oa_dm4 and oa_dm5); scanning the blocks, not the
// list and the level's records, made the pushes 10% faster on oa_dm5 at 6
// and 40 m/s. `world` and `triangles` are read only for the exact sweep's
// lanes (`planesMade` false), which hold a padded extent: for them, the
// plane and extent as the list's scan takes them.
template <typename Blocks, typename Triangles>
[[gnu::always_inline]] inline bool blocksKeepClear(const World& world, const Blocks& blocks,
                                                   const Triangles& triangles, bool planesMade,
                                                   const Bounds& box, const Vec3& from,
                                                   const Vec3& to, EllipsoidRadii radii,
                                                   float margin, detail::BoxMaskFunction boxMask) {
  for (const detail::CandidateBlock& block : blocks) {
    for (std::uint32_t lanes = boxMask(block, box); lanes != 0; lanes &= lanes - 1) {
      const int lane = std::countr_zero(lanes);
      const detail::FaceTest face =
          planesMade ? detail::FaceTest{Vec3(block.normalX[lane], block.normalY[lane],
                                             block.normalZ[lane]),
                                        block.distance[lane], block.reach[lane]}
                     : detail::planesFaceTest(world, triangles[block.slot[lane]], radii);
      if (!keepsClear(face, from, to, margin)) return false;
    }
  }
  return true;
}

// touchesNothing where the body's planes candidates do not decide it: its
// query is made to cover `box` if it does not already (the body's own
// query, whenever it holds the box, however much larger: cover() would
// query again for a box far smaller than the query's; at 40 m/s, about 1
// push in 15 did, and the body's next step then queried again for its own
// move, 3 to 5% of a 40 m/s step's instructions). A new query is padded like
// a walking body's own, so that it serves the body's next steps too. Only
// the cost depends on the pad.
[[gnu::noinline]] bool touchesNothingElsewhere(const World& world, const Vec3& from, const Vec3& to,
                                               EllipsoidRadii radii, float margin,
                                               const Bounds& box, detail::BodyCache& cache,
                                               SweepScratch& sweep,
                                               detail::BoxMaskFunction boxMask) {
  NearbyTriangles& nearby = cache.nearby;
  if (!nearby.holds(world, box.low, box.high))
    nearby.cover(world, box.low, box.high, kPushQueryPad + 2 * (to - from).norm(), sweep);
  if (cache.planes.madeFrom(nearby, radii))
    return blocksKeepClear(world, cache.planes.blocks, cache.planes.triangles, true, box, from, to,
                           radii, margin, boxMask);
  if (cache.exact.madeFrom(nearby, radii))
    return blocksKeepClear(world, cache.exact.blocks, cache.exact.triangles, false, box, from, to,
                           radii, margin, boxMask);
  for (const CandidateTriangle& c : nearby.list()) {
    if (!boxesOverlap(c.low, c.high, box.low, box.high)) continue;
    if (!keepsClear(detail::planesFaceTest(world, c.triangle, radii), from, to, margin))
      return false;
  }
  return true;
}

// Whether a body with `radii` moving its centre from `from` to `to` keeps
// clear of every triangle by more than a quarter of its skin: each triangle
// whose box meets the box of the move is that far beyond the body's extent
// in front of its plane (or behind it) at both ends, so the body never nears
// its plane. Neither narrow phase then has anything to slide against (the
// planes method's pre-check and the exact sweep's both reject every such
// triangle), and the body goes the whole way. The margin covers rounding:
// a body resting on a floor is a whole skin above it. `cache` is the body's
// own: its query is made to cover the box if it does not already. Inline,
// the common case (a walking body's planes candidates, made from a query
// that holds the box) and the rest out of line: the call's entry and exit
// alone were 25 instructions a push.
[[gnu::always_inline]] inline bool touchesNothing(const World& world, const Vec3& from,
                                                  const Vec3& to, EllipsoidRadii radii, float skin,
                                                  detail::BodyCache& cache, SweepScratch& sweep,
                                                  detail::BoxMaskFunction boxMask) {
  const float margin = 0.25f * skin;
  const Bounds box = detail::pushBounds(from, to, radii, margin);
  if (cache.planes.madeFrom(cache.nearby, radii) && cache.nearby.holds(world, box.low, box.high))
    return blocksKeepClear(world, cache.planes.blocks, cache.planes.triangles, true, box, from, to,
                           radii, margin, boxMask);
  return touchesNothingElsewhere(world, from, to, radii, margin, box, cache, sweep, boxMask);
}

// A body the sweep stopped where it met another: set back to `at` along its
// move (as a move from its step's start against the level: the straight
// line from there may cut a corner its slides went round), and its velocity
// loses what closes on the other body along `normal`. Never upward speed
// from it: running into another's shoulder is not a jump over it.
void stopAtBody(const World& world, Body& body, const Vec3& at, const Vec3& normal,
                StepScratch& scratch, StepReport* report, detail::BodyCache& cache) {
  if (touchesNothing(world, body.lastStepStart, at, body.radii, body.settings.skin, cache,
                     scratch.sweep, detail::boxMaskFunction())) {
    body.position = at;
  } else {
    swapBodyCache(scratch, cache);
    const SlideResult slide =
        slideAgainstLevel(world, body.lastStepStart, at, body.radii, body.settings,
                          walkableNormalY(body.settings), scratch);
    swapBodyCache(scratch, cache);
    body.position = slide.end;
    recordSlide(world, report, slide, false);
  }
  const float closing = body.velocity.dot(normal);
  if (closing < 0) {
    const float up = std::max(body.velocity.y(), 0.0f);
    body.velocity -= closing * normal;
    body.velocity.y() = std::min(body.velocity.y(), up);
  }
  if (report) report->stoppedByBody = true;
}

}  // namespace

namespace detail {

void pushRange(const World& world, const BodyGrid& grid, std::span<Body> bodies, std::size_t first,
               std::size_t last, StepScratch& scratch, std::span<StepReport> reports,
               std::span<BodyCache> caches) {
  if (grid.entries_.size() < 2 || first >= last) return;
  // The clearance test's box mask, asked once a pass (the pushes' boxMask
  // calls each tested the CPU).
  const detail::BoxMaskFunction boxMask = detail::boxMaskFunction();
  // Most bodies of a small crowd have no other near them and were not
  // stopped by the sweep: the pass visits only the others, by their bits
  // (the full loop's head, with its spilled pointers, took 28 instructions
  // a body; a tight loop over every body's head, 8 a body-step on fan).
  std::uint64_t visit = 0;
  if (grid.sortedNeighbours_) {
    visit = detail::linkedBits(grid.nearHead_, BodyGrid::kNoNeighbour);
    if (!grid.stops_.empty())
      for (std::size_t i = first; i < last; ++i)
        if (grid.stops_[i].time < 1) visit |= std::uint64_t(1) << i;
    // [first, last): first < last <= 64 here.
    visit &= ~((std::uint64_t(1) << first) - 1);
    if (last < 64) visit &= (std::uint64_t(1) << last) - 1;
  }
  // The pushes found, then made (or carried) a pass later: each body's
  // clearance test waits on its push's long chain of square roots and
  // divisions, and apart from it the tests of bodies in a row overlap. A
  // push changes only its own body's position and its own cache, which
  // nothing else in the pass reads.
  struct PendingPush {
    std::uint32_t body;
    Vec3 push;
  };
  std::array<PendingPush, 64> pending;
  std::size_t pendingCount = 0;
  auto makePending = [&] {
    for (std::size_t k = 0; k < pendingCount; ++k) {
      Body& body = bodies[pending[k].body];
      const Vec3& push = pending[k].push;
      const Vec3 end = body.position + push;
      if (touchesNothing(world, body.position, end, body.radii, body.settings.skin,
                         caches[pending[k].body], scratch.sweep, boxMask))
        body.position = end;
      else
        body.deferredPush = push;
    }
    pendingCount = 0;
  };
  for (std::size_t i = first; i < last; ++i) {
    if (grid.sortedNeighbours_) {
      if (visit == 0) break;
      i = std::size_t(std::countr_zero(visit));
      visit &= visit - 1;
    }
    Body& body = bodies[i];
    const BodyGrid::Entry& self =
        grid.entries_[grid.sortedNeighbours_ ? std::uint32_t(i) : grid.places_[i].entry];
    if (!grid.stops_.empty() && grid.stops_[i].time < 1)
      stopAtBody(world, body, self.position, grid.stops_[i].normal, scratch,
                 reports.empty() ? nullptr : &reports[i], caches[i]);
    // Most bodies of a small crowd have no other near them.
    if (grid.sortedNeighbours_ && grid.nearHead_[i] == BodyGrid::kNoNeighbour) continue;
    NearestPushers nearest;
    if (grid.sortedNeighbours_) {
      // The grid's candidates whose boxes overlap, found by sorting: no more
      // than kMaxBodyCandidates, so examined in any order they give the
      // same nearest pushers.
      // Each pair's distance and overlap were measured once, for both
      // bodies, as the unsorted path measures them (detail::keepOverlapping).
      for (std::uint32_t link = grid.nearHead_[i]; link != BodyGrid::kNoNeighbour;
           link = grid.nearLinks_[link].next) {
        const BodyGrid::NearLink& near = grid.nearLinks_[link];
        const bool known = apartKnown(near.distance);
        if (!nearest.wants(known ? near.distance : 0, near.body)) continue;
        const Vec3& other = grid.entries_[near.body].position;
        assert(near.overlap > 0);
        nearest.offer({near.body, known,
                       Vec3(self.position.x() - other.x(), self.position.y() - other.y(),
                            self.position.z() - other.z()),
                       near.overlap});
      }
    } else {
      // Its own cell first, outwards from its own place (a cell's bodies sit
      // in index order): in a pile larger than the candidate cap, each body
      // meets the bodies nearest it in index order, not all the same few.
      const BodyGrid::Place& place = grid.places_[i];
      const BodyGrid::Cell& own = grid.cells_[place.cellSlot];
      // The candidates whose boxes overlap this body's, as (this body's
      // entry, the other's) pairs, measured after the gathering four at a
      // time (detail::keepOverlapping): a pile gathers kMaxBodyCandidates a
      // body, and each one's three square roots and three divisions, one at
      // a time, were most of its body phase.
      struct CandidatePair {
        std::uint64_t pair;
        float distance, overlap;
      };
      std::array<CandidatePair, kMaxBodyCandidates> candidates;
      std::size_t boxesOverlapping = 0;
      int examined = 0;
      auto examine = [&](std::uint32_t otherEntry) {
        ++examined;
        const BodyGrid::Entry& other = grid.entries_[otherEntry];
        // Overlapping ellipsoids overlap in their bounding boxes too: most
        // candidates of a walking crowd end here, before any square root.
        // With no branch (the pair written, the count moved on by the
        // test): in a pile, which candidates pass is no pattern. A NaN
        // passes, to be measured, as it did with an early return.
        const float reachXZ = self.radii.xz + other.radii.xz;
        const bool boxes = int(!(std::abs(self.position.x() - other.position.x()) >= reachXZ)) &
                           int(!(std::abs(self.position.z() - other.position.z()) >= reachXZ)) &
                           int(!(std::abs(self.position.y() - other.position.y()) >=
                                 self.radii.y + other.radii.y));
        candidates[boxesOverlapping].pair = std::uint64_t(place.entry) << 32 | otherEntry;
        boxesOverlapping += boxes;
      };
      for (std::uint32_t step = 1; examined < kMaxBodyCandidates; ++step) {
        const bool below = place.entry >= own.first + step,
                   above = place.entry + step < own.first + own.count;
        if (!below && !above) break;
        if (below) examine(place.entry - step);
        if (above && examined < kMaxBodyCandidates) examine(place.entry + step);
      }
      // Then the 7 other cells that may hold an overlapping body. Most are
      // empty: their occupancy bits, when kept, spare those a hash look-up.
      unsigned around = 0x7f;
      if (!grid.occupied_.empty()) {
        around = 0;
        const std::array<std::uint32_t, 7>& offsets = grid.bitOffsets_[place.upperHalf];
        const std::uint64_t* occupied = grid.occupied_.data();
        for (int k = 0; k < 7; ++k) {
          const std::uint32_t bit = place.bit + offsets[k];
          around |= unsigned(occupied[bit >> 6] >> (bit & 63) & 1) << k;
        }
      }
      for (; around != 0 && examined < kMaxBodyCandidates; around &= around - 1) {
        const int k = std::countr_zero(around);
        const BodyGrid::Cell& cell =
            grid.cells_[grid.find(place.key + kNeighbourOffsets[place.upperHalf][k])];
        for (std::uint32_t e = cell.first, end = cell.first + cell.count;
             e < end && examined < kMaxBodyCandidates; ++e)
          examine(e);
      }
      // The nearest of those that overlap: which pushers that keeps does not
      // depend on when each pair was measured.
      const std::size_t overlapping =
          detail::keepOverlapping(grid.entries_.data(), candidates.data(), boxesOverlapping);
      for (std::size_t k = 0; k < overlapping; ++k) {
        const CandidatePair& c = candidates[k];
        const BodyGrid::Entry& other = grid.entries_[std::uint32_t(c.pair)];
        const bool known = apartKnown(c.distance);
        if (!nearest.wants(known ? c.distance : 0, other.body)) continue;
        nearest.offer(
            {other.body, known,
             Vec3(self.position.x() - other.position.x(), self.position.y() - other.position.y(),
                  self.position.z() - other.position.z()),
             c.overlap});
      }
    }

    if (nearest.size() == 0) continue;
    // Half of each overlap, plus half the skin so that the pair ends just
    // apart; the velocity loses only its horizontal closing speed: removing
    // it along a tilted line between centres would turn a fast body's run
    // into a jump over the other's shoulder.
    Vec3 push = Vec3::Zero();
    float largest = 0;
    for (int k = 0; k < nearest.size(); ++k) {
      const Pusher& p = nearest[k];
      const Vec3 level(p.apart.x(), 0, p.apart.z());
      const float length = level.norm();
      const Vec3 away = p.apartKnown && length > 1e-6f ? Vec3(level / length)
                                                       : tieBreakDirection(self.body, p.body);
      const float share = 0.5f * p.overlap + 0.5f * body.settings.skin;
      push += share * away;
      largest = std::max(largest, share);
      const float closing = body.velocity.dot(away);
      if (closing < 0) body.velocity -= closing * away;
      if (!reports.empty() && reports[i].contactCount < kMaxReportedContacts) {
        StepReport& report = reports[i];
        const int c = report.contactCount++;
        report.contactNormals[c] = away;
        report.contactPoints[c] = body.position - body.radii.xz * away;  // `away` is level
        report.contactTriangles[c] = report.contactSurfaces[c] = kBodyContact;
      }
    }
    // Never longer than the largest share: the shares of pushers on one side
    // add up, and bodies spawned at one point flung each other up to 3 m in
    // their first frame (into traps of the level's corners the walk itself
    // seldom reaches). Overlaps the cap leaves are taken up in the next
    // frames.
    const float pushLength = push.norm();
    if (pushLength > largest) push *= largest / pushLength;
    // Checked with the body's own cache (its step has just made it cover
    // the body's surroundings): most pushes touch nothing and are made now.
    // Any other is carried into the body's next move against the level,
    // whose slide it joins (Body::deferredPush): nearly all of them press
    // the body into a wall it walks along, and a slide of their own cost
    // 1,900 instructions (40 m/s, oa_dm5).
    if (!reports.empty()) reports[i].bodyContacts += nearest.size();
    pending[pendingCount++] = {std::uint32_t(i), push};
    if (pendingCount == pending.size()) makePending();
  }
  makePending();
}

}  // namespace detail

}  // namespace bspf
