// SPDX-License-Identifier: MIT
#include <bspc/edges.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numbers>
#include <numeric>
#include <span>
#include <tuple>

#include "flat_map.h"
#include "parallel.h"

namespace bspc {

namespace {

using V3 = Eigen::Vector3d;
using V2 = Eigen::Vector2d;

// Angles within this of each other (radians) are equal: float corners of a
// 10 cm triangle 100 m from the origin are 1e-5 m, 1e-4 rad, apart.
constexpr double kAngleTolerance = 1e-3;
// Below this a face about an edge lies on the triangle itself (a twin).
constexpr double kOnTriangle = 1e-6;

struct EdgeUse {
  std::uint32_t low, high;  // the edge's vertices, low < high
  std::uint32_t triangle;
  int k;  // edge k of the triangle: corner k to corner k + 1
  auto key() const { return std::tie(low, high, triangle, k); }
};

// Every triangle edge, grouped by its pair of vertices (sorted: the
// groups do not depend on hashing).
class EdgeMap {
 public:
  explicit EdgeMap(const Mesh& mesh) {
    // Sorted in two steps, cheaper than one sort of them all: counted into
    // runs by low vertex, then each run sorted.
    constexpr std::ptrdiff_t kShortRun = 16;
    auto use = [&](std::uint32_t t, int k) {
      const std::uint32_t a = mesh.triangles[t][k], b = mesh.triangles[t][(k + 1) % 3];
      return EdgeUse{std::min(a, b), std::max(a, b), t, k};
    };
    std::uint32_t vertexCount = 0;
    for (const auto& tri : mesh.triangles)
      for (const std::uint32_t v : tri) vertexCount = std::max(vertexCount, v + 1);
    std::vector<std::size_t> runStart(std::size_t(vertexCount) + 1, 0);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) ++runStart[use(t, k).low + 1];
    std::partial_sum(runStart.begin(), runStart.end(), runStart.begin());
    uses_.resize(mesh.triangles.size() * 3);
    std::vector<std::size_t> next(runStart.begin(), runStart.end() - 1);
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k) {
        const EdgeUse u = use(t, k);
        uses_[next[u.low]++] = u;
      }
    // A run is in (triangle, k) order as filled: sorted on the high vertex
    // alone, stably (insertion, for the short runs of most vertices), it is
    // in (high, triangle, k) order.
    for (std::uint32_t v = 0; v < vertexCount; ++v) {
      const auto first = uses_.begin() + runStart[v], last = uses_.begin() + runStart[v + 1];
      if (last - first > kShortRun) {
        std::sort(first, last,
                  [](const EdgeUse& x, const EdgeUse& y) { return x.key() < y.key(); });
        continue;
      }
      for (auto it = first + (first != last); it < last; ++it) {
        const EdgeUse moving = *it;
        auto hole = it;
        for (; hole != first && (hole - 1)->high > moving.high; --hole) *hole = *(hole - 1);
        *hole = moving;
      }
    }
    group_.assign(mesh.triangles.size(), {});
    for (std::size_t i = 0; i < uses_.size();) {
      std::size_t j = i;
      while (j < uses_.size() && uses_[j].low == uses_[i].low && uses_[j].high == uses_[i].high)
        ++j;
      for (std::size_t u = i; u < j; ++u) group_[uses_[u].triangle][uses_[u].k] = {i, j};
      i = j;
    }
  }
  // The uses of triangle t's edge k (t's own among them).
  std::span<const EdgeUse> around(std::uint32_t t, int k) const {
    const auto [first, last] = group_[t][k];
    return {uses_.data() + first, last - first};
  }

 private:
  std::vector<EdgeUse> uses_;
  std::vector<std::array<std::pair<std::size_t, std::size_t>, 3>> group_;
};

// Per-triangle passes are handed out in ranges of this many.
constexpr std::size_t kTriangleRange = 1024;

