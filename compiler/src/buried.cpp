// SPDX-License-Identifier: MIT
#include <bspc/buried.h>
#include <bspc/edges.h>
#include <bspc/mesh_checks.h>

#include <algorithm>
#include <numeric>

#include "parallel.h"

namespace bspc {

namespace {

using V3 = Eigen::Vector3d;

// An edge whose neighbour's far corner rises less than this above the
// triangle's plane, metres, still counts as convex: the test below does not
// rely on convexity (see findBuriedFaces), which only keeps out pieces whose
// volume almost no point lies behind every face of.
constexpr double kConvexTolerance = 1e-4;

struct Plane {
  V3 normal;  // unit, pointing out of the piece
  double offset;
};

// The pieces that can hold a buried face, each with the planes of its
// triangles, and a bounding-volume tree over their boxes.
class Containers {
 public:
  Containers(const Mesh& mesh, const ClosedPieces& pieces) {
    const std::size_t n = mesh.triangles.size(), count = pieces.volume6.size();
    // The triangles of each piece, in order (a counting sort).
    std::vector<std::uint32_t> start(count + 1, 0);
    for (std::uint32_t t = 0; t < n; ++t)
      if (pieces.pieceOf[t] != ClosedPieces::kOpen) ++start[pieces.pieceOf[t] + 1];
    std::partial_sum(start.begin(), start.end(), start.begin());
    std::vector<std::uint32_t> byPiece(start.back()), next(start.begin(), start.end() - 1);
    for (std::uint32_t t = 0; t < n; ++t)
      if (pieces.pieceOf[t] != ClosedPieces::kOpen) byPiece[next[pieces.pieceOf[t]]++] = t;

    for (std::uint32_t p = 0; p < count; ++p) {
      if (!(pieces.volume6[p] > 0)) continue;
      const std::size_t firstPlane = planes_.size();
      Eigen::AlignedBox3d box;
      bool convex = true;
      for (std::uint32_t i = start[p]; i < start[p + 1] && convex; ++i) {
        const std::uint32_t t = byPiece[i];
        const auto& tri = mesh.triangles[t];
        const V3& a = mesh.vertices[tri[0]];
        const V3 normal = (mesh.vertices[tri[1]] - a).cross(mesh.vertices[tri[2]] - a).normalized();
        if (!normal.allFinite()) {
          convex = false;
          break;
        }
        for (int k = 0; k < 3; ++k) {
          box.extend(mesh.vertices[tri[k]]);
          const auto& across = mesh.triangles[pieces.across[t][k]];
          for (const std::uint32_t corner : across)
            if (corner != tri[k] && corner != tri[(k + 1) % 3] &&
                normal.dot(mesh.vertices[corner] - a) > kConvexTolerance)
              convex = false;
        }
        planes_.push_back({normal, normal.dot(a)});
      }
      if (!convex) {
        planes_.resize(firstPlane);
        continue;
      }
      pieces_.push_back({box, p, static_cast<std::uint32_t>(firstPlane),
                         static_cast<std::uint32_t>(planes_.size())});
    }
    order_.resize(pieces_.size());
    std::iota(order_.begin(), order_.end(), std::uint32_t{0});
    if (!pieces_.empty()) build(0, static_cast<std::uint32_t>(order_.size()));
  }

  std::size_t size() const { return pieces_.size(); }

  // Whether the triangle with these corners, of closed piece `own` (or
  // kOpen), lies at least kBuriedMargin behind every plane of one container
  // other than its own piece.
  bool buries(const std::array<V3, 3>& corners, std::uint32_t own) const {
    if (nodes_.empty()) return false;
    Eigen::AlignedBox3d wanted;
    for (const V3& corner : corners) wanted.extend(corner);
    wanted.min().array() -= kBuriedMargin;
    wanted.max().array() += kBuriedMargin;
    std::uint32_t stack[64];
    int depth = 0;
    stack[depth++] = 0;
    while (depth > 0) {
      const Node& node = nodes_[stack[--depth]];
      if (!node.box.contains(wanted)) continue;
      if (node.count > 0) {
        for (std::uint32_t i = node.first; i < node.first + node.count; ++i) {
          const Piece& piece = pieces_[order_[i]];
          if (piece.piece != own && piece.box.contains(wanted) && behindAll(piece, corners))
            return true;
        }
        continue;
      }
      stack[depth++] = node.first;
      stack[depth++] = node.first + 1;
    }
    return false;
  }

 private:
  static constexpr std::uint32_t kLeafPieces = 4;

