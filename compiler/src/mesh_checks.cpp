// SPDX-License-Identifier: MIT
#include <bspc/mesh_checks.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <unordered_map>

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

std::uint64_t edgeKey(std::uint32_t from, std::uint32_t to) {
  return std::uint64_t(from) << 32 | to;
}

}  // namespace

PieceCounts countClosedPieces(const Mesh& mesh) {
  const std::size_t n = mesh.triangles.size();
  // Each directed edge, with the triangle using it, and how often it is used.
  std::unordered_map<std::uint64_t, std::uint32_t> firstUser, uses;
  firstUser.reserve(3 * n);
  uses.reserve(3 * n);
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint64_t key = edgeKey(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3]);
      firstUser.emplace(key, t);
      ++uses[key];
    }
  // Joined across each edge; a piece is open when one of its edges has no
  // reverse, or either direction is used more than once.
  Pieces pieces(n);
  std::vector<bool> open(n, false);
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      const auto reverse = uses.find(edgeKey(b, a));
      if (reverse == uses.end() || reverse->second != 1 || uses[edgeKey(a, b)] != 1) {
        open[t] = true;
        continue;
      }
      pieces.join(t, firstUser[edgeKey(b, a)]);
    }
  // Per piece: open or not, signed volume (six times it, about the piece's
  // first corner, so a level far from the origin loses no precision), size.
  struct Piece {
    bool open = false;
    double volume6 = 0;
    std::uint32_t triangles = 0;
    Eigen::Vector3d origin;
  };
  std::unordered_map<std::uint32_t, Piece> byRoot;
  for (std::uint32_t t = 0; t < n; ++t) {
    const auto& tri = mesh.triangles[t];
    auto [it, made] = byRoot.try_emplace(pieces.find(t));
    Piece& piece = it->second;
    if (made) piece.origin = mesh.vertices[tri[0]];
    const Eigen::Vector3d a = mesh.vertices[tri[0]] - piece.origin,
                          b = mesh.vertices[tri[1]] - piece.origin,
                          c = mesh.vertices[tri[2]] - piece.origin;
    piece.volume6 += a.dot(b.cross(c));
    piece.open = piece.open || open[t];
    ++piece.triangles;
  }
  PieceCounts counts;
  for (const auto& [root, piece] : byRoot) {
    if (piece.open) continue;
    ++counts.closedPieces;
    if (piece.volume6 < 0) {
      ++counts.insideOutPieces;
      counts.insideOutTriangles += piece.triangles;
    }
  }
  return counts;
}

std::vector<std::string> meshWarnings(const Mesh& clean) {
  std::vector<std::string> warnings;
  const PieceCounts pieces = countClosedPieces(clean);
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

}  // namespace bspc