struct Geometry {
  const Mesh& mesh;
  std::vector<V3> normal;
  // Per triangle, edge k: the unit direction in its plane, perpendicular to
  // the edge, pointing into it. Once each: turning about an edge needs it for
  // every face around.
  std::vector<std::array<V3, 3>> inward;
  Geometry(const Mesh& m, bspf::ThreadPool* pool) : mesh(m) {
    normal.resize(m.triangles.size());
    inward.resize(m.triangles.size());
    runParallel(pool, m.triangles.size(), kTriangleRange,
                [&](int, std::size_t first, std::size_t last) {
                  for (std::size_t t = first; t < last; ++t) {
                    const auto& corners = m.triangles[t];
                    normal[t] = (m.vertices[corners[1]] - m.vertices[corners[0]])
                                    .cross(m.vertices[corners[2]] - m.vertices[corners[0]])
                                    .normalized();
                    for (int k = 0; k < 3; ++k)
                      inward[t][k] =
                          normal[t]
                              .cross(corner(std::uint32_t(t), k + 1) - corner(std::uint32_t(t), k))
                              .normalized();
                  }
                });
  }
  const V3& corner(std::uint32_t t, int k) const { return mesh.vertices[mesh.triangles[t][k % 3]]; }
  // The angle, in [0, 2 pi), from triangle t (turning through `side`, t's
  // normal or its opposite) to triangle u about their shared edge (t's edge
  // k, u's edge j).
  double turn(std::uint32_t t, int k, const V3& side, std::uint32_t u, int j) const {
    const V3& w = inward[u][j];
    double angle = std::atan2(w.dot(side), w.dot(inward[t][k]));
    if (angle < 0) angle += 2 * std::numbers::pi;
    return angle;
  }
  // Whether u runs along the shared edge the opposite way to t (one
  // consistently wound surface).
  bool consistent(std::uint32_t t, int k, std::uint32_t u, int j) const {
    return mesh.triangles[t][k] == mesh.triangles[u][(j + 1) % 3];
  }
};

// The face first met turning about t's edge k from t through `side`, as
// (triangle, its edge, angle); triangle == t when none (faces lying on t
// itself, at angle 0, are passed over). Ties: the lower triangle index.
struct Turn {
  std::uint32_t triangle;
  int k;
  double angle;
};
Turn firstTurn(const Geometry& g, const EdgeMap& edges, std::uint32_t t, int k, const V3& side) {
  Turn best{t, k, 2 * std::numbers::pi};
  for (const EdgeUse& use : edges.around(t, k)) {
    if (use.triangle == t) continue;
    const double angle = g.turn(t, k, side, use.triangle, use.k);
    if (angle < kOnTriangle || angle > 2 * std::numbers::pi - kOnTriangle) continue;
    // Coincident faces (a touching solid's face, the other side of a
    // two-sided one) meet at the same angle: the one wound with t first.
    const bool tie = std::abs(angle - best.angle) <= kOnTriangle;
    if ((!tie && angle < best.angle) ||
        (tie && g.consistent(t, k, use.triangle, use.k) &&
         (best.triangle == t || !g.consistent(t, k, best.triangle, best.k))))
      best = {use.triangle, use.k, angle};
  }
  return best;
}

// Per triangle, edge k: the face first met turning about the edge from the
// triangle's back (firstTurn through -normal), into its solid.
using BackTurns = std::vector<std::array<Turn, 3>>;
BackTurns backTurns(const Geometry& g, const EdgeMap& edges, bspf::ThreadPool* pool) {
  BackTurns back(g.mesh.triangles.size());
  runParallel(pool, back.size(), kTriangleRange, [&](int, std::size_t first, std::size_t last) {
    for (auto t = std::uint32_t(first); t < last; ++t)
      for (int k = 0; k < 3; ++k) back[t][k] = firstTurn(g, edges, t, k, -g.normal[t]);
  });
  return back;
}

// Triangles with the same three corners as t wound the other way.
bool hasTwin(const Mesh& mesh, const EdgeMap& edges, std::uint32_t t) {
  const auto& tri = mesh.triangles[t];
  for (const EdgeUse& use : edges.around(t, 0)) {
    if (use.triangle == t) continue;
    const auto& other = mesh.triangles[use.triangle];
    if (std::find(other.begin(), other.end(), tri[2]) != other.end()) return true;
  }
  return false;
}

