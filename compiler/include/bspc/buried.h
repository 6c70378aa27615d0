// SPDX-License-Identifier: MIT
// bspc/buried.h: the stage that finds the faces buried inside another closed
// solid (a brush sunk into a wall, a pillar's foot inside the floor's slab),
// which no body outside the solids can touch (docs/algorithm.md, "Faces no
// body can touch").
#pragma once

#include <bspc/edges.h>
#include <bspc/mesh.h>
#include <bspf/thread_pool.h>

#include <cstdint>
#include <vector>

namespace bspc {

/// How far inside a solid, metres, every corner of a face must lie for the
/// face to count as buried: a face touching the solid's surface, or within
/// this of it, is kept, and the rounding of the blob's float corners (6e-5 m
/// a kilometre from the origin) cannot bring a kept solid's surface onto it.
inline constexpr double kBuriedMargin = 1e-3;

/// What findBuriedFaces saw.
struct BuriedReport {
  /// Closed, consistently wound pieces of the mesh: triangles joined across
  /// their edges as solidNeighbours (edges.h) pairs them, so solids
  /// touching along an edge are pieces of their own.
  std::uint32_t closedPieces = 0;
  /// Those that can hold a buried face: positive volume, every edge convex.
  std::uint32_t containers = 0;
  /// Triangles buried, whatever else drops them.
  std::uint32_t buried = 0;
  /// Of those, the ones only this rule drops (the compile's count: a face
  /// also covered is counted by the covered rule, EdgeReport).
  std::uint32_t dropped = 0;
};

/// Per triangle of `mesh`: whether it belongs to a closed piece A and lies
/// inside the volume of another closed piece B, each of its corners at least
/// kBuriedMargin behind the plane of every triangle of B. B must have
/// positive volume and every edge convex (within 0.1 mm); pieces that are
/// open, inside out or not convex hold nothing, and the triangles of open
/// pieces are never buried. A face is kept whenever the test cannot decide.
/// Precondition: a cleaned mesh (welded: pieces are joined by shared vertex
/// indices, so a triangle soup must be welded first; no degenerate
/// triangle).
/// With a pool, the triangles are shared between its threads; the result is
/// the same on any number of threads. O(n log n) for a mesh of brushes.
std::vector<bool> findBuriedFaces(const Mesh& mesh, BuriedReport& report,
                                  bspf::ThreadPool* pool = nullptr);
/// The same for edges.mesh(), from edges found once for this and
/// findCoveredFaces.
std::vector<bool> findBuriedFaces(const SolidEdges& edges, BuriedReport& report,
                                  bspf::ThreadPool* pool = nullptr);

}  // namespace bspc
