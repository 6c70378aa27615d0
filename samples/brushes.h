// SPDX-License-Identifier: MIT
// brushes.h: the brush oracle, the solids of a level as convex sets of planes
// (the `.brushes.txt` files beside the sample and shared levels), answering
// whether a point lies strictly inside any of them. Used by the `walkers`
// sample (--brushes) and by its tests; needs the runtime's Vec3 and Eigen only.
//
// File format: one brush a line, groups of four numbers `nx ny nz d` with a
// unit normal pointing out; p is inside the brush when n·p < d for every
// plane of the line. Blank lines are skipped.
#pragma once

#include <bspf/geometry.h>

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <vector>

namespace bspf::walkers {

/// One plane of a brush: the brush lies where normal·p < distance.
struct BrushPlane {
  Eigen::Vector3d normal;
  double distance = 0;
};

using Brush = std::vector<BrushPlane>;

/// A set of convex brushes with a uniform-grid index over their bounding
/// boxes (each box from the brush's vertices, the feasible intersections of
/// plane triples). A brush with fewer than four planes or no vertex is taken
/// as unbounded and tested for every point.
class BrushSet {
 public:
  BrushSet() = default;
  explicit BrushSet(std::vector<Brush> brushes);

  /// Reads a `.brushes.txt` file. Throws std::runtime_error naming the file
  /// and line when it cannot be read or a line is not groups of four numbers.
  static BrushSet load(const std::filesystem::path& path);

  /// Whether p lies inside some brush by more than `margin` metres:
  /// n·p < d - margin for every plane of that brush. A margin > 0 ignores
  /// points touching a face within float noise.
  bool insideAnySolid(const Vec3& p, float margin) const { return findSolid(p, margin) >= 0; }

  /// The index (line number from 0, blank lines not counted) of the first
  /// brush holding p as insideAnySolid does, or -1.
  int findSolid(const Vec3& p, float margin) const;

  std::size_t size() const { return brushes_.size(); }
  const Brush& brush(std::size_t i) const { return brushes_[i]; }
  /// The bounding box of brush i (infinite for an unbounded one).
  const Eigen::AlignedBox3d& bounds(std::size_t i) const { return bounds_[i]; }

 private:
  bool inside(std::size_t brush, const Eigen::Vector3d& p, double margin) const;

  std::vector<Brush> brushes_;
  std::vector<Eigen::AlignedBox3d> bounds_;
  // Grid over the union of the finite boxes: cell c lists the brushes
  // cellBrushes_[cellStart_[c] .. cellStart_[c + 1]).
  Eigen::AlignedBox3d gridBounds_;
  Eigen::Vector3i cells_ = Eigen::Vector3i::Zero();
  double cellSize_ = 1;
  std::vector<std::uint32_t> cellStart_;
  std::vector<std::uint32_t> cellBrushes_;
  // Brushes tested for every point: unbounded, or spanning many cells.
  std::vector<std::uint32_t> everywhere_;
};

}  // namespace bspf::walkers
