// SPDX-License-Identifier: MIT
#include <bspc/build_tree.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>

namespace bspc {

namespace {

// A candidate split as the blob will store it: float, so the build classifies
// triangles against exactly the plane the runtime reads.
struct Split {
  Eigen::Vector3f normal;
  float distance;
};

// The axis-aligned box around a node's cell (conservative for oblique splits).
struct Box {
  Eigen::Vector3d low, high;

  // The box around the part of this box on one side of a plane.
  Box clipped(const Split& split, bool keepFront) const {
    const Eigen::Vector3d n = split.normal.cast<double>();
    const double sign = keepFront ? 1.0 : -1.0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
    Eigen::Vector3d hi = -lo;
    auto corner = [&](int i) {
      return Eigen::Vector3d(i & 1 ? high.x() : low.x(), i & 2 ? high.y() : low.y(),
                             i & 4 ? high.z() : low.z());
    };
    auto add = [&](const Eigen::Vector3d& p) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    };
    double side[8];
    for (int i = 0; i < 8; ++i) {
      side[i] = sign * (n.dot(corner(i)) - split.distance);
      if (side[i] >= 0) add(corner(i));
    }
    for (int i = 0; i < 8; ++i)
      for (int axis = 0; axis < 3; ++axis) {
        const int j = i | (1 << axis);
        if (j == i || (side[i] >= 0) == (side[j] >= 0)) continue;
        const double t = side[i] / (side[i] - side[j]);
        add(corner(i) + t * (corner(j) - corner(i)));
      }
    if (!(lo.array() <= hi.array()).all()) return {low, low};  // nothing on that side
    return {lo, hi};
  }

