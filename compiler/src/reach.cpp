// SPDX-License-Identifier: MIT
// The reach stage: a flood of the level's free space on a grid, from body
// centres the game names, then every face no reached place lets a body touch
// is dropped. Why it never drops a face a body can touch: docs/algorithm.md,
// "Faces no body can touch".
#include <bspc/reach.h>
#include <bspf/geometry.h>
#include <bspf/thread_pool.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>

#include "parallel.h"

namespace bspc {

namespace {

using Vec3d = Eigen::Vector3d;

// Every distance below is measured in "body space", the level scaled by
// (1/radiusXZ, 1/radiusY, 1/radiusXZ), where the body is the unit sphere: it
// touches a triangle exactly when its centre is within distance 1 of it.
//
// A cell's centre is within `halfDiagonal` (body space) of every point of
// the cell. So a cell holding a place where the body can be (distance >= 1
// from every triangle) has its centre at >= 1 - halfDiagonal: cells closer
// than that are blocked and never hold the body. A body at distance <= 1
// from a triangle has its cell's centre within 1 + halfDiagonal: faces
// further than that from every reached centre are never touched. The small
// margin covers rounding and a body resting a skin's width inside contact.
constexpr double kMarginBodySpace = 0.02;
// The largest cell, as a fraction of the smaller radius, it may grow to, to
// fit maxCells: a wall crossed by the path between two neighbouring cell
// centres is within half a cell of one of them, which must then be blocked
// ((h / 2) / r < 1 - halfDiagonal - margin); 0.6 keeps clear of that bound.
constexpr double kLargestCellOfRadius = 0.6;

struct Grid {
  Vec3d origin;  // world, the low corner of cell (0, 0, 0)
  double cell = 0;
  std::array<std::int64_t, 3> size{};
  std::uint64_t count() const { return std::uint64_t(size[0]) * size[1] * size[2]; }
  std::uint64_t index(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return (std::uint64_t(k) * size[1] + std::uint64_t(j)) * size[0] + std::uint64_t(i);
  }
  Vec3d centre(std::int64_t i, std::int64_t j, std::int64_t k) const {
    return origin + cell * Vec3d(double(i) + 0.5, double(j) + 0.5, double(k) + 0.5);
  }
};

// A bit a cell. The passes over triangles run on several threads and set
// bits of shared words: relaxed atomic reads and ORs, whose result (an OR)
// does not depend on the order the threads run in.
class Bits {
 public:
  explicit Bits(std::uint64_t count) : words_((count + 63) / 64, 0) {}
  bool get(std::uint64_t i) const {
    return (std::atomic_ref<const std::uint64_t>(words_[i >> 6]).load(std::memory_order_relaxed) >>
            (i & 63)) &
           1;
  }
  void set(std::uint64_t i) {
    std::atomic_ref<std::uint64_t>(words_[i >> 6])
        .fetch_or(std::uint64_t(1) << (i & 63), std::memory_order_relaxed);
  }

