// SPDX-License-Identifier: MIT
// bspc/reach.h: the stage that drops the faces no body can touch, found by
// flooding the level's free space from points a body can be at.
#pragma once

#include <bspc/mesh.h>
#include <bspc/settings.h>
#include <bspf/thread_pool.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace bspc {

/// What dropUnreachableFaces did.
struct ReachReport {
  bool applied = false;  ///< false: the rule was off or the level too large
  std::uint64_t dropped = 0;
  std::uint64_t cells = 0;    ///< in the grid
  std::uint64_t reached = 0;  ///< cells the flood reached
  double cellMetres = 0;
  /// The flood reached the grid's border: the level is open (or a point is
  /// outside it), so faces seen from outside are kept.
  bool leaked = false;
};

/// Reads `--reach-from` points: one "x y z" a line, metres; blank lines and
/// lines starting with '#' are skipped. Throws CompileError naming the file
/// and line of the first malformed or non-finite line, or an empty file.
std::vector<Eigen::Vector3d> readReachPoints(const std::filesystem::path& file);

/// The reach stage: `mesh` without the triangles that no body of the given
/// radii, moving anywhere it can go from settings.from without passing
/// through a triangle, can touch; the others keep their order. Conservative:
/// where the grid cannot tell, a face is kept (see docs/algorithm.md,
/// "Faces no body can touch"). Returns `mesh` unchanged when settings.from
/// is empty, and with a warning in `warnings` when the grid would be too
/// large. Throws CompileError when a point is outside the mesh's bounds or
/// within a body's size of a triangle (it is not a place a body can be).
/// With a pool, the passes over the triangles are shared between its
/// threads (the flood runs on this one); the result is the same on any
/// number of threads. Deterministic; O(cells + the cells near each
/// triangle).
Mesh dropUnreachableFaces(const Mesh& mesh, const ReachSettings& settings, ReachReport& report,
                          std::vector<std::string>& warnings, bspf::ThreadPool* pool = nullptr);

}  // namespace bspc