// Whether each triangle's solid lies behind it: at each edge, turning from
// the triangle through its back, the first face met (passing over faces on
// the triangle itself) is wound with it and either closes a wedge of solid
// (under 180 degrees) and has no twin (is not one side of a two-sided
// surface), or continues the plane and is itself backed. Decided by a fixed point: a plane of
// coplanar triangles is backed only if its rim is.
std::vector<bool> solidBehind(const Geometry& g, const EdgeMap& edges, const BackTurns& back) {
  const std::size_t n = g.mesh.triangles.size();
  std::vector<bool> twin(n);
  for (std::uint32_t t = 0; t < n; ++t) twin[t] = hasTwin(g.mesh, edges, t);
  std::vector<bool> backed(n, true);
  // (u, t): t is backed only if u is. One list, not a list per triangle.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> reliance;
  for (std::uint32_t t = 0; t < n; ++t) {
    for (int k = 0; k < 3 && backed[t]; ++k) {
      const Turn& first = back[t][k];
      const bool found = first.triangle != t;
      if (!found || !g.consistent(t, k, first.triangle, first.k) || first.angle < kAngleTolerance ||
          first.angle > std::numbers::pi + kAngleTolerance) {
        backed[t] = false;
      } else if (first.angle < std::numbers::pi - kAngleTolerance) {
        // A wedge of solid, unless its face is one side of a two-sided surface.
        if (twin[first.triangle]) backed[t] = false;
      } else {
        if (g.normal[t].dot(g.normal[first.triangle]) <= 0)
          backed[t] = false;
        else
          reliance.push_back({first.triangle, t});
      }
    }
  }
  // Unbacked triangles unback those that rely on them, through the chain
  // (a worklist: linear however long the chains of coplanar triangles).
  // Those relying on u: reliedOnBy[reliedStart[u], reliedStart[u + 1]).
  std::vector<std::uint32_t> reliedStart(n + 1, 0), reliedOnBy(reliance.size());
  for (const auto& [u, t] : reliance) ++reliedStart[u + 1];
  std::partial_sum(reliedStart.begin(), reliedStart.end(), reliedStart.begin());
  std::vector<std::uint32_t> next(reliedStart.begin(), reliedStart.end() - 1);
  for (const auto& [u, t] : reliance) reliedOnBy[next[u]++] = t;
  std::vector<std::uint32_t> pending;
  for (std::uint32_t t = 0; t < n; ++t)
    if (!backed[t]) pending.push_back(t);
  while (!pending.empty()) {
    const std::uint32_t u = pending.back();
    pending.pop_back();
    for (std::uint32_t i = reliedStart[u]; i < reliedStart[u + 1]; ++i)
      if (const std::uint32_t t = reliedOnBy[i]; backed[t]) {
        backed[t] = false;
        pending.push_back(t);
      }
  }
  return backed;
}

// Plane buckets: quantised normal and distance, so coincident planes land in
// the same or a neighbouring bucket.
struct PlaneKey {
  std::int64_t nx, ny, nz, d;
  bool operator==(const PlaneKey&) const = default;
};
constexpr double kNormalStep = 1e-3, kDistanceStep = 1e-2;
PlaneKey planeKey(const V3& n, double d) {
  return {std::llround(n.x() / kNormalStep), std::llround(n.y() / kNormalStep),
          std::llround(n.z() / kNormalStep), std::llround(d / kDistanceStep)};
}

// The backed triangles by plane bucket. A face looks in the 81 buckets
// around its own; most are empty, so they are found as 27 normal buckets
// (one hash lookup each, made once per normal bucket asked about: the
// faces of a level share few) whose triangles are sorted by distance
// bucket (a binary search for the three wanted).
class PlaneBuckets {
 public:
  struct Entry {
    PlaneKey key;
    std::uint32_t triangle;
    Eigen::AlignedBox3d box;
  };

  explicit PlaneBuckets(std::vector<Entry> entries) : entries_(std::move(entries)) {
    std::sort(entries_.begin(), entries_.end(), [](const Entry& x, const Entry& y) {
      return std::tie(x.key.nx, x.key.ny, x.key.nz, x.key.d, x.triangle) <
             std::tie(y.key.nx, y.key.ny, y.key.nz, y.key.d, y.triangle);
    });
    for (std::uint32_t i = 0; i < entries_.size();) {
      std::uint32_t j = i;
      while (j < entries_.size() && sameNormal(entries_[j].key, entries_[i].key)) ++j;
      runs_.tryEmplace(normalOf(entries_[i].key), {i, j});
      i = j;
    }
  }

  // One thread's memory of the normal buckets it asked about: per bucket,
  // the runs of the buckets around it (the look-ups made once).
  class Around;

  // Calls visit(entry) for every entry whose bucket is within one step of
  // `home` in each of its four numbers, in no particular order. `around`:
  // the calling thread's own.
  template <typename Visit>
  void forNeighbours(const PlaneKey& home, Around& around, Visit&& visit) const;

