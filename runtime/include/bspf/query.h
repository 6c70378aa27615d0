// SPDX-License-Identifier: MIT
// bspf/query.h: which parts of a level a moving ellipsoid can touch.
//
// Broad phase for the movement step: the BSP leaves whose cells a swept
// ellipsoid overlaps, in the order the path passes them, and the triangles
// those leaves list. Read-only on the World; all scratch belongs to the caller
// (one SweepScratch per thread), so queries run concurrently on one World.
#pragma once

#include <bspf/geometry.h>
#include <bspf/world.h>

#include <cstdint>
#include <span>
#include <vector>

namespace bspf {

/// Extra margin, metres, added to the ellipsoid's extent at every node plane so
/// float rounding never drops a leaf the volume touches. Positions far from the
/// origin get a proportionally larger margin (about 4 ulp of the plane offset).
inline constexpr float kSweepMarginMetres = 1e-4f;

/// Appends to `leavesOut` (not cleared first) the leaf number of every leaf
/// whose cell the ellipsoid with `radii`, swept from centre `from` to centre
/// `to` (metres), may overlap: near side first at each node, which is the order
/// the path passes them. At each node the plane is offset by the ellipsoid's
/// extent along that plane's normal (effectiveRadius), so the test is exact for
/// each half-space and conservative for a cell. No leaf the volume overlaps is
/// missed; a few it does not overlap may be listed. Cost: O(visited nodes), no
/// allocation beyond growing `leavesOut`.
/// Preconditions: finite points, radii > 0.
void collectSweptLeaves(const World& world, const Vec3& from, const Vec3& to, EllipsoidRadii radii,
                        std::vector<std::uint32_t>& leavesOut);

/// The leaf whose cell contains point `p` (metres). A point exactly on a split
/// plane counts as in front of it. Cost: O(tree depth).
std::uint32_t locateLeaf(const World& world, const Vec3& p);

/// Appends to `leavesOut` (not cleared first) every leaf whose cell the
/// axis-aligned box [low, high] (metres) may overlap, near side of each node
/// (the side of the box's centre) first. Conservative like
/// collectSweptLeaves: padded by kSweepMarginMetres at each plane.
/// Cost: O(visited nodes). Preconditions: finite, low <= high per axis.
void collectBoxLeaves(const World& world, const Vec3& low, const Vec3& high,
                      std::vector<std::uint32_t>& leavesOut);

/// A triangle a query found, with its bounding box from the blob (metres).
struct CandidateTriangle {
  std::uint32_t triangle;
  Vec3 low, high;
};

/// Per-thread scratch for the candidate queries: the leaves of the current
/// query and which triangles it already listed. Reusable across worlds.
class SweepScratch {
 public:
  std::vector<std::uint32_t> leaves;