  // How likely a query of the given reach overlaps the box, up to a constant:
  // the volume of the box grown by the reach on every side.
  double reachVolume(double reach) const {
    const Eigen::Vector3d size = (high - low).array() + 2 * reach;
    return size.x() * size.y() * size.z();
  }
};

enum Side : std::uint8_t { kFront = 1, kBack = 2, kBoth = kFront | kBack };

// How far, metres, a corner may sit off a plane and still count as on it.
// Grows with the plane's offset, as float rounding of the plane does.
double onPlaneTolerance(const Split& split) { return 1e-5 + 2e-7 * std::abs(split.distance); }

class TreeBuilder {
 public:
  TreeBuilder(const Mesh& mesh, const TreeSettings& settings,
              const std::function<void(std::string_view)>& progress)
      : mesh_(mesh), settings_(settings), progress_(progress) {
    faceNormals_.reserve(mesh.triangles.size());
    centroids_.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]],
                            &c = mesh.vertices[t[2]];
      faceNormals_.push_back((b - a).cross(c - a).normalized());
      centroids_.push_back((a + b + c) / 3.0);
    }
  }

  BspTree build() {
    std::vector<std::uint32_t> all(mesh_.triangles.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all[i] = i;
    Box bounds{mesh_.vertices.front(), mesh_.vertices.front()};
    for (const Eigen::Vector3d& v : mesh_.vertices) {
      bounds.low = bounds.low.cwiseMin(v);
      bounds.high = bounds.high.cwiseMax(v);
    }
    tree_.root = buildNode(all, bounds, 0);
    return std::move(tree_);
  }

 private:
  Side classify(std::uint32_t triangle, const Split& split) const {
    const Eigen::Vector3d n = split.normal.cast<double>();
    const double d = split.distance;
    const double tolerance = onPlaneTolerance(split);
    double lowest = std::numeric_limits<double>::infinity();
    double highest = -lowest;
    for (const std::uint32_t v : mesh_.triangles[triangle]) {
      const double s = n.dot(mesh_.vertices[v]) - d;
      lowest = std::min(lowest, s);
      highest = std::max(highest, s);
    }
    if (highest <= tolerance && lowest >= -tolerance)  // lies in the plane
      return faceNormals_[triangle].dot(n) >= 0 ? kFront : kBack;
    // Conservative: a corner within the tolerance of a side counts as reaching it.
    const bool front = highest > -tolerance;
    const bool back = lowest < tolerance;
    return front && back ? kBoth : (front ? kFront : kBack);
  }

  std::vector<Split> candidates(const std::vector<std::uint32_t>& triangles) const {
    std::vector<Split> out;
    const auto n = triangles.size();
    if (settings_.candidates != SplitCandidates::Triangle) {
      std::vector<double> coordinate(n);
      const std::uint32_t quantiles = settings_.axisCandidatesPerAxis;
      for (int axis = 0; axis < 3; ++axis) {
        for (std::size_t i = 0; i < n; ++i) coordinate[i] = centroids_[triangles[i]][axis];
        std::sort(coordinate.begin(), coordinate.end());
        float previous = std::numeric_limits<float>::quiet_NaN();
        for (std::uint32_t q = 1; q <= quantiles; ++q) {
          const float at = static_cast<float>(coordinate[q * n / (quantiles + 1)]);
          if (at == previous) continue;
          previous = at;
          out.push_back({Eigen::Vector3f::Unit(axis), at});
        }
      }
    }
    if (settings_.candidates != SplitCandidates::Axis) {
      const std::size_t step = std::max<std::size_t>(1, n / settings_.triangleCandidates);
      for (std::size_t i = 0; i < n; i += step) {
        const std::uint32_t t = triangles[i];
        const Eigen::Vector3f normal = faceNormals_[t].cast<float>();
        const auto distance =
            static_cast<float>(normal.cast<double>().dot(mesh_.vertices[mesh_.triangles[t][0]]));
        out.push_back({normal, distance});
      }
    }
    return out;
  }

  // The best-scoring split among those that make progress on both sides and
  // pay for themselves: its expected query cost (one node test plus the triangles of each
  // child, weighted by how likely a query reaches the child's cell) is below
  // the leaf's (all its triangles). When none pays at the query reach and
  // the node has more than kDenseNodeTriangles, the same at a reach of at
  // most a quarter of its cell's longest side: a cell much smaller than the
  // query reach is seen whole by every query that reaches it, so at that
  // reach no split of a dense cluster of tiny triangles pays (its
  // straddlers outweigh the gain), and such leaves grew to thousands of
  // triangles. At the cell's own scale a split pays unless it lists most
  // triangles on both sides.
  std::optional<Split> chooseSplit(const std::vector<std::uint32_t>& triangles,
                                   const Box& cell) const {
    // The candidates that make progress on both sides, with their counts.
    struct Counted {
      Split split;
      double frontTotal, backTotal, both;
    };
    std::vector<Counted> counted;
    for (const Split& split : candidates(triangles)) {
      std::size_t front = 0, back = 0, both = 0;
      for (const std::uint32_t t : triangles) {
        switch (classify(t, split)) {
          case kFront: ++front; break;
          case kBack: ++back; break;
          case kBoth: ++both; break;
        }
      }
      if (front + both == triangles.size() || back + both == triangles.size()) continue;
      counted.push_back({split, double(front + both), double(back + both), double(both)});
    }
    const double n = static_cast<double>(triangles.size());
    auto best = [&](double reach) {
      std::optional<Split> chosen;
      double bestScore = std::numeric_limits<double>::infinity();
      for (const Counted& c : counted) {
        if (splitCost(cell, c.split, c.frontTotal, c.backTotal, reach) >= n) continue;
        const double score = settings_.balanceWeight * std::abs(c.frontTotal - c.backTotal) / n +
                             settings_.splitWeight * c.both / n;
        if (score < bestScore) {
          bestScore = score;
          chosen = c.split;
        }
      }
      return chosen;
    };
    std::optional<Split> chosen = best(settings_.queryReach);
    if (!chosen && triangles.size() > kDenseNodeTriangles)
      chosen = best(std::min(settings_.queryReach, 0.25 * (cell.high - cell.low).maxCoeff()));
    return chosen;
  }

  double splitCost(const Box& cell, const Split& split, double frontTotal, double backTotal,
                   double reach) const {
    const double whole = cell.reachVolume(reach);
    return 1.0 + (cell.clipped(split, true).reachVolume(reach) * frontTotal +
                  cell.clipped(split, false).reachVolume(reach) * backTotal) /
                     whole;
  }

  std::int32_t makeLeaf(std::vector<std::uint32_t>& triangles, std::uint32_t depth) {
    std::sort(triangles.begin(), triangles.end());
    const auto first = static_cast<std::uint32_t>(tree_.leafTriangles.size());
    tree_.leafTriangles.insert(tree_.leafTriangles.end(), triangles.begin(), triangles.end());
    tree_.leaves.emplace_back(first, static_cast<std::uint32_t>(triangles.size()));
    tree_.depth = std::max(tree_.depth, depth);
    if (progress_ && tree_.leaves.size() % 4096 == 0)
      progress_("build tree: " + std::to_string(tree_.leaves.size()) + " leaves");
    return -static_cast<std::int32_t>(tree_.leaves.size());
  }

  std::int32_t buildNode(std::vector<std::uint32_t>& triangles, const Box& cell,
                         std::uint32_t depth) {
    if (triangles.size() <= settings_.maxLeafTriangles || depth >= settings_.maxDepth)
      return makeLeaf(triangles, depth);
    const std::optional<Split> split = chooseSplit(triangles, cell);
    if (!split) return makeLeaf(triangles, depth);

    std::vector<std::uint32_t> front, back;
    for (const std::uint32_t t : triangles) {
      const Side side = classify(t, *split);
      if (side & kFront) front.push_back(t);
      if (side & kBack) back.push_back(t);
    }
    triangles.clear();
    triangles.shrink_to_fit();

    const auto index = static_cast<std::int32_t>(tree_.nodes.size());
    tree_.nodes.emplace_back();
    const std::int32_t frontChild = buildNode(front, cell.clipped(*split, true), depth + 1);
    const std::int32_t backChild = buildNode(back, cell.clipped(*split, false), depth + 1);
    const bspf::schema::Plane plane(
        bspf::schema::Vec3(split->normal.x(), split->normal.y(), split->normal.z()),
        split->distance);
    tree_.nodes[index] = bspf::schema::Node(plane, frontChild, backChild);
    return index;
  }

  const Mesh& mesh_;
  const TreeSettings& settings_;
  const std::function<void(std::string_view)>& progress_;
  std::vector<Eigen::Vector3d> faceNormals_;
  std::vector<Eigen::Vector3d> centroids_;
  BspTree tree_;
};

}  // namespace

BspTree buildTree(const Mesh& mesh, const TreeSettings& settings,
                  const std::function<void(std::string_view)>& progress) {
  return TreeBuilder(mesh, settings, progress).build();
}

}  // namespace bspc