 private:
  struct NormalKey {
    std::int64_t nx, ny, nz;
    bool operator==(const NormalKey&) const = default;
  };
  struct NormalKeyHash {
    std::uint64_t operator()(const NormalKey& k) const {
      std::uint64_t h = std::uint64_t(k.nx);
      h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull + std::uint64_t(k.ny);
      h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull + std::uint64_t(k.nz);
      return h ^ (h >> 32);
    }
  };
  static NormalKey normalOf(const PlaneKey& k) { return {k.nx, k.ny, k.nz}; }
  static bool sameNormal(const PlaneKey& a, const PlaneKey& b) {
    return a.nx == b.nx && a.ny == b.ny && a.nz == b.nz;
  }

  // A range of entries_ (one normal bucket's), or of Around's runs.
  using Run = std::pair<std::uint32_t, std::uint32_t>;
  std::vector<Entry> entries_;
  FlatMap<NormalKey, Run, NormalKeyHash> runs_;
};

class PlaneBuckets::Around {
  friend class PlaneBuckets;
  FlatMap<NormalKey, Run, NormalKeyHash> known_;
  std::vector<Run> runs_;
};

template <typename Visit>
void PlaneBuckets::forNeighbours(const PlaneKey& home, Around& around, Visit&& visit) const {
  const auto [known, added] = around.known_.tryEmplace(normalOf(home), {});
  if (added) {
    const auto first = static_cast<std::uint32_t>(around.runs_.size());
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz)
          if (const Run* run = runs_.find({home.nx + dx, home.ny + dy, home.nz + dz}))
            around.runs_.push_back(*run);
    *known = {first, static_cast<std::uint32_t>(around.runs_.size())};
  }
  const auto nearerThan = [](const Entry& entry, std::int64_t d) { return entry.key.d < d; };
  for (std::uint32_t r = known->first; r < known->second; ++r) {
    const auto first = entries_.begin() + around.runs_[r].first,
               last = entries_.begin() + around.runs_[r].second;
    for (auto it = std::lower_bound(first, last, home.d - 1, nearerThan);
         it != last && it->key.d <= home.d + 1; ++it)
      visit(*it);
  }
}

using Polygon = std::vector<V2>;

// The next corner after corner i of a polygon of `count`: a comparison, not
// a division (the clipping's inner loops).
std::size_t nextCorner(std::size_t i, std::size_t count) { return i + 1 == count ? 0 : i + 1; }

double area(std::span<const V2> p) {
  double twice = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const V2 &a = p[i], &b = p[nextCorner(i, p.size())];
    twice += a.x() * b.y() - a.y() * b.x();
  }
  return twice / 2;
}

// The parts of convex `p` on each side of the line through a with direction
// `along`: `inside` where cross(along, q - a) >= -margin.
void split(const Polygon& p, const V2& a, const V2& along, double margin, Polygon& inside,
           Polygon& outside) {
  inside.clear(), outside.clear();
  auto side = [&](const V2& q) {
    const V2 r = q - a;
    return along.x() * r.y() - along.y() * r.x() + margin;
  };
  if (p.empty()) return;
  // Each corner's side worked out once, and carried to the next edge.
  const double firstSide = side(p[0]);
  double s = firstSide;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const std::size_t j = nextCorner(i, p.size());
    const V2 &q = p[i], &next = p[j];
    const double sNext = j == 0 ? firstSide : side(next);
    (s >= 0 ? inside : outside).push_back(q);
    if ((s >= 0) != (sNext >= 0)) {
      const V2 cross = q + (next - q) * (s / (s - sNext));
      inside.push_back(cross);
      outside.push_back(cross);
    }
    s = sNext;
  }
}

// Convex polygons end to end in one array, so clipping many of them makes
// no allocation per polygon.
class Polygons {
 public:
  std::size_t size() const { return ends_.size(); }
  std::span<const V2> operator[](std::size_t i) const {
    const std::size_t first = i == 0 ? 0 : ends_[i - 1];
    return {points_.data() + first, ends_[i] - first};
  }
  void push_back(std::span<const V2> polygon) {
    points_.insert(points_.end(), polygon.begin(), polygon.end());
    ends_.push_back(points_.size());
  }
  void clear() { points_.clear(), ends_.clear(); }
  bool empty() const { return ends_.empty(); }