 private:
  std::vector<std::uint64_t> words_;
};

struct BodyTriangle {
  Vec3d a, b, c;    // body space
  Vec3d normal;     // body space, unit; zero when too thin to have one
  Vec3d low, high;  // world-space box
};

// Calls visit(cell) for each cell for which consider(cell) holds and whose
// centre is within `reach` (body space) of `tri`, until visit returns false.
// Only the cells in the slab of the triangle's plane are looked at: a large
// slanted triangle's box holds far more.
template <typename Consider, typename Visit>
void forCellsNear(const Grid& grid, const Vec3d& toBody, const BodyTriangle& tri, double reach,
                  Consider&& consider, Visit&& visit) {
  std::array<std::int64_t, 3> first{}, last{};
  for (int axis = 0; axis < 3; ++axis) {
    const double pad = reach / toBody[axis];
    first[axis] = std::max<std::int64_t>(
        0, std::int64_t(std::floor((tri.low[axis] - pad - grid.origin[axis]) / grid.cell - 0.5)));
    last[axis] = std::min<std::int64_t>(
        grid.size[axis] - 1,
        std::int64_t(std::ceil((tri.high[axis] + pad - grid.origin[axis]) / grid.cell - 0.5)));
    if (first[axis] > last[axis]) return;
  }
  // The axis along which the plane's body-space distance changes fastest
  // per cell: along it the slab is a few cells thick.
  const Vec3d rate = tri.normal.cwiseProduct(toBody) * grid.cell;
  int across = 0;
  for (int axis = 1; axis < 3; ++axis)
    if (std::abs(rate[axis]) > std::abs(rate[across])) across = axis;
  const int u = (across + 1) % 3, v = (across + 2) % 3;
  const double planeOffset = tri.normal.dot(tri.a);
  std::array<std::int64_t, 3> at{};
  for (at[v] = first[v]; at[v] <= last[v]; ++at[v]) {
    for (at[u] = first[u]; at[u] <= last[u]; ++at[u]) {
      std::int64_t from = first[across], to = last[across];
      if (std::abs(rate[across]) > 1e-9) {
        at[across] = 0;
        const double side0 =
            tri.normal.dot(grid.centre(at[0], at[1], at[2]).cwiseProduct(toBody)) - planeOffset;
        // side(index) = side0 + rate * index; |side| <= reach, one cell of slack.
        double lo = (-reach - side0) / rate[across], hi = (reach - side0) / rate[across];
        if (lo > hi) std::swap(lo, hi);
        from = std::max(from, std::int64_t(std::floor(lo)) - 1);
        to = std::min(to, std::int64_t(std::ceil(hi)) + 1);
      }
      for (at[across] = from; at[across] <= to; ++at[across]) {
        const std::uint64_t cell = grid.index(at[0], at[1], at[2]);
        if (!consider(cell)) continue;
        const Vec3d p = grid.centre(at[0], at[1], at[2]).cwiseProduct(toBody);
        const double squared =
            (p - bspf::closestPointOnTriangle<Vec3d>(p, tri.a, tri.b, tri.c)).squaredNorm();
        if (squared <= reach * reach && !visit(cell)) return;
      }
    }
  }
}

std::string pointText(const Vec3d& p) {
  std::ostringstream out;
  out << p.x() << ' ' << p.y() << ' ' << p.z();
  return out.str();
}

}  // namespace

std::vector<Vec3d> readReachPoints(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw CompileError(file.string() + ": cannot read the --reach-from points");
  std::vector<Vec3d> points;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const auto text = line.find_first_not_of(" \t\r");
    if (text == std::string::npos || line[text] == '#') continue;
    std::istringstream fields(line);
    Vec3d p;
    std::string extra;
    if (!(fields >> p.x() >> p.y() >> p.z()) || (fields >> extra) || !p.allFinite())
      throw CompileError(file.string() + ":" + std::to_string(number) +
                         ": expected a point as three finite numbers \"x y z\", got \"" + line +
                         "\"");
    points.push_back(p);
  }
  if (points.empty())
    throw CompileError(file.string() + ": no points (one \"x y z\" a line, body centres)");
  return points;
}

