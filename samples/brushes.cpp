// SPDX-License-Identifier: MIT
#include "brushes.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace bspf::walkers {

namespace {

// The bounding box of a convex brush from its vertices: every feasible
// intersection point of three of its planes. Empty when there is none.
Eigen::AlignedBox3d vertexBounds(const Brush& brush) {
  Eigen::AlignedBox3d box;  // empty
  const std::size_t n = brush.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      for (std::size_t k = j + 1; k < n; ++k) {
        Eigen::Matrix3d a;
        a.row(0) = brush[i].normal.transpose();
        a.row(1) = brush[j].normal.transpose();
        a.row(2) = brush[k].normal.transpose();
        if (std::abs(a.determinant()) < 1e-9) continue;
        const Eigen::Vector3d b(brush[i].distance, brush[j].distance, brush[k].distance);
        const Eigen::Vector3d v = a.partialPivLu().solve(b);
        if (!v.allFinite()) continue;
        bool feasible = true;
        for (const BrushPlane& plane : brush)
          if (plane.normal.dot(v) > plane.distance + 1e-6 * (1 + std::abs(plane.distance))) {
            feasible = false;
            break;
          }
        if (feasible) box.extend(v);
      }
  return box;
}

}  // namespace

BrushSet::BrushSet(std::vector<Brush> brushes) : brushes_(std::move(brushes)) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const Eigen::AlignedBox3d infinite(Eigen::Vector3d::Constant(-kInf),
                                     Eigen::Vector3d::Constant(kInf));
  bounds_.reserve(brushes_.size());
  gridBounds_.setEmpty();
  for (const Brush& brush : brushes_) {
    Eigen::AlignedBox3d box = brush.size() >= 4 ? vertexBounds(brush) : Eigen::AlignedBox3d();
    if (box.isEmpty()) {
      box = infinite;
    } else {
      // Loose by 1 cm: a box too tight would drop points, one too loose only
      // costs a plane test.
      box.min().array() -= 0.01;
      box.max().array() += 0.01;
      gridBounds_.extend(box);
    }
    bounds_.push_back(box);
  }

  // Cells of about a metre or more, at most 128 along the longest axis.
  if (!gridBounds_.isEmpty()) {
    const Eigen::Vector3d extent = gridBounds_.sizes();
    cellSize_ = std::max(1.0, extent.maxCoeff() / 128);
    for (int a = 0; a < 3; ++a)
      cells_[a] = std::max(1, static_cast<int>(std::ceil(extent[a] / cellSize_)));
  }
  const std::size_t cellCount = std::size_t(cells_.x()) * cells_.y() * cells_.z();
  auto cellRange = [&](const Eigen::AlignedBox3d& box, Eigen::Vector3i& lo, Eigen::Vector3i& hi) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::clamp(
          static_cast<int>(std::floor((box.min()[a] - gridBounds_.min()[a]) / cellSize_)), 0,
          cells_[a] - 1);
      hi[a] = std::clamp(
          static_cast<int>(std::floor((box.max()[a] - gridBounds_.min()[a]) / cellSize_)), 0,
          cells_[a] - 1);
    }
  };
  // Counting pass, then filling pass (compressed rows).
  std::vector<std::uint32_t> counts(cellCount + 1, 0);
  std::vector<bool> gridded(brushes_.size(), false);
  for (std::size_t b = 0; b < brushes_.size(); ++b) {
    if (!std::isfinite(bounds_[b].min().x())) {
      everywhere_.push_back(static_cast<std::uint32_t>(b));
      continue;
    }
    Eigen::Vector3i lo, hi;
    cellRange(bounds_[b], lo, hi);
    const std::size_t spanned =
        std::size_t(hi.x() - lo.x() + 1) * (hi.y() - lo.y() + 1) * (hi.z() - lo.z() + 1);
    if (spanned > 4096) {
      everywhere_.push_back(static_cast<std::uint32_t>(b));
      continue;
    }
    gridded[b] = true;
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z)
          ++counts[(std::size_t(x) * cells_.y() + y) * cells_.z() + z];
  }
  cellStart_.assign(cellCount + 1, 0);
  for (std::size_t c = 0; c < cellCount; ++c) cellStart_[c + 1] = cellStart_[c] + counts[c];
  cellBrushes_.resize(cellStart_[cellCount]);
  std::vector<std::uint32_t> fill(cellStart_.begin(), cellStart_.end() - 1);
  for (std::size_t b = 0; b < brushes_.size(); ++b) {
    if (!gridded[b]) continue;
    Eigen::Vector3i lo, hi;
    cellRange(bounds_[b], lo, hi);
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z)
          cellBrushes_[fill[(std::size_t(x) * cells_.y() + y) * cells_.z() + z]++] =
              static_cast<std::uint32_t>(b);
  }
}

BrushSet BrushSet::load(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open the brush file");
  std::vector<Brush> brushes;
  std::string line;
  int lineNumber = 0;
  while (std::getline(in, line)) {
    ++lineNumber;
    std::istringstream fields(line);
    std::vector<double> values;
    std::string token;
    while (fields >> token) {
      std::size_t used = 0;
      double v = 0;
      try {
        v = std::stod(token, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != token.size() || !std::isfinite(v))
        throw std::runtime_error(path.string() + ": line " + std::to_string(lineNumber) +
                                 ": not a number: '" + token + "'");
      values.push_back(v);
    }
    if (values.empty()) continue;
    if (values.size() % 4 != 0)
      throw std::runtime_error(path.string() + ": line " + std::to_string(lineNumber) + ": " +
                               std::to_string(values.size()) +
                               " numbers, not groups of four (nx ny nz d)");
    Brush brush;
    for (std::size_t i = 0; i < values.size(); i += 4)
      brush.push_back({Eigen::Vector3d(values[i], values[i + 1], values[i + 2]), values[i + 3]});
    brushes.push_back(std::move(brush));
  }
  return BrushSet(std::move(brushes));
}

bool BrushSet::inside(std::size_t brush, const Eigen::Vector3d& p, double margin) const {
  if (!bounds_[brush].contains(p)) return false;
  for (const BrushPlane& plane : brushes_[brush])
    if (!(plane.normal.dot(p) < plane.distance - margin)) return false;
  return true;
}

int BrushSet::findSolid(const Vec3& point, float margin) const {
  const Eigen::Vector3d p = point.cast<double>();
  int found = -1;
  auto consider = [&](std::uint32_t b) {
    if ((found < 0 || int(b) < found) && inside(b, p, margin)) found = int(b);
  };
  for (const std::uint32_t b : everywhere_) consider(b);
  if (!cellStart_.empty() && gridBounds_.contains(p)) {
    Eigen::Vector3i c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(static_cast<int>(std::floor((p[a] - gridBounds_.min()[a]) / cellSize_)), 0,
                        cells_[a] - 1);
    const std::size_t cell = (std::size_t(c.x()) * cells_.y() + c.y()) * cells_.z() + c.z();
    for (std::uint32_t i = cellStart_[cell]; i < cellStart_[cell + 1]; ++i)
      consider(cellBrushes_[i]);
  }
  return found;
}

}  // namespace bspf::walkers