 private:
  std::vector<V2> points_;
  std::vector<std::size_t> ends_;
};

// What covered() clips with, kept from face to face so that it allocates
// only when a face needs more room than any before it.
struct ClipScratch {
  Polygons left, next;
  Polygon piece, inside, outside;
};

// Whether triangle f is covered by the union of triangles `cover` (all in
// its plane, facing the other way), each grown by 0.1 mm.
bool covered(const Geometry& g, std::uint32_t f, const std::vector<std::uint32_t>& cover,
             ClipScratch& scratch) {
  const V3 origin = g.corner(f, 0);
  const V3 u = (g.corner(f, 1) - origin).normalized();
  const V3 v = g.normal[f].cross(u);
  auto flat = [&](const V3& p) { return V2((p - origin).dot(u), (p - origin).dot(v)); };
  auto& [left, next, piece, inside, outside] = scratch;
  left.clear();
  left.push_back(std::array{flat(g.corner(f, 0)), flat(g.corner(f, 1)), flat(g.corner(f, 2))});
  constexpr double kMargin = 1e-4, kLeftArea = 1e-8;
  // Beyond a cover's box by this much, a piece is beyond its margin too
  // (but past a needle-thin cover's sharp corners, where the margin
  // reaches further: such a piece stays uncovered, which keeps the face).
  constexpr double kReach = 4 * kMargin;
  constexpr std::size_t kMaxPieces = 256;
  for (const std::uint32_t c : cover) {
    // On the stack: a face can have many covering faces.
    std::array<V2, 3> shape{flat(g.corner(c, 0)), flat(g.corner(c, 1)), flat(g.corner(c, 2))};
    if (area(shape) < 0) std::reverse(shape.begin(), shape.end());
    // What the cover can reach, its margin included: a piece wholly beyond
    // it is left whole. Clipped, it would come back in fragments (one for
    // each edge line it crosses), which the next covers would clip again.
    const V2 reachLow = shape[0].cwiseMin(shape[1]).cwiseMin(shape[2]);
    const V2 reachHigh = shape[0].cwiseMax(shape[1]).cwiseMax(shape[2]);
    next.clear();
    for (std::size_t i = 0; i < left.size(); ++i) {
      const std::span<const V2> whole = left[i];
      V2 low = whole[0], high = whole[0];
      for (const V2& q : whole) low = low.cwiseMin(q), high = high.cwiseMax(q);
      if ((low.array() > reachHigh.array() + kReach).any() ||
          (high.array() < reachLow.array() - kReach).any()) {
        next.push_back(whole);
        continue;
      }
      piece.assign(left[i].begin(), left[i].end());
      for (int e = 0; e < 3 && !piece.empty(); ++e) {
        const V2 along = (shape[(e + 1) % 3] - shape[e]).normalized();
        split(piece, shape[e], along, kMargin, inside, outside);
        if (outside.size() >= 3 && std::abs(area(outside)) > kLeftArea) next.push_back(outside);
        std::swap(piece, inside);
        if (piece.size() < 3) piece.clear();
      }
    }
    std::swap(left, next);
    if (left.empty()) return true;
    if (left.size() > kMaxPieces) return false;
  }
  return false;
}

}  // namespace

struct SolidEdges::Parts {
  Geometry geometry;
  EdgeMap edges;
  BackTurns back;
  Parts(const Mesh& mesh, bspf::ThreadPool* pool)
      : geometry(mesh, pool), edges(mesh), back(backTurns(geometry, edges, pool)) {}
};

SolidEdges::SolidEdges(const Mesh& mesh, bspf::ThreadPool* pool)
    : parts_(std::make_unique<const Parts>(mesh, pool)) {}
SolidEdges::~SolidEdges() = default;
const Mesh& SolidEdges::mesh() const { return parts_->geometry.mesh; }

std::vector<bool> findCoveredFaces(const Mesh& mesh) { return findCoveredFaces(SolidEdges(mesh)); }