Mesh dropUnreachableFaces(const Mesh& mesh, const ReachSettings& settings, ReachReport& report,
                          std::vector<std::string>& warnings, bspf::ThreadPool* pool) {
  report = ReachReport{};
  if (settings.from.empty() || mesh.triangles.empty()) return mesh;
  const Vec3d radii(settings.radiusXZ, settings.radiusY, settings.radiusXZ);
  const Vec3d toBody = radii.cwiseInverse();

  Vec3d low = Vec3d::Constant(std::numeric_limits<double>::infinity()), high = -low;
  for (const Vec3d& v : mesh.vertices) low = low.cwiseMin(v), high = high.cwiseMax(v);
  for (std::size_t n = 0; n < settings.from.size(); ++n) {
    const Vec3d& p = settings.from[n];
    if ((p.array() < low.array()).any() || (p.array() > high.array()).any())
      throw CompileError("--reach-from point " + std::to_string(n + 1) + " (" + pointText(p) +
                         ") is outside the level's bounds");
  }

  // The grid: the mesh's box with room for a body and two cells around it,
  // so a flood that leaks out of an open level goes round it.
  Grid grid;
  const double smaller = radii.minCoeff();
  for (grid.cell = settings.cellOfRadius * smaller;; grid.cell *= 1.25) {
    grid.origin = low - radii - Vec3d::Constant(2 * grid.cell);
    const Vec3d span = high + radii + Vec3d::Constant(2 * grid.cell) - grid.origin;
    for (int axis = 0; axis < 3; ++axis)
      grid.size[axis] = std::max<std::int64_t>(1, std::int64_t(std::ceil(span[axis] / grid.cell)));
    if (grid.count() <= settings.maxCells) break;
    if (grid.cell * 1.25 > kLargestCellOfRadius * smaller) {
      warnings.push_back("--reach-from ignored: the level is too large for its grid (" +
                         std::to_string(grid.count()) + " cells of " + std::to_string(grid.cell) +
                         " m, over " + std::to_string(settings.maxCells) + "); every face is kept");
      return mesh;
    }
  }
  const double halfDiagonal = (0.5 * grid.cell * toBody).norm();
  const double blockReach = 1 - halfDiagonal - kMarginBodySpace;
  const double keepReach = 1 + halfDiagonal + kMarginBodySpace;

  std::vector<BodyTriangle> body(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& tri = mesh.triangles[t];
    BodyTriangle& b = body[t];
    const Vec3d& a = mesh.vertices[tri[0]];
    const Vec3d& bv = mesh.vertices[tri[1]];
    const Vec3d& c = mesh.vertices[tri[2]];
    b.a = a.cwiseProduct(toBody), b.b = bv.cwiseProduct(toBody), b.c = c.cwiseProduct(toBody);
    const Vec3d n = (b.b - b.a).cross(b.c - b.a);
    b.normal = n.norm() > 0 ? Vec3d(n.normalized()) : Vec3d::Zero();
    b.low = a.cwiseMin(bv).cwiseMin(c), b.high = a.cwiseMax(bv).cwiseMax(c);
  }

  // Triangles are handed out in chunks to the pool's threads (or all to
  // this one): each pass's result is the same whichever thread did what.
  const auto eachTriangle = [&](const auto& work) {
    const auto range = [&](int, std::size_t first, std::size_t last) {
      for (std::size_t t = first; t < last; ++t) work(t);
    };
    runParallel(pool, body.size(), 64, range);
  };
  Bits blocked(grid.count()), reached(grid.count());
  eachTriangle([&](std::size_t t) {
    forCellsNear(
        grid, toBody, body[t], blockReach, [&](std::uint64_t cell) { return !blocked.get(cell); },
        [&](std::uint64_t cell) {
          blocked.set(cell);
          return true;
        });
  });

  // The flood, depth first over the six neighbours of each cell.
  // Cell numbers fit 32 bits (maxCells <= 2^32): half the memory of a
  // flood that can hold most of the grid.
  std::vector<std::uint32_t> stack;
  for (std::size_t n = 0; n < settings.from.size(); ++n) {
    const Vec3d at = (settings.from[n] - grid.origin) / grid.cell;
    const std::uint64_t cell =
        grid.index(std::int64_t(at.x()), std::int64_t(at.y()), std::int64_t(at.z()));
    if (blocked.get(cell))
      throw CompileError("--reach-from point " + std::to_string(n + 1) + " (" +
                         pointText(settings.from[n]) +
                         ") is within a body's size of a surface: give body centres, clear of "
                         "every surface by the body's radii");
    if (!reached.get(cell)) reached.set(cell), stack.push_back(std::uint32_t(cell));
  }
  const std::uint64_t sx = std::uint64_t(grid.size[0]), sy = std::uint64_t(grid.size[1]);
  while (!stack.empty()) {
    const std::uint64_t cell = stack.back();
    stack.pop_back();
    ++report.reached;
    const std::uint64_t i = cell % sx, j = (cell / sx) % sy, k = cell / (sx * sy);
    if (i == 0 || j == 0 || k == 0 || i + 1 == sx || j + 1 == sy ||
        k + 1 == std::uint64_t(grid.size[2])) {
      report.leaked = true;
    }
    const auto go = [&](bool inside, std::uint64_t next) {
      if (inside && !blocked.get(next) && !reached.get(next))
        reached.set(next), stack.push_back(std::uint32_t(next));
    };
    go(i > 0, cell - 1);
    go(i + 1 < sx, cell + 1);
    go(j > 0, cell - sx);
    go(j + 1 < sy, cell + sx);
    go(k > 0, cell - sx * sy);
    go(k + 1 < std::uint64_t(grid.size[2]), cell + sx * sy);
  }

  Mesh kept;
  kept.warnings = mesh.warnings;
  // Bytes, not std::vector<bool>: threads write neighbouring entries.
  std::vector<std::uint8_t> keptByte(mesh.triangles.size(), 0);
  eachTriangle([&](std::size_t t) {
    forCellsNear(
        grid, toBody, body[t], keepReach, [&](std::uint64_t cell) { return reached.get(cell); },
        [&](std::uint64_t) {
          keptByte[t] = 1;
          return false;
        });
  });
  const std::vector<bool> keep(keptByte.begin(), keptByte.end());
  // The kept triangles in their order, with the vertices they use in theirs.
  std::vector<bool> used(mesh.vertices.size(), false);
  std::vector<std::uint32_t> newIndex(mesh.vertices.size(), 0);
  for (std::size_t t = 0; t < keep.size(); ++t)
    if (keep[t])
      for (const std::uint32_t v : mesh.triangles[t]) used[v] = true;
  for (std::size_t v = 0; v < used.size(); ++v) {
    if (!used[v]) continue;
    newIndex[v] = std::uint32_t(kept.vertices.size());
    kept.vertices.push_back(mesh.vertices[v]);
  }
  for (std::size_t t = 0; t < keep.size(); ++t) {
    if (!keep[t]) continue;
    const auto& tri = mesh.triangles[t];
    kept.triangles.push_back({newIndex[tri[0]], newIndex[tri[1]], newIndex[tri[2]]});
  }
  carrySurfaces(mesh, keep, kept);
  report.applied = true;
  report.dropped = mesh.triangles.size() - kept.triangles.size();
  report.cells = grid.count();
  report.cellMetres = grid.cell;
  if (report.leaked)
    warnings.push_back(
        "--reach-from: the free space reached from the points leaks out of the level (an "
        "opening, or a point outside it): faces seen from outside are kept");
  return kept;
}

}  // namespace bspc
