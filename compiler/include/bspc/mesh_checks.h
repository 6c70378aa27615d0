// SPDX-License-Identifier: MIT
// bspc/mesh_checks.h: what a cleaned mesh says about mistakes made before
// bspc saw it. Such a mesh compiles; these say why it may not behave.
#pragma once

#include <bspc/mesh.h>

#include <cstdint>
#include <string>
#include <vector>

namespace bspc {

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

}  // namespace bspc
