// SPDX-License-Identifier: MIT
// bspc/mesh_checks.h: what a cleaned mesh says about mistakes made before
// bspc saw it. Such a mesh compiles; these say why it may not behave.
#pragma once

#include <bspc/mesh.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace bspc {

class SolidEdges;  // edges.h

/// The closed pieces of a mesh: sets of triangles joined by shared edges in
/// which every edge is shared by exactly two triangles, once in each
/// direction (a closed, consistently wound surface, such as a brush).
struct PieceCounts {
  std::uint32_t closedPieces = 0;
  /// Closed pieces whose signed volume is negative: wound clockwise seen from
  /// outside, so their faces point inward and bodies pass into them.
  std::uint32_t insideOutPieces = 0;
  /// Triangles of those pieces.
  std::uint32_t insideOutTriangles = 0;
};

/// Each triangle's closed piece, as PieceCounts defines them.
struct ClosedPieces {
  static constexpr std::uint32_t kOpen = ~std::uint32_t(0);
  /// Per triangle: the index of its closed piece, or kOpen when the set of
  /// triangles joined to it by shared edges is not closed. Pieces are
  /// numbered in the order of their first triangle.
  std::vector<std::uint32_t> pieceOf;
  /// Per closed piece: six times its signed volume, cubic metres (negative:
  /// inside out), and its triangles.
  std::vector<double> volume6;
  std::vector<std::uint32_t> triangleCount;
  /// Per triangle of a closed piece, edge k (corner k to corner k + 1): the
  /// triangle across it, which runs along it the other way. kOpen for the
  /// triangles of open pieces.
  std::vector<std::array<std::uint32_t, 3>> across;
};

/// Finds `mesh`'s closed pieces. Vertices are matched by index, so weld
/// first (cleanMesh). Linear in the mesh's size; deterministic.
ClosedPieces findClosedPieces(const Mesh& mesh);

/// The closed pieces for a given pairing of triangle edges: across[t][k] is
/// the triangle that closes triangle t's edge k (running along it the other
/// way, and paired back to t), or ClosedPieces::kOpen. Triangles are joined
/// across paired edges; a piece is closed when all its edges are paired.
/// findClosedPieces(mesh) pairs by vertex index; solidNeighbours (edges.h)
/// also pairs edges that touching solids share.
ClosedPieces findClosedPieces(const Mesh& mesh, std::vector<std::array<std::uint32_t, 3>> across);

/// Counts `mesh`'s closed pieces and the inside-out ones among them.
/// Vertices are matched by index, so weld first (cleanMesh). Linear in the
/// mesh's size.
PieceCounts countClosedPieces(const Mesh& mesh);

/// A level at most this wide, metres, along its widest axis, or at least
/// kSmallestLikelyLevelMetres, looks like metres; beyond, its unit is likely
/// wrong (centimetres, inches, Quake units without --scale).
inline constexpr double kLargestLikelyLevelMetres = 10000;
inline constexpr double kSmallestLikelyLevelMetres = 1;

/// The warnings for a cleaned mesh, one line each, without the file's name:
/// inside-out closed pieces (with their counts), and a size outside
/// [kSmallestLikelyLevelMetres, kLargestLikelyLevelMetres]. Empty when
/// neither applies.
std::vector<std::string> meshWarnings(const Mesh& clean);
/// The same, from `edges` of the cleaned mesh: its edges grouped once for
/// the face rules and these checks.
std::vector<std::string> meshWarnings(const SolidEdges& edges);

}  // namespace bspc
