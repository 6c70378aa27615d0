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

/// Per-thread scratch for collectCandidateTriangles: remembers which triangles
/// were already listed in the current query. Reusable across worlds.
class SweepScratch {
 public:
  std::vector<std::uint32_t> leaves;

 private:
  friend void collectCandidateTriangles(const World&, const Vec3&, const Vec3&, EllipsoidRadii,
                                        SweepScratch&, std::vector<std::uint32_t>&);
  std::vector<std::uint32_t> stamp_;
  std::uint32_t generation_ = 0;
};

/// Replaces the contents of `trianglesOut` with the triangle indices listed by
/// the leaves collectSweptLeaves returns, each once, in leaf order (the order
/// of first appearance along the path). Every triangle any point of the swept
/// volume touches is among them. Cost: O(visited nodes + listed references);
/// allocates only when `scratch` or `trianglesOut` must grow.
void collectCandidateTriangles(const World& world, const Vec3& from, const Vec3& to,
                               EllipsoidRadii radii, SweepScratch& scratch,
                               std::vector<std::uint32_t>& trianglesOut);

}  // namespace bspf
