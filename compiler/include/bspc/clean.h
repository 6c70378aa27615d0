// SPDX-License-Identifier: MIT
// bspc/clean.h: stage 2, make the mesh fit for collision.
#pragma once

#include <bspc/mesh.h>
#include <bspc/settings.h>

#include <cstdint>

namespace bspc {

struct CleanReport {
  std::uint32_t inputVertices = 0;
  std::uint32_t inputTriangles = 0;
  /// Vertices merged into an earlier one within the weld tolerance.
  std::uint32_t weldedVertices = 0;
  /// Triangles whose corners collapsed to fewer than three vertices, or that
  /// are a line to float precision (not bspf::isUsableTriangle).
  std::uint32_t droppedDegenerate = 0;
  /// Triangles below the minimum area (collinear corners, needles).
  std::uint32_t droppedZeroArea = 0;
  /// Repeats of a kept triangle with the same corners and winding. The same
  /// corners with opposite winding are kept: they are the back of a two-sided
  /// surface.
  std::uint32_t droppedDuplicate = 0;
  /// Triangles left out by the surface selection (CleanSettings::
  /// dropSurfaces, onlySurfaces), before any other check.
  std::uint32_t droppedBySurface = 0;
  std::uint32_t outputVertices = 0;
  std::uint32_t outputTriangles = 0;
};

/// Leaves out the triangles of the surfaces the settings drop (or of those
/// they do not keep only), rounds positions to float (as the blob stores
/// them), welds vertices within the tolerance (deterministically: each joins
/// the first earlier vertex in reach), drops degenerate, zero-area and
/// duplicate triangles and unused vertices, and keeps the order of what
/// remains. Each kept triangle keeps its surface; the result's surface table
/// holds the surfaces its triangles use, in the order they first use them
/// (a mesh without surfaces gets one, kDefaultSurface). Throws CompileError
/// when a surface to drop or keep is not one of the mesh's (naming it), a
/// surface index is out of range, there are more than 65536 surfaces, a
/// coordinate is not finite as a float or beyond bspf::kMaxCoordinate, an
/// index is out of range, or no triangle remains.
Mesh cleanMesh(const Mesh& mesh, const CleanSettings& settings, CleanReport& report);

}  // namespace bspc
