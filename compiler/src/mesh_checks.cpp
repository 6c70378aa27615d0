// SPDX-License-Identifier: MIT
#include <bspc/edges.h>
#include <bspc/mesh_checks.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <span>
#include <sstream>

namespace bspc {

namespace {

// Union-find over triangles, with path halving.
class Pieces {
 public:
  explicit Pieces(std::size_t count) : parent_(count) {
    std::iota(parent_.begin(), parent_.end(), std::uint32_t{0});
  }
  std::uint32_t find(std::uint32_t t) {
    while (parent_[t] != t) t = parent_[t] = parent_[parent_[t]];
    return t;
  }
  void join(std::uint32_t a, std::uint32_t b) {
    a = find(a), b = find(b);
    if (a != b) parent_[std::max(a, b)] = std::min(a, b);
  }

 private:
  std::vector<std::uint32_t> parent_;
};

// Every directed triangle edge, by its first vertex (a counting sort), then
// its second, then triangle: a few bytes an edge, and no hashing.
class DirectedEdges {
 public:
  struct Use {
    std::uint32_t to, triangle;
  };

  explicit DirectedEdges(const Mesh& mesh) {
    std::uint32_t vertexCount = 0;
    for (const auto& tri : mesh.triangles)
      for (const std::uint32_t v : tri) vertexCount = std::max(vertexCount, v + 1);
    start_.assign(std::size_t(vertexCount) + 1, 0);
    for (const auto& tri : mesh.triangles)
      for (const std::uint32_t v : tri) ++start_[v + 1];
    std::partial_sum(start_.begin(), start_.end(), start_.begin());
    uses_.resize(start_.back());
    std::vector<std::size_t> next(start_.begin(), start_.end() - 1);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        uses_[next[mesh.triangles[t][k]]++] = {mesh.triangles[t][(k + 1) % 3], t};
    for (std::uint32_t v = 0; v < vertexCount; ++v)
      std::sort(uses_.begin() + start_[v], uses_.begin() + start_[v + 1],
                [](const Use& x, const Use& y) {
                  return x.to < y.to || (x.to == y.to && x.triangle < y.triangle);
                });
  }

  // The uses of edge from -> to, in triangle order.
  std::span<const Use> uses(std::uint32_t from, std::uint32_t to) const {
    if (std::size_t(from) + 1 >= start_.size()) return {};
    const auto first = uses_.begin() + start_[from], last = uses_.begin() + start_[from + 1];
    const auto [low, high] = std::equal_range(
        first, last, Use{to, 0}, [](const Use& x, const Use& y) { return x.to < y.to; });
    return {low, high};
  }

 private:
  std::vector<std::size_t> start_;
  std::vector<Use> uses_;
};

}  // namespace

ClosedPieces findClosedPieces(const Mesh& mesh) {
  const std::size_t n = mesh.triangles.size();
  const DirectedEdges edges(mesh);
  // An edge pairs two triangles when it is used once in each direction.
  std::vector<std::array<std::uint32_t, 3>> across(
      n, {ClosedPieces::kOpen, ClosedPieces::kOpen, ClosedPieces::kOpen});
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      const auto reverse = edges.uses(b, a);
      if (reverse.size() == 1 && edges.uses(a, b).size() == 1)
        across[t][k] = reverse.front().triangle;
    }
  return findClosedPieces(mesh, std::move(across));
}

ClosedPieces findClosedPieces(const Mesh& mesh, std::vector<std::array<std::uint32_t, 3>> across) {
  const std::size_t n = mesh.triangles.size();
  // Joined across each paired edge; a piece is open when one of its edges
  // is not paired.
  Pieces pieces(n);
  std::vector<bool> open(n, false);
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      if (across[t][k] == ClosedPieces::kOpen)
        open[t] = true;
      else
        pieces.join(t, across[t][k]);
    }
  // Per piece: open or not, signed volume (six times it, about the piece's
  // first corner, so a level far from the origin loses no precision), size.
  // Roots are pieces' lowest triangles, so numbering them in order of their
  // root numbers them in order of first triangle.
  struct Piece {
    bool open = false;
    double volume6 = 0;
    std::uint32_t triangles = 0;
  };
  std::vector<Piece> byRoot(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    const std::uint32_t root = pieces.find(t);
    Piece& piece = byRoot[root];
    const Eigen::Vector3d& origin = mesh.vertices[mesh.triangles[root][0]];
    const Eigen::Vector3d a = mesh.vertices[tri[0]] - origin, b = mesh.vertices[tri[1]] - origin,
                          c = mesh.vertices[tri[2]] - origin;
    piece.volume6 += a.dot(b.cross(c));
    piece.open = piece.open || open[t];
    ++piece.triangles;
  }
  ClosedPieces out;
  std::vector<std::uint32_t> index(n, ClosedPieces::kOpen);
  for (std::uint32_t t = 0; t < n; ++t) {
    const Piece& piece = byRoot[t];
    if (piece.triangles == 0 || piece.open) continue;
    index[t] = static_cast<std::uint32_t>(out.volume6.size());
    out.volume6.push_back(piece.volume6);
    out.triangleCount.push_back(piece.triangles);
  }
  out.pieceOf.resize(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    out.pieceOf[t] = index[pieces.find(t)];
    if (out.pieceOf[t] == ClosedPieces::kOpen) across[t].fill(ClosedPieces::kOpen);
  }
  out.across = std::move(across);
  return out;
}

namespace {

PieceCounts countPieces(const ClosedPieces& pieces) {
  PieceCounts counts;
  counts.closedPieces = static_cast<std::uint32_t>(pieces.volume6.size());
  for (std::size_t p = 0; p < pieces.volume6.size(); ++p)
    if (pieces.volume6[p] < 0) {
      ++counts.insideOutPieces;
      counts.insideOutTriangles += pieces.triangleCount[p];
    }
  return counts;
}

std::vector<std::string> warningsFor(const Mesh& clean, const PieceCounts& pieces) {
  std::vector<std::string> warnings;
  if (pieces.insideOutPieces > 0) {
    std::ostringstream line;
    line << pieces.insideOutPieces << " of " << pieces.closedPieces << " closed pieces ("
         << pieces.insideOutTriangles
         << " triangles) are inside out: their volume is negative, their faces point inward, and "
            "bodies will pass into them (flip their winding)";
    warnings.push_back(line.str());
  }
  if (!clean.vertices.empty()) {
    Eigen::Vector3d low = clean.vertices.front(), high = low;
    for (const Eigen::Vector3d& v : clean.vertices) low = low.cwiseMin(v), high = high.cwiseMax(v);
    const double across = (high - low).maxCoeff();
    if (across > kLargestLikelyLevelMetres || across < kSmallestLikelyLevelMetres) {
      std::ostringstream line;
      line << "the level is " << across << " m across ("
           << (across > kLargestLikelyLevelMetres ? "over 10 km" : "under 1 m")
           << "): are its units metres? (--scale converts them)";
      warnings.push_back(line.str());
    }
  }
  return warnings;
}

}  // namespace

PieceCounts countClosedPieces(const Mesh& mesh) { return countPieces(findClosedPieces(mesh)); }

std::vector<std::string> meshWarnings(const Mesh& clean) {
  return warningsFor(clean, countClosedPieces(clean));
}

std::vector<std::string> meshWarnings(const SolidEdges& edges) {
  const Mesh& clean = edges.mesh();
  return warningsFor(clean, countPieces(findClosedPieces(clean, pairedNeighbours(edges))));
}

}  // namespace bspc