  struct Piece {
    Eigen::AlignedBox3d box;
    std::uint32_t piece;  // in ClosedPieces
    std::uint32_t firstPlane, lastPlane;
  };
  // A leaf (count > 0) holds order_[first, first + count); an inner node's
  // children are nodes_[first] and nodes_[first + 1].
  struct Node {
    Eigen::AlignedBox3d box;
    std::uint32_t first = 0, count = 0;
  };

  bool behindAll(const Piece& piece, const std::array<V3, 3>& corners) const {
    for (std::uint32_t i = piece.firstPlane; i < piece.lastPlane; ++i) {
      const Plane& plane = planes_[i];
      for (const V3& corner : corners)
        if (plane.normal.dot(corner) - plane.offset > -kBuriedMargin) return false;
    }
    return true;
  }

  // Median splits along the widest axis of the boxes' centres; the tree's
  // depth is about log2 of the pieces, far under the query's stack.
  void build(std::uint32_t first, std::uint32_t last) {
    const std::size_t self = nodes_.size();
    nodes_.push_back({});
    struct Frame {
      std::size_t node;
      std::uint32_t first, last;
    };
    std::vector<Frame> pending{{self, first, last}};
    while (!pending.empty()) {
      const Frame frame = pending.back();
      pending.pop_back();
      Eigen::AlignedBox3d box, centres;
      for (std::uint32_t i = frame.first; i < frame.last; ++i) {
        box.extend(pieces_[order_[i]].box);
        centres.extend(pieces_[order_[i]].box.center());
      }
      nodes_[frame.node].box = box;
      if (frame.last - frame.first <= kLeafPieces) {
        nodes_[frame.node].first = frame.first;
        nodes_[frame.node].count = frame.last - frame.first;
        continue;
      }
      int axis = 0;
      centres.sizes().maxCoeff(&axis);
      const std::uint32_t middle = frame.first + (frame.last - frame.first) / 2;
      // Ties broken by index: the same tree whatever the library's sort.
      std::nth_element(order_.begin() + frame.first, order_.begin() + middle,
                       order_.begin() + frame.last, [&](std::uint32_t x, std::uint32_t y) {
                         const double cx = pieces_[x].box.center()[axis],
                                      cy = pieces_[y].box.center()[axis];
                         return cx < cy || (cx == cy && x < y);
                       });
      const std::size_t children = nodes_.size();
      nodes_.push_back({});
      nodes_.push_back({});
      nodes_[frame.node].first = static_cast<std::uint32_t>(children);
      pending.push_back({children, frame.first, middle});
      pending.push_back({children + 1, middle, frame.last});
    }
  }

  std::vector<Plane> planes_;
  std::vector<Piece> pieces_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

}  // namespace

// Why the test is sound whatever the shape of B: a point behind the plane of
// every triangle of a closed, consistently wound surface sees each triangle
// from behind, so each adds a positive solid angle to the surface's winding
// number about the point; that number is a whole number, so it is at least
// 1, and a body coming from where it is 0 (far away) would have to cross the
// surface to reach the point. Convexity only picks the pieces worth trying.
std::vector<bool> findBuriedFaces(const Mesh& mesh, BuriedReport& report, bspf::ThreadPool* pool) {
  return findBuriedFaces(SolidEdges(mesh), report, pool);
}

std::vector<bool> findBuriedFaces(const SolidEdges& edges, BuriedReport& report,
                                  bspf::ThreadPool* pool) {
  const Mesh& mesh = edges.mesh();
  const std::size_t n = mesh.triangles.size();
  const ClosedPieces pieces = findClosedPieces(mesh, solidNeighbours(edges));
  const Containers containers(mesh, pieces);
  report.closedPieces = static_cast<std::uint32_t>(pieces.volume6.size());
  report.containers = static_cast<std::uint32_t>(containers.size());
  // Bytes, not vector<bool>'s bits: threads write neighbouring triangles.
  std::vector<std::uint8_t> buried(n, 0);
  const auto range = [&](int, std::size_t first, std::size_t last) {
    for (std::size_t t = first; t < last; ++t) {
      if (pieces.pieceOf[t] == ClosedPieces::kOpen) continue;
      const auto& tri = mesh.triangles[t];
      buried[t] = containers.buries(
          {mesh.vertices[tri[0]], mesh.vertices[tri[1]], mesh.vertices[tri[2]]}, pieces.pieceOf[t]);
    }
  };
  if (containers.size() > 0) runParallel(pool, n, 256, range);
  std::vector<bool> out(n);
  for (std::size_t t = 0; t < n; ++t) {
    out[t] = buried[t] != 0;
    report.buried += buried[t];
  }
  return out;
}

}  // namespace bspc