 private:
  friend class CandidateGather;
  std::vector<std::uint32_t> stamp_;
  std::vector<std::uint32_t> kept_;  // a query's leaf entries, as it sifts them
  std::uint32_t generation_ = 0;
};

/// Replaces the contents of `trianglesOut` with the triangles that the
/// leaves collectSweptLeaves returns list and whose bounding box overlaps the
/// swept volume's (padded by kSweepMarginMetres), each once, in leaf order
/// (the order of first appearance along the path). Every triangle any point
/// of the swept volume touches is among them. Cost: O(visited nodes + listed
/// references), each reference a read of its 24-byte box; allocates only
/// when `scratch` or `trianglesOut` must grow.
void collectCandidateTriangles(const World& world, const Vec3& from, const Vec3& to,
                               EllipsoidRadii radii, SweepScratch& scratch,
                               std::vector<std::uint32_t>& trianglesOut);

/// Replaces the contents of `out` with the triangles, each once, in leaf
/// order, whose bounding box overlaps the box [low, high] (metres, padded by
/// kSweepMarginMetres), with their boxes. Every triangle with a point in the
/// box is among them. Cost and allocation as collectCandidateTriangles.
/// Preconditions: finite, low <= high per axis.
void collectBoxCandidates(const World& world, const Vec3& low, const Vec3& high,
                          SweepScratch& scratch, std::vector<CandidateTriangle>& out);

/// The triangles near a moving body, for several queries in a row: one box
/// query, padded, answers every later request for a box inside the one
/// queried (the slides of one step, and the next frames' steps while the
/// body stays inside it: temporal coherence). Reusable across worlds; not
/// shared between threads.
class NearbyTriangles {
 public:
  /// Makes list() hold (at least) every triangle with a point in [low, high]
  /// (metres), as collectBoxCandidates does: one whose bounding box reaches
  /// the box but which has no point in it may be missing. Queries the tree
  /// for [low, high] grown by `pad` metres on every side only when
  /// [low, high] is not inside the box last queried on this `world` (by
  /// World::id()), or when that box is larger than [low, high] by more than
  /// 10 * pad + 0.1 m plus |ahead| along an axis (it would list too much).
  /// `ahead`, metres: a query also reaches this much further along each axis
  /// on the side it points to (where a moving body goes next).
  /// Preconditions: finite, low <= high, pad >= 0.
  void cover(const World& world, const Vec3& low, const Vec3& high, float pad,
             SweepScratch& scratch, const Vec3& ahead = Vec3::Zero());
  /// Whether list() holds (at least) every triangle with a point in
  /// [low, high] (metres) on `world`: the box last queried on `world`
  /// contains [low, high]. Unlike cover(), it accepts a box however much
  /// larger: for a one-off test near a body, reusing the body's list costs
  /// less than a query. Preconditions: finite, low <= high.
  bool holds(const World& world, const Vec3& low, const Vec3& high) const {
    return worldId_ == world.id() && (low.array() >= low_.array()).all() &&
           (high.array() <= high_.array()).all();
  }
  /// Forgets the last query, so the next cover() queries again.
  void clear() { worldId_ = 0; }
  /// The triangles of the last query, in leaf order, with their boxes.
  std::span<const CandidateTriangle> list() const { return list_; }
  /// How many tree queries cover() made since construction (diagnostics).
  std::uint64_t queries() const { return queries_; }
  /// A number naming the last query, unique within the process (0 before
  /// the first), so what was derived from list() can tell it is stale.
  std::uint64_t queryId() const { return queryId_; }

 private:
  std::uint64_t worldId_ = 0;
  Vec3 low_ = Vec3::Zero(), high_ = Vec3::Zero();
  std::vector<CandidateTriangle> list_;
  std::uint64_t queries_ = 0;
  std::uint64_t queryId_ = 0;
};

/// An axis-aligned box, metres.
struct Bounds {
  Vec3 low, high;
};

/// Grows the box [low, high] by the queries' margin: kSweepMarginMetres plus
/// about 4 ulp of the coordinates, as at the tree's planes.
inline void padBounds(Vec3& low, Vec3& high) {
  const Vec3 pad =
      Vec3::Constant(kSweepMarginMetres) + 4e-7f * low.cwiseAbs().cwiseMax(high.cwiseAbs());
  low -= pad;
  high += pad;
}

/// The bounding box of the ellipsoid with `radii` swept from centre `from` to
/// centre `to`, padded like the queries (padBounds), so a triangle whose box
/// misses it cannot touch the swept volume. Inline: the step calls it once
/// per slide iteration.
inline Bounds sweptBounds(const Vec3& from, const Vec3& to, EllipsoidRadii radii) {
  // Three lanes, each in scalar registers: Eigen built a 4-float array from
  // four floats by storing them on the stack and loading them back as one
  // 16-byte value, which cannot be forwarded from the stores and waited for
  // them (two fifths of `touchesNothing`'s samples in perf, walkers).
  const Vec3 extent(radii.xz, radii.y, radii.xz);
  Bounds bounds{from.cwiseMin(to) - extent, from.cwiseMax(to) + extent};
  padBounds(bounds.low, bounds.high);
  return bounds;
}

/// Whether the boxes [aLow, aHigh] and [bLow, bHigh] overlap (touching
/// counts).
inline bool boxesOverlap(const Vec3& aLow, const Vec3& aHigh, const Vec3& bLow, const Vec3& bHigh) {
  return aLow.x() <= bHigh.x() && bLow.x() <= aHigh.x() && aLow.y() <= bHigh.y() &&
         bLow.y() <= aHigh.y() && aLow.z() <= bHigh.z() && bLow.z() <= aHigh.z();
}

}  // namespace bspf
