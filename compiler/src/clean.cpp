// SPDX-License-Identifier: MIT
#include <bspc/clean.h>
#include <bspf/world.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <unordered_map>

#include "flat_map.h"

namespace bspc {

namespace {

struct CellKey {
  std::int64_t x, y, z;
  bool operator==(const CellKey&) const = default;
};

struct CellHash {
  std::uint64_t operator()(const CellKey& k) const {
    std::uint64_t h = static_cast<std::uint64_t>(k.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(k.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(k.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return h;
  }
};

// The first vertex at each position, -0 counted as +0 (they weld alike): a
// hash set of vertex indices, the positions read from the vertices, so it
// takes 4 bytes a slot however many copies a position has.
class FirstCopies {
 public:
  explicit FirstCopies(const std::vector<Eigen::Vector3d>& vertices) : vertices_(vertices) {
    resize(16);
  }

  // The first vertex at vertex i's position: i itself when it is the first
  // (vertices are offered in order).
  std::uint32_t firstOf(std::uint32_t i) {
    if (2 * (size_ + 1) > slots_.size()) resize(2 * slots_.size());
    const Eigen::Vector3d& p = vertices_[i];
    for (std::size_t s = slotOf(p);; s = (s + 1) & (slots_.size() - 1)) {
      if (slots_[s] == kEmpty) {
        slots_[s] = i;
        ++size_;
        return i;
      }
      if (vertices_[slots_[s]] == p) return slots_[s];
    }
  }

 private:
  static constexpr std::uint32_t kEmpty = std::numeric_limits<std::uint32_t>::max();

  std::size_t slotOf(const Eigen::Vector3d& p) const {
    std::uint64_t h = std::bit_cast<std::uint64_t>(p.x() + 0.0);
    h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull + std::bit_cast<std::uint64_t>(p.y() + 0.0);
    h = (h ^ (h >> 29)) * 0xBF58476D1CE4E5B9ull + std::bit_cast<std::uint64_t>(p.z() + 0.0);
    return std::size_t(((h ^ (h >> 32)) * 0x9E3779B97F4A7C15ull) >> shift_);
  }

  void resize(std::size_t slots) {
    std::vector<std::uint32_t> old = std::move(slots_);
    slots_.assign(slots, kEmpty);
    shift_ = 64 - std::countr_zero(slots);
    for (const std::uint32_t v : old)
      if (v != kEmpty) {
        std::size_t s = slotOf(vertices_[v]);
        while (slots_[s] != kEmpty) s = (s + 1) & (slots - 1);
        slots_[s] = v;
      }
  }

  const std::vector<Eigen::Vector3d>& vertices_;
  std::vector<std::uint32_t> slots_;
  int shift_ = 64;
  std::size_t size_ = 0;
};

// Beyond this many cells from 0, a coordinate is keyed by its exact value:
// a float that large has no other float within a tolerance of it (its
// neighbours are at least |c| / 2^25 away), so only equal coordinates can
// weld.
constexpr double kGridCells = 1073741824.0;  // 2^30
// Grid cells are this many tolerances wide. A vertex looks in its own cell
// and, along each axis, in the neighbouring cell only when it lies within a
// tolerance of that side: about 3.4 cells, against 27 for cells one
// tolerance wide (each look-up a likely cache miss). Wider cells would hold
// more of the kept vertices, which are only known to be a tolerance apart.
constexpr double kCellTolerances = 4;
// Exact keys start here, beyond every grid cell index (at most 2^30 + 1).
constexpr std::int64_t kExactKeys = std::int64_t(1) << 40;

// Maps every vertex to the first earlier vertex within `tolerance` (itself if
// none). The result depends only on the input order, never on hash order.
// Near-linear for every tolerance: each axis of a vertex is keyed either by a
// grid cell kCellTolerances tolerances wide (so a match lies in its cell or
// the one next to it) or by its exact value (tolerance 0, or far from 0
// against the tolerance; a match then has the same value). The vertices
// kept are more than a tolerance apart, so a key holds a bounded number of
// them.
std::vector<std::uint32_t> weld(const std::vector<Eigen::Vector3d>& vertices, double tolerance) {
  std::vector<std::uint32_t> target(vertices.size());
  const double tolerance2 = tolerance * tolerance;
  const double cellWidth = kCellTolerances * tolerance;
  // How near a cell's side, in cells, a vertex looks across it too: a
  // tolerance, and a margin for the rounding of c / cellWidth (a cell index
  // is below 2^30, so off by under 2^-22). Looking in a cell too many only
  // costs the look-up: the distance test decides.
  const double nearSide = 1 / kCellTolerances + 1e-4;
  // The vertices kept in each cell, as a chain through `kept`: the cell's
  // latest, then each one's predecessor.
  struct Kept {
    std::uint32_t vertex, previous;
  };
  std::vector<Kept> kept;
  FlatMap<CellKey, std::uint32_t, CellHash> cellLatest;
  constexpr std::uint32_t kEndOfCell = std::numeric_limits<std::uint32_t>::max();
  // A vertex at the position of an earlier one (most of them: a triangle
  // soup repeats each corner) welds where the first one did: it searches the
  // same cells, where every vertex kept since lies after the first one's
  // answer. -0 and +0 are one position.
  FirstCopies firstCopies(vertices);
  // An axis's key, and the cells either side to look in too (0 or -1, 0 or
  // 1): none when it is keyed by value.
  struct AxisKey {
    std::int64_t key;
    int below = 0, above = 0;
  };
  auto keyOf = [&](double c) {
    if (tolerance == 0 || !(std::abs(c) <= kGridCells * cellWidth))
      // -0 and +0 are one position; clean has rounded c to a float already.
      return AxisKey{kExactKeys + std::bit_cast<std::uint32_t>(static_cast<float>(c) + 0.0f)};
    const double cells = c / cellWidth, cell = std::floor(cells);
    return AxisKey{static_cast<std::int64_t>(cell), cells - cell < nearSide ? -1 : 0,
                   cell + 1 - cells < nearSide ? 1 : 0};
  };
  for (std::uint32_t i = 0; i < vertices.size(); ++i) {
    const Eigen::Vector3d& p = vertices[i];
    if (const std::uint32_t first = firstCopies.firstOf(i); first != i) {
      target[i] = target[first];
      continue;
    }
    const AxisKey x = keyOf(p.x()), y = keyOf(p.y()), z = keyOf(p.z());
    std::uint32_t best = i;
    for (int dx = x.below; dx <= x.above; ++dx)
      for (int dy = y.below; dy <= y.above; ++dy)
        for (int dz = z.below; dz <= z.above; ++dz) {
          const std::uint32_t* latest = cellLatest.find({x.key + dx, y.key + dy, z.key + dz});
          for (std::uint32_t e = latest ? *latest : kEndOfCell; e != kEndOfCell;
               e = kept[e].previous) {
            const std::uint32_t j = kept[e].vertex;
            if (j < best && (vertices[j] - p).squaredNorm() <= tolerance2) best = j;
          }
        }
    target[i] = best;
    if (best == i) {
      const auto entry = static_cast<std::uint32_t>(kept.size());
      const auto [latest, added] = cellLatest.tryEmplace({x.key, y.key, z.key}, entry);
      kept.push_back({i, added ? kEndOfCell : *latest});
      *latest = entry;
    }
  }
  return target;
}

// A triangle's corners as a key (compared member by member).
struct TriangleKey {
  std::uint32_t a, b, c;
  bool operator==(const TriangleKey&) const = default;
};
struct TriangleHash {
  std::uint64_t operator()(const TriangleKey& t) const {
    return (std::uint64_t(t.a) * 73856093u) ^ (std::uint64_t(t.b) * 19349663u) ^
           (std::uint64_t(t.c) * 83492791u);
  }
};

// The same triangle under any rotation of its corners, winding kept.
std::array<std::uint32_t, 3> canonicalRotation(const std::array<std::uint32_t, 3>& t) {
  if (t[1] < t[0] && t[1] < t[2]) return {t[1], t[2], t[0]};
  if (t[2] < t[0] && t[2] < t[1]) return {t[2], t[0], t[1]};
  return t;
}

// The surface table as the mesh gives it: its own, or kDefaultSurface.
std::vector<std::string> surfaceNames(const Mesh& mesh) {
  return mesh.surfaces.empty() ? std::vector<std::string>{kDefaultSurface} : mesh.surfaces;
}

// Up to 8 names, quoted, for an error message.
std::string someNames(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < 8; ++i) out += (i ? ", '" : "'") + names[i] + "'";
  if (names.size() > 8) out += ", ... (" + std::to_string(names.size()) + " in all)";
  return out;
}

// Whether each surface of the mesh is kept by the selection. Throws for a
// name the mesh has no surface of.
std::vector<bool> keptSurfaces(const std::vector<std::string>& names,
                               const CleanSettings& settings) {
  const bool only = !settings.onlySurfaces.empty();
  std::vector<bool> kept(names.size(), !only);
  for (const std::vector<std::string>* given : {&settings.dropSurfaces, &settings.onlySurfaces})
    for (const std::string& name : *given) {
      const auto at = std::find(names.begin(), names.end(), name);
      if (at == names.end())
        throw CompileError("no surface (material) is named '" + name + "' (given to " +
                           (given == &settings.onlySurfaces ? "--only-surface" : "--drop-surface") +
                           "); the surfaces are " + someNames(names));
      for (auto it = at; it != names.end(); it = std::find(it + 1, names.end(), name))
        kept[it - names.begin()] = only;
    }
  return kept;
}

std::string shortNumber(double value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

Mesh cleanMesh(const Mesh& mesh, const CleanSettings& settings, CleanReport& report) {
  report = CleanReport{};
  report.inputVertices = static_cast<std::uint32_t>(mesh.vertices.size());
  report.inputTriangles = static_cast<std::uint32_t>(mesh.triangles.size());

  // The blob stores floats: clean and compute everything on what it will hold.
  std::vector<Eigen::Vector3d> rounded(mesh.vertices.size());
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const double c = mesh.vertices[i][k];
      const float f = static_cast<float>(c);
      if (!std::isfinite(c) || !std::isfinite(f))
        throw CompileError("vertex " + std::to_string(i) + " has a coordinate that is " +
                           (std::isfinite(c) ? "too large for a float" : "not finite"));
      // The runtime refuses a blob beyond its bound; say so here, in the
      // source's terms, rather than write a level no game can load.
      if (std::abs(f) > bspf::kMaxCoordinate)
        throw CompileError("vertex " + std::to_string(i) + " has a coordinate of " +
                           shortNumber(c) + " m, beyond the runtime's bound of 1e5 m" +
                           " (check --scale)");
      rounded[i][k] = f;
    }
  }
  const std::vector<std::uint32_t> target = weld(rounded, settings.weldTolerance);
  for (std::uint32_t i = 0; i < target.size(); ++i) report.weldedVertices += target[i] != i;

  const std::vector<std::string> names = surfaceNames(mesh);
  if (!mesh.triangleSurfaces.empty() && mesh.triangleSurfaces.size() != mesh.triangles.size())
    throw CompileError("the mesh's triangle surfaces and triangles differ in number");
  const std::vector<bool> keep = keptSurfaces(names, settings);
  // Old surface index -> index in out.surfaces, in the order of first use.
  std::vector<std::uint32_t> newSurface(names.size(), std::numeric_limits<std::uint32_t>::max());
  std::unordered_map<std::string, std::uint32_t> surfaceByName;

  Mesh out;
  std::vector<std::uint32_t> newIndex(rounded.size(), std::numeric_limits<std::uint32_t>::max());
  FlatMap<TriangleKey, bool, TriangleHash> seen(mesh.triangles.size());
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    const std::uint32_t surface = mesh.triangleSurfaces.empty() ? 0 : mesh.triangleSurfaces[t];
    if (surface >= names.size())
      throw CompileError("triangle " + std::to_string(t) + " has a surface index out of range");
    if (!keep[surface]) {
      ++report.droppedBySurface;
      continue;
    }
    std::array<std::uint32_t, 3> tri;
    for (int k = 0; k < 3; ++k) {
      const std::uint32_t v = mesh.triangles[t][k];
      if (v >= rounded.size())
        throw CompileError("triangle " + std::to_string(t) + " has a vertex index out of range");
      tri[k] = target[v];
    }
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      ++report.droppedDegenerate;
      continue;
    }
    const double area =
        0.5 * (rounded[tri[1]] - rounded[tri[0]]).cross(rounded[tri[2]] - rounded[tri[0]]).norm();
    if (!(area > settings.minTriangleArea) || area == 0) {
      ++report.droppedZeroArea;
      continue;
    }
    auto corner = [&](int k) {
      const Eigen::Vector3d& v = rounded[tri[k]];
      return bspf::schema::Vec3(float(v.x()), float(v.y()), float(v.z()));
    };
    // A line to float precision (the runtime would refuse the blob) is
    // degenerate, however large its area.
    if (!bspf::isUsableTriangle(corner(0), corner(1), corner(2))) {
      ++report.droppedDegenerate;
      continue;
    }
    const std::array<std::uint32_t, 3> rotated = canonicalRotation(tri);
    if (!seen.tryEmplace({rotated[0], rotated[1], rotated[2]}, true).second) {
      ++report.droppedDuplicate;
      continue;
    }
    std::array<std::uint32_t, 3> kept;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& index = newIndex[tri[k]];
      if (index == std::numeric_limits<std::uint32_t>::max()) {
        index = static_cast<std::uint32_t>(out.vertices.size());
        out.vertices.push_back(rounded[tri[k]]);
      }
      kept[k] = index;
    }
    out.triangles.push_back(kept);
    std::uint32_t& renumbered = newSurface[surface];
    if (renumbered == std::numeric_limits<std::uint32_t>::max()) {
      // Surfaces of one name (a mesh made in memory may repeat one) merge.
      const auto [at, added] = surfaceByName.try_emplace(
          names[surface], static_cast<std::uint32_t>(out.surfaces.size()));
      if (added) out.surfaces.push_back(names[surface]);
      renumbered = at->second;
    }
    out.triangleSurfaces.push_back(renumbered);
  }
  // The blob's surface ids are 16-bit.
  if (out.surfaces.size() > 65536)
    throw CompileError("more than 65536 surfaces (materials): " +
                       std::to_string(out.surfaces.size()) + " (merge materials)");
  report.outputVertices = static_cast<std::uint32_t>(out.vertices.size());
  report.outputTriangles = static_cast<std::uint32_t>(out.triangles.size());
  if (out.triangles.empty() && report.droppedBySurface == report.inputTriangles)
    throw CompileError("no triangle is left: the surface selection left out all " +
                       std::to_string(report.inputTriangles) + " triangles");
  if (out.triangles.empty() && report.droppedBySurface > 0)
    throw CompileError("no triangle is left: the surface selection left out " +
                       std::to_string(report.droppedBySurface) + " of " +
                       std::to_string(report.inputTriangles) +
                       " triangles, and cleaning dropped the rest");
  if (out.triangles.empty())
    throw CompileError("no triangle is left after cleaning (" +
                       std::to_string(report.inputTriangles) + " degenerate or zero-area)");
  return out;
}

}  // namespace bspc
