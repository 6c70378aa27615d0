// SPDX-License-Identifier: MIT
// bspc/edges.h: the stage between clean and tree: faces no body can meet
// are dropped, and each triangle edge is classified against the whole mesh,
// so the runtime's planes method knows which of a triangle's planes a body
// can meet (docs/algorithm.md, "Ghost edges").
#pragma once

#include <bspc/mesh.h>
#include <bspf/thread_pool.h>

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

namespace bspc {

/// What lies across a triangle edge, seen from the front of the triangle:
/// the first face met turning about the edge from the triangle's front
/// (faces lying on the triangle itself passed over). A face met first that
/// is wound against the triangle (the back of a two-sided surface) counts
/// as convex: its plane is kept.
enum class EdgeKind : std::uint8_t {
  Open,      ///< no other triangle has this edge (matched by welded vertex)
  Convex,    ///< the first face met bends away behind the triangle's plane
  Concave,   ///< it rises in front of the triangle's plane
  Coplanar,  ///< it continues the triangle's plane, facing the same way
};

/// Counts from dropCoveredFaces and classifyEdges.
struct EdgeReport {
  /// Faces dropped for lying against an opposite coincident face of a
  /// solid (touching solids): in front of them is inside that solid.
  std::uint32_t droppedCovered = 0;
  /// Edges of the kept triangles by kind (each triangle's 3 counted).
  std::uint32_t open = 0, convex = 0, concave = 0, coplanar = 0;
  /// Edge planes the planes method skips (meetable bit cleared).
  std::uint32_t skippedEdgePlanes = 0;
};

/// The mesh without the faces that lie against an opposite coincident face
/// belonging to a closed solid (each triangle's area covered, within 0.1 mm,
/// by the union of opposite-facing triangles in its plane whose solid lies
/// in front of it). A face kept whenever that cannot be shown: an open mesh,
/// a two-sided surface (a triangle pair with the same corners, as curved
/// patches are exported) or a solid whose neighbours do not match keeps
/// every face. Deterministic: the order of the kept triangles is the input
/// order. Precondition: a cleaned mesh (welded, no degenerate triangle).
Mesh dropCoveredFaces(const Mesh& mesh, EdgeReport& report);

/// A cleaned mesh's triangle edges, grouped by their pair of vertices, and
/// for each triangle edge the face first met turning about it from the
/// triangle's back: what findCoveredFaces and solidNeighbours (so
/// findBuriedFaces) both work from, found once for both. Refers to `mesh`,
/// which must outlive it. With a pool, the per-triangle work is shared
/// between its threads (the same result on any number).
class SolidEdges {
 public:
  explicit SolidEdges(const Mesh& mesh, bspf::ThreadPool* pool = nullptr);
  SolidEdges(const SolidEdges&) = delete;
  SolidEdges& operator=(const SolidEdges&) = delete;
  ~SolidEdges();
  const Mesh& mesh() const;
  /// What it holds: private to edges.cpp.
  struct Parts;
  const Parts& parts() const { return *parts_; }

 private:
  std::unique_ptr<const Parts> parts_;
};

/// Per triangle: whether dropCoveredFaces drops it.
std::vector<bool> findCoveredFaces(const Mesh& mesh);
/// The same, from `edges` of the mesh (shared with solidNeighbours). With a
/// pool, the faces are shared between its threads (the same result on any
/// number).
std::vector<bool> findCoveredFaces(const SolidEdges& edges, bspf::ThreadPool* pool = nullptr);

/// Per triangle, edge k (corner k to corner k + 1): the triangle across it
/// that closes the same solid, or ~0u. Across an edge of two triangles, the
/// other one; across an edge more share (solids touching along it), the
/// first face met turning about the edge from the triangle's back, into its
/// solid. Either way only when it runs along the edge the other way and
/// chooses the triangle back, so pieces joined across these pairs are
/// closed surfaces (findClosedPieces in mesh_checks.h). Precondition: a
/// cleaned mesh.
std::vector<std::array<std::uint32_t, 3>> solidNeighbours(const Mesh& mesh);
/// The same, from `edges` of the mesh (shared with findCoveredFaces).
std::vector<std::array<std::uint32_t, 3>> solidNeighbours(const SolidEdges& edges);

/// Per triangle, edge k: the other triangle when exactly two share the edge
/// and they run along it opposite ways, or ~0u: the pairing by
/// vertex index that findClosedPieces(mesh) (mesh_checks.h) makes, from the
/// edges already grouped for the face rules.
std::vector<std::array<std::uint32_t, 3>> pairedNeighbours(const SolidEdges& edges);

/// A triangle's three edges (edge k from corner k to corner k + 1).
struct TriangleEdges {
  std::array<EdgeKind, 3> kind{};
  /// Coplanar edges only: the neighbour is the triangle turned half a turn
  /// about the edge's midpoint (the two make a parallelogram, as a quad's
  /// two triangles do), within 0.1 mm.
  std::array<bool, 3> mirrored{};
};

/// Classifies every triangle's edges against the whole mesh. With a pool,
/// the triangles are shared between its threads (the same result on any
/// number).
std::vector<TriangleEdges> classifyEdges(const Mesh& mesh, bspf::ThreadPool* pool = nullptr);

/// Bit k (0-2): edge plane k can be met; bit 3 + k: cap k can be met. The
/// planes method treats a cleared plane as always holding. With
/// `skipMirrored`, the edge plane of a mirrored coplanar edge is cleared
/// (the region it adds is the neighbour's own but for the neighbour's far
/// corner, which then loses its cap's bevel); otherwise, as bspc compiles,
/// every plane is kept: skipping planes only adds contacts, and on the
/// shared levels it added refused moves (docs/algorithm.md). Caps are always
/// kept. Adds to `report`'s edge counts.
std::vector<std::uint8_t> meetablePlanes(const std::vector<TriangleEdges>& edges,
                                         EdgeReport& report, bool skipMirrored = false);

}  // namespace bspc