std::vector<bool> findCoveredFaces(const SolidEdges& solid, bspf::ThreadPool* pool) {
  const Geometry& g = solid.parts().geometry;
  const Mesh& mesh = g.mesh;
  const std::vector<bool> backed = solidBehind(g, solid.parts().edges, solid.parts().back);
  const std::size_t n = mesh.triangles.size();

  auto bounds = [&](std::uint32_t t) {
    Eigen::AlignedBox3d box;
    for (int k = 0; k < 3; ++k) box.extend(g.corner(t, k));
    return box;
  };
  std::vector<PlaneBuckets::Entry> backedEntries;
  for (std::uint32_t t = 0; t < n; ++t)
    if (backed[t])
      backedEntries.push_back(
          {planeKey(g.normal[t], g.normal[t].dot(g.corner(t, 0))), t, bounds(t)});
  PlaneBuckets planes(std::move(backedEntries));

  // Each face decided alone, into its own byte: the same on any number of
  // threads, each with its own look-ups and clipping memory.
  struct Working {
    PlaneBuckets::Around around;
    std::vector<std::uint32_t> cover;
    ClipScratch scratch;
  };
  std::vector<Working> working(pool ? std::size_t(pool->threadCount()) : 1);
  std::vector<std::uint8_t> dropped(n, 0);
  const auto decide = [&](int thread, std::size_t first, std::size_t last) {
    // Named, not a structured binding: the lambda below captures `cover`,
    // which C++20 allows of a binding but clang 14 does not.
    Working& mine = working[std::size_t(thread)];
    PlaneBuckets::Around& around = mine.around;
    std::vector<std::uint32_t>& cover = mine.cover;
    ClipScratch& scratch = mine.scratch;
    for (auto f = std::uint32_t(first); f < last; ++f) {
      const V3 opposite = -g.normal[f];
      const double d = opposite.dot(g.corner(f, 0));
      const PlaneKey home = planeKey(opposite, d);
      Eigen::AlignedBox3d box = bounds(f);
      double scale = 1;
      for (int k = 0; k < 3; ++k) scale = std::max(scale, g.corner(f, k).cwiseAbs().maxCoeff());
      const double tolerance = 1e-4 + 1e-6 * scale;
      box.min().array() -= tolerance, box.max().array() += tolerance;
      cover.clear();
      planes.forNeighbours(home, around, [&](const PlaneBuckets::Entry& entry) {
        const std::uint32_t c = entry.triangle;
        if (c == f || g.normal[c].dot(opposite) < 1 - 2e-7) return;
        if (!box.intersects(entry.box)) return;
        bool inPlane = true;
        for (int k = 0; k < 3; ++k)
          inPlane = inPlane &&
                    std::abs(g.normal[c].dot(g.corner(f, k) - g.corner(c, 0))) <= tolerance &&
                    std::abs(g.normal[f].dot(g.corner(c, k) - g.corner(f, 0))) <= tolerance;
        if (inPlane) cover.push_back(c);
      });
      // Many overlapping faces in one plane (hostile input): keep the face
      // rather than clip it against them all.
      constexpr std::size_t kMaxCover = 64;
      if (cover.empty() || cover.size() > kMaxCover) continue;
      std::sort(cover.begin(), cover.end());
      dropped[f] = covered(g, f, cover, scratch);
    }
  };
  // Ranges of 256: a face's clipping takes far longer than one's normals.
  runParallel(pool, n, 256, decide);
  return std::vector<bool>(dropped.begin(), dropped.end());
}

Mesh dropCoveredFaces(const Mesh& mesh, EdgeReport& report) {
  const std::vector<bool> covered = findCoveredFaces(mesh);
  std::vector<bool> keep(covered.size());
  for (std::size_t t = 0; t < covered.size(); ++t) {
    keep[t] = !covered[t];
    report.droppedCovered += covered[t];
  }
  return keepTriangles(mesh, keep);
}

std::vector<std::array<std::uint32_t, 3>> solidNeighbours(const Mesh& mesh) {
  return solidNeighbours(SolidEdges(mesh));
}

std::vector<std::array<std::uint32_t, 3>> solidNeighbours(const SolidEdges& solid) {
  constexpr std::uint32_t kNone = ~std::uint32_t(0);
  const Geometry& g = solid.parts().geometry;
  const EdgeMap& edges = solid.parts().edges;
  const std::size_t n = g.mesh.triangles.size();
  // Each edge's candidate: the other triangle of a two-triangle edge, or the
  // first face turning from the triangle's back into its solid; kept when
  // it runs the other way along the edge.
  std::vector<std::array<std::pair<std::uint32_t, int>, 3>> candidate(n);
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const std::span<const EdgeUse> around = edges.around(t, k);
      std::pair<std::uint32_t, int> found{kNone, 0};
      if (around.size() == 2) {
        const EdgeUse& other = around[0].triangle == t ? around[1] : around[0];
        found = {other.triangle, other.k};
      } else if (around.size() > 2) {
        const Turn& first = solid.parts().back[t][k];
        if (first.triangle != t) found = {first.triangle, first.k};
      }
      if (found.first != kNone && !g.consistent(t, k, found.first, found.second))
        found.first = kNone;
      candidate[t][k] = found;
    }
  // Only pairs that choose each other: then every edge of a closed piece
  // is cancelled by one running the other way.
  std::vector<std::array<std::uint32_t, 3>> out(n, {kNone, kNone, kNone});
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      const auto [u, j] = candidate[t][k];
      if (u != kNone && candidate[u][j].first == t && candidate[u][j].second == k) out[t][k] = u;
    }
  return out;
}

std::vector<std::array<std::uint32_t, 3>> pairedNeighbours(const SolidEdges& solid) {
  const Geometry& g = solid.parts().geometry;
  const EdgeMap& edges = solid.parts().edges;
  const std::size_t n = g.mesh.triangles.size();
  constexpr std::uint32_t kNone = ~std::uint32_t(0);
  std::vector<std::array<std::uint32_t, 3>> out(n, {kNone, kNone, kNone});
  for (std::uint32_t t = 0; t < n; ++t)
    for (int k = 0; k < 3; ++k) {
      // Two uses of the edge, one each way: the edge used once in each
      // direction. (A triangle of distinct corners uses an edge once.)
      const std::span<const EdgeUse> around = edges.around(t, k);
      if (around.size() != 2) continue;
      const EdgeUse& other = around[0].triangle == t ? around[1] : around[0];
      if (g.consistent(t, k, other.triangle, other.k)) out[t][k] = other.triangle;
    }
  return out;
}

std::vector<TriangleEdges> classifyEdges(const Mesh& mesh, bspf::ThreadPool* pool) {
  const Geometry g(mesh, pool);
  const EdgeMap edges(mesh);
  std::vector<TriangleEdges> out(mesh.triangles.size());
  runParallel(pool, out.size(), kTriangleRange, [&](int, std::size_t first, std::size_t last) {
    for (auto t = std::uint32_t(first); t < last; ++t) {
      for (int k = 0; k < 3; ++k) {
        const Turn first = firstTurn(g, edges, t, k, g.normal[t]);
        EdgeKind& kind = out[t].kind[k];
        if (first.triangle == t)
          kind = EdgeKind::Open;
        else if (first.angle < std::numbers::pi - kAngleTolerance)
          kind = g.consistent(t, k, first.triangle, first.k) ? EdgeKind::Concave : EdgeKind::Convex;
        else if (first.angle <= std::numbers::pi + kAngleTolerance &&
                 g.normal[t].dot(g.normal[first.triangle]) > 0 &&
                 g.consistent(t, k, first.triangle, first.k))
          kind = EdgeKind::Coplanar;
        else
          kind = EdgeKind::Convex;
        if (kind == EdgeKind::Coplanar) {
          const V3 mirror = g.corner(t, k) + g.corner(t, k + 1) - g.corner(t, k + 2);
          out[t].mirrored[k] = (g.corner(first.triangle, first.k + 2) - mirror).norm() <= 1e-4;
        }
      }
    }
  });
  return out;
}

std::vector<std::uint8_t> meetablePlanes(const std::vector<TriangleEdges>& edges,
                                         EdgeReport& report, bool skipMirrored) {
  std::vector<std::uint8_t> masks;
  masks.reserve(edges.size());
  for (const TriangleEdges& triangle : edges) {
    std::uint8_t mask = 0b111000;  // caps: always met
    for (int k = 0; k < 3; ++k) {
      switch (triangle.kind[k]) {
        case EdgeKind::Open: ++report.open; break;
        case EdgeKind::Convex: ++report.convex; break;
        case EdgeKind::Concave: ++report.concave; break;
        case EdgeKind::Coplanar: ++report.coplanar; break;
      }
      if (skipMirrored && triangle.kind[k] == EdgeKind::Coplanar && triangle.mirrored[k])
        ++report.skippedEdgePlanes;
      else
        mask |= std::uint8_t(1u << k);
    }
    masks.push_back(mask);
  }
  return masks;
}

}  // namespace bspc
