// SPDX-License-Identifier: MIT
// The whole compile: the blob holds the input's triangles with correct planes,
// every leaf lists every triangle overlapping its cell, output is
// deterministic, settings act as documented, metadata and the CLI report it.
#include <bspc/clean.h>
#include <bspc/compile.h>
#include <bspc/edges.h>
#include <bspc/import.h>
#include <bspc/settings.h>
#include <bspf/world.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace fs = std::filesystem;
using bspf::test::AlignedBytes;
using Eigen::Vector3d;

namespace {

// ---------------------------------------------------------------- helpers

std::vector<std::uint8_t> readBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  REQUIRE(in);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  REQUIRE(out);
}

std::string quoted(const fs::path& path) {
  std::string out = "'";
  for (const char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

std::string bspcCommand() { return quoted(bspf::test::bspcExecutable()); }

fs::path arenaObj() { return bspf::test::samplesDir() / "arena.obj"; }

// A blob in memory, viewed in place (the bytes live as long as the World).
struct ViewedWorld {
  std::unique_ptr<AlignedBytes> bytes;
  bspf::World world;
};

ViewedWorld viewBlob(const std::vector<std::uint8_t>& blob) {
  auto bytes = std::make_unique<AlignedBytes>(blob);
  bspf::OpenResult opened = bspf::viewWorld(bytes->span());
  INFO(opened.message);
  REQUIRE(opened);
  return {std::move(bytes), *opened.world};
}

bspf::World openFile(const fs::path& path) {
  bspf::OpenResult opened = bspf::openWorld(path);
  INFO(opened.message);
  REQUIRE(opened);
  return *opened.world;
}

// arena.obj compiled once with default settings through compileFile, shared by
// the tests that only read it (a compile of the arena takes about half a
// second in Debug).
struct ArenaBuild {
  fs::path output;
  bspc::CompileReport report;
  bspf::World world;
};

const ArenaBuild& arenaBuild() {
  static const ArenaBuild build = [] {
    const fs::path dir = bspf::test::freshTempDir("compile-arena");
    const fs::path output = dir / "arena.bspf";
    const bspc::CompileReport report = bspc::compileFile(arenaObj(), output, {});
    return ArenaBuild{output, report, openFile(output)};
  }();
  return build;
}

// A level-like mesh in memory: boxes (one far from the origin), a tilted
// box-ish prism, and random triangles with fixed seed, so splits are oblique.
bspc::Mesh mixedMesh() {
  bspc::Mesh mesh = bspf::test::boxMesh({-10, -1, -10}, {10, 0, 10});
  bspf::test::append(mesh, bspf::test::boxMesh({-2, 0, -2}, {-1, 3, -1}));
  bspf::test::append(mesh, bspf::test::boxMesh({3, 0, 4}, {5, 0.5, 8}));
  bspf::test::append(mesh, bspf::test::boxMesh({500, 20, -300}, {502, 21, -298}));
  // A ramp: a box sheared along x.
  bspc::Mesh ramp = bspf::test::boxMesh({-8, 0, 2}, {-4, 1, 6});
  for (Vector3d& v : ramp.vertices) v.y() += 0.35 * (v.x() + 8);
  bspf::test::append(mesh, ramp);
  std::mt19937 rng(1234);
  std::uniform_real_distribution<double> coordinate(-9.5, 9.5);
  int added = 0;
  while (added < 60) {
    const Vector3d a(coordinate(rng), std::abs(coordinate(rng)) * 0.4, coordinate(rng));
    const Vector3d b = a + Vector3d(coordinate(rng), coordinate(rng), coordinate(rng)) * 0.2;
    const Vector3d c = a + Vector3d(coordinate(rng), coordinate(rng), coordinate(rng)) * 0.2;
    const Vector3d n = (b - a).cross(c - a);
    // Well-shaped triangles only: area and smallest height not tiny.
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    if (n.norm() < 0.5 || n.norm() / longest < 0.2) continue;
    const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {a, b, c});
    mesh.triangles.push_back({base, base + 1, base + 2});
    ++added;
  }
  return mesh;
}

Vector3d toDouble(const bspf::schema::Vec3& v) { return {v.x(), v.y(), v.z()}; }
Vector3d toDouble(const bspf::schema::Plane& p) { return toDouble(p.normal()); }
double side(const bspf::schema::Plane& plane, const Vector3d& p) {
  return toDouble(plane.normal()).dot(p) - double(plane.distance());
}

using Corners = std::array<Vector3d, 3>;

// The input's triangles as the blob should hold them: corners rounded to float.
std::vector<Corners> referenceTriangles(const bspc::Mesh& mesh) {
  std::vector<Corners> out;
  for (const auto& t : mesh.triangles) {
    Corners c;
    for (int k = 0; k < 3; ++k) c[k] = mesh.vertices[t[k]].cast<float>().cast<double>();
    out.push_back(c);
  }
  return out;
}

Corners corners(const bspf::World& world, std::uint32_t triangle) {
  const bspf::schema::Triangle& t = world.triangles()[triangle];
  const auto v = world.vertices();
  return {toDouble(v[t.v0()]), toDouble(v[t.v1()]), toDouble(v[t.v2()])};
}

double magnitude(const Corners& c) {
  double m = 1.0;
  for (const Vector3d& v : c) m = std::max(m, v.cwiseAbs().maxCoeff());
  return m;
}

// Equal as vertex triples up to a rotation of the corners (winding kept).
bool sameTriangle(const Corners& a, const Corners& b) {
  const double tolerance = 1e-6 * std::max(magnitude(a), magnitude(b));
  for (int r = 0; r < 3; ++r) {
    bool all = true;
    for (int k = 0; k < 3 && all; ++k)
      all = (a[k] - b[(k + r) % 3]).cwiseAbs().maxCoeff() <= tolerance;
    if (all) return true;
  }
  return false;
}

std::string show(const Corners& c) {
  std::ostringstream out;
  for (const Vector3d& v : c) out << "(" << v.x() << ", " << v.y() << ", " << v.z() << ") ";
  return out.str();
}

// `mesh` cleaned and without its covered faces, as bspc keeps it; checks that
// bspc reported dropping as many.
bspc::Mesh withoutCoveredFaces(const bspc::Mesh& mesh, std::uint32_t reported) {
  bspc::CleanReport clean;
  bspc::EdgeReport edges;
  bspc::Mesh kept = bspc::dropCoveredFaces(bspc::cleanMesh(mesh, {}, clean), edges);
  CHECK(edges.droppedCovered == reported);
  return kept;
}

// Every input triangle is in the blob and every blob triangle comes from the
// input, as vertex triples up to rotation with the winding kept.
void checkSameTriangles(const bspc::Mesh& input, const bspf::World& world) {
  const std::vector<Corners> reference = referenceTriangles(input);
  std::vector<Corners> stored;
  for (std::uint32_t t = 0; t < world.triangles().size(); ++t) stored.push_back(corners(world, t));
  for (const Corners& r : reference) {
    const bool found = std::any_of(stored.begin(), stored.end(),
                                   [&](const Corners& s) { return sameTriangle(r, s); });
    INFO("input triangle " << show(r));
    CHECK(found);
  }
  for (const Corners& s : stored) {
    const bool found = std::any_of(reference.begin(), reference.end(),
                                   [&](const Corners& r) { return sameTriangle(r, s); });
    INFO("stored triangle " << show(s));
    CHECK(found);
  }
}

// The face, edge and cap planes of every triangle, as the schema documents them.
void checkTrianglePlanes(const bspf::World& world) {
  REQUIRE(world.trianglePlanes().size() == world.triangles().size());
  int failures = 0;
  for (std::uint32_t t = 0; t < world.triangles().size() && failures < 10; ++t) {
    const Corners v = corners(world, t);
    const bspf::schema::TrianglePlanes& planes = world.trianglePlanes()[t];
    const double tolerance = 1e-5 * magnitude(v);
    INFO("triangle " << t << ": " << show(v));
    bool ok = true;
    auto check = [&](bool condition, const char* what) {
      if (!condition) {
        ok = false;
        FAIL_CHECK(what);
      }
    };

    const bspf::schema::Plane& face = planes.face();
    const Vector3d faceNormal = toDouble(face);
    const Vector3d rightHand = (v[1] - v[0]).cross(v[2] - v[0]).normalized();
    check(std::abs(faceNormal.norm() - 1) <= 1e-6, "face normal has unit length");
    check(faceNormal.dot(rightHand) >= 1 - 1e-6, "face normal follows the right-hand rule");
    for (int k = 0; k < 3; ++k)
      check(std::abs(side(face, v[k])) <= tolerance, "face plane contains the corners");

    for (int i = 0; i < 3; ++i) {
      const bspf::schema::Plane& edge = *planes.edges()->Get(i);
      INFO("edge " << i << " side of opposite corner " << side(edge, v[(i + 2) % 3]));
      check(std::abs(toDouble(edge).norm() - 1) <= 1e-6, "edge normal has unit length");
      check(std::abs(side(edge, v[i])) <= tolerance, "edge plane contains corner i");
      check(std::abs(side(edge, v[(i + 1) % 3])) <= tolerance, "edge plane contains corner i+1");
      check(std::abs(toDouble(edge).dot(faceNormal)) <= 1e-5,
            "edge plane is perpendicular to the face");
      check(side(edge, v[(i + 2) % 3]) > 0, "opposite corner is in front of the edge plane");
    }
    for (int i = 0; i < 3; ++i) {
      const bspf::schema::Plane& cap = *planes.caps()->Get(i);
      const Vector3d opposite = (v[(i + 2) % 3] - v[(i + 1) % 3]).normalized();
      INFO("cap " << i << " sides " << side(cap, v[(i + 1) % 3]) << ", "
                  << side(cap, v[(i + 2) % 3]));
      check(std::abs(toDouble(cap).norm() - 1) <= 1e-6, "cap normal has unit length");
      check(std::abs(side(cap, v[i])) <= tolerance, "cap plane contains corner i");
      check(std::abs(toDouble(cap).dot(opposite)) <= 1e-5,
            "cap plane is parallel to the opposite edge");
      check(side(cap, v[(i + 1) % 3]) > 0 && side(cap, v[(i + 2) % 3]) > 0,
            "the other corners are in front of the cap plane");
    }
    if (!ok) ++failures;
  }
  CHECK(failures == 0);
}

// ---------------------------------------------------------------- leaf cells

struct HalfSpace {
  const bspf::schema::Plane* plane;
  bool front;
};

// Every leaf's cell: the half-spaces of the nodes on its path from the root.
std::vector<std::vector<HalfSpace>> leafCells(const bspf::World& world) {
  std::vector<std::vector<HalfSpace>> cells(world.leaves().size());
  std::vector<int> seen(world.leaves().size(), 0);
  std::vector<HalfSpace> path;
  auto walk = [&](auto&& self, std::int32_t ref) -> void {
    if (ref < 0) {
      const auto leaf = static_cast<std::uint32_t>(-ref - 1);
      REQUIRE(leaf < cells.size());
      cells[leaf] = path;
      ++seen[leaf];
      return;
    }
    const bspf::schema::Node& node = world.nodes()[ref];
    path.push_back({&node.split(), true});
    self(self, node.front());
    path.back().front = false;
    self(self, node.back());
    path.pop_back();
  };
  walk(walk, world.root());
  for (std::size_t leaf = 0; leaf < seen.size(); ++leaf) {
    INFO("leaf " << leaf);
    REQUIRE(seen[leaf] == 1);
  }
  return cells;
}

constexpr double kTie = 1e-4;

// Whether triangle `corners` lies in `plane` (then the compiler lists it only
// on the side its normal faces, as build_tree.h documents).
bool liesIn(const bspf::schema::Plane& plane, const Corners& c) {
  return std::all_of(c.begin(), c.end(),
                     [&](const Vector3d& v) { return std::abs(side(plane, v)) < kTie; });
}

// The leaves a point of `triangle` falls into: descend from the root, going
// both ways when the point is within kTie of a split plane (except for a
// triangle lying in the plane, which only belongs to the side it faces).
void descend(const bspf::World& world, std::int32_t ref, const Vector3d& p, const Corners& triangle,
             std::vector<std::uint32_t>& leaves) {
  if (ref < 0) {
    leaves.push_back(static_cast<std::uint32_t>(-ref - 1));
    return;
  }
  const bspf::schema::Node& node = world.nodes()[ref];
  const double s = side(node.split(), p);
  bool front = s > -kTie, back = s < kTie;
  if (front && back && liesIn(node.split(), triangle)) {
    const Vector3d n = (triangle[1] - triangle[0]).cross(triangle[2] - triangle[0]);
    front = n.dot(toDouble(node.split())) >= 0;
    back = !front;
  }
  if (front) descend(world, node.front(), p, triangle, leaves);
  if (back) descend(world, node.back(), p, triangle, leaves);
}

bool inCell(const std::vector<HalfSpace>& cell, const Vector3d& p) {
  return std::all_of(cell.begin(), cell.end(), [&](const HalfSpace& h) {
    const double s = side(*h.plane, p);
    return h.front ? s > -kTie : s < kTie;
  });
}

// Points of a triangle: corners, centroid, edge midpoints and random
// barycentric points (fixed seed).
std::vector<Vector3d> samplePoints(const Corners& c, std::mt19937& rng) {
  std::vector<Vector3d> points{c[0],
                               c[1],
                               c[2],
                               (c[0] + c[1] + c[2]) / 3.0,
                               (c[0] + c[1]) / 2.0,
                               (c[1] + c[2]) / 2.0,
                               (c[2] + c[0]) / 2.0};
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < 12; ++i) {
    const double r1 = std::sqrt(unit(rng)), r2 = unit(rng);
    points.push_back((1 - r1) * c[0] + r1 * (1 - r2) * c[1] + r1 * r2 * c[2]);
  }
  return points;
}

void checkLeavesCoverTriangles(const bspf::World& world) {
  const std::vector<std::vector<HalfSpace>> cells = leafCells(world);
  std::mt19937 rng(20240601);
  int failures = 0;
  for (std::uint32_t t = 0; t < world.triangles().size() && failures < 10; ++t) {
    const Corners c = corners(world, t);
    const std::vector<Vector3d> points = samplePoints(c, rng);
    for (std::size_t i = 0; i < points.size(); ++i) {
      std::vector<std::uint32_t> leaves;
      descend(world, world.root(), points[i], c, leaves);
      REQUIRE(!leaves.empty());
      for (const std::uint32_t leaf : leaves) {
        // The leaf reached is one whose derived cell holds the point.
        REQUIRE(inCell(cells[leaf], points[i]));
        const auto list = world.leafTriangleList(leaf);
        if (std::find(list.begin(), list.end(), t) == list.end()) {
          ++failures;
          FAIL_CHECK("leaf " << leaf << " (cell of " << cells[leaf].size()
                             << " half-spaces) holds point " << i << " of triangle " << t << " "
                             << show(c) << " but does not list it");
        }
      }
      // Cross-check the descent against the cells for the centroid: every
      // leaf whose cell holds the point (beyond the ties) is reached.
      if (i == 3) {
        for (std::uint32_t leaf = 0; leaf < cells.size(); ++leaf) {
          const bool strictlyInside =
              std::all_of(cells[leaf].begin(), cells[leaf].end(), [&](const HalfSpace& h) {
                const double s = side(*h.plane, points[i]);
                return h.front ? s > kTie : s < -kTie;
              });
          if (strictlyInside) CHECK(std::find(leaves.begin(), leaves.end(), leaf) != leaves.end());
        }
      }
    }
  }
  CHECK(failures == 0);
}

// ---------------------------------------------------------------- JSON

// A strict little JSON reader that flattens nested objects into "a.b" keys
// with the raw text of scalar values. std::nullopt when the text is not JSON.
class FlatJson {
 public:
  static std::optional<std::map<std::string, std::string>> parse(const std::string& text) {
    FlatJson reader(text);
    reader.skipSpace();
    if (!reader.value("")) return std::nullopt;
    reader.skipSpace();
    if (reader.at_ != text.size()) return std::nullopt;
    return reader.out_;
  }

 private:
  explicit FlatJson(const std::string& text) : text_(text) {}
  bool more() const { return at_ < text_.size(); }
  char peek() const { return more() ? text_[at_] : '\0'; }
  void skipSpace() {
    while (more() && std::isspace(static_cast<unsigned char>(peek()))) ++at_;
  }
  bool literal(const std::string& word) {
    if (text_.compare(at_, word.size(), word) != 0) return false;
    at_ += word.size();
    return true;
  }
  bool string(std::string& out) {
    if (peek() != '"') return false;
    ++at_;
    while (more() && peek() != '"') {
      if (peek() == '\\') {
        ++at_;
        if (!more()) return false;
      } else if (static_cast<unsigned char>(peek()) < 0x20) {
        return false;
      }
      out += text_[at_++];
    }
    if (!more()) return false;
    ++at_;
    return true;
  }
  bool number(std::string& out) {
    const std::size_t start = at_;
    auto digits = [&] {
      const std::size_t from = at_;
      while (std::isdigit(static_cast<unsigned char>(peek()))) ++at_;
      return at_ > from;
    };
    if (peek() == '-') ++at_;
    if (peek() == '0') {
      ++at_;
    } else if (!digits()) {
      return false;
    }
    if (peek() == '.') {
      ++at_;
      if (!digits()) return false;
    }
    if (peek() == 'e' || peek() == 'E') {
      ++at_;
      if (peek() == '+' || peek() == '-') ++at_;
      if (!digits()) return false;
    }
    out = text_.substr(start, at_ - start);
    return true;
  }
  bool value(const std::string& path) {
    skipSpace();
    if (peek() == '{') {
      ++at_;
      skipSpace();
      if (peek() == '}') return ++at_, true;
      while (true) {
        skipSpace();
        std::string key;
        if (!string(key)) return false;
        skipSpace();
        if (peek() != ':') return false;
        ++at_;
        if (!value(path.empty() ? key : path + "." + key)) return false;
        skipSpace();
        if (peek() == ',') {
          ++at_;
          continue;
        }
        if (peek() == '}') return ++at_, true;
        return false;
      }
    }
    if (peek() == '[') {
      ++at_;
      skipSpace();
      if (peek() == ']') return ++at_, true;
      for (int i = 0;; ++i) {
        if (!value(path + "[" + std::to_string(i) + "]")) return false;
        skipSpace();
        if (peek() == ',') {
          ++at_;
          continue;
        }
        if (peek() == ']') return ++at_, true;
        return false;
      }
    }
    std::string scalar;
    if (peek() == '"') {
      if (!string(scalar)) return false;
    } else if (literal("true")) {
      scalar = "true";
    } else if (literal("false")) {
      scalar = "false";
    } else if (literal("null")) {
      scalar = "null";
    } else if (!number(scalar)) {
      return false;
    }
    out_[path] = scalar;
    return true;
  }

  const std::string& text_;
  std::size_t at_ = 0;
  std::map<std::string, std::string> out_;
};

// `bspc --info` output: "name  value" lines, the name in a 24-column field.
std::map<std::string, std::string> infoLines(const std::string& text) {
  std::map<std::string, std::string> out;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (line.size() <= 24) continue;
    std::string name = line.substr(0, 24);
    name.erase(name.find_last_not_of(' ') + 1);
    out[name] = line.substr(24);
  }
  return out;
}

}  // namespace

// ==================================================================== round trip

TEST_CASE("compiling arena.obj keeps every imported triangle with its winding",
          "[compiler][compile]") {
  const ArenaBuild& build = arenaBuild();
  const bspc::Mesh imported = bspc::importMesh(arenaObj(), {});
  REQUIRE(imported.triangles.size() == 364);
  // Cleaning drops nothing from the sample, so every imported triangle must
  // appear but the faces pressed against another solid (dropCoveredFaces).
  CHECK(build.report.clean.droppedDegenerate == 0);
  CHECK(build.report.clean.droppedZeroArea == 0);
  CHECK(build.report.clean.droppedDuplicate == 0);
  const bspc::Mesh kept = withoutCoveredFaces(imported, build.report.edges.droppedCovered);
  CHECK(build.world.triangles().size() == kept.triangles.size());
  checkSameTriangles(kept, build.world);
}

TEST_CASE("compiling a mesh in memory keeps every triangle with its winding",
          "[compiler][compile]") {
  const bspc::Mesh mesh = mixedMesh();
  bspc::CompileReport report;
  const ViewedWorld compiled = viewBlob(bspc::compileMesh(mesh, {}, "mixed", report));
  CHECK(report.clean.droppedDegenerate + report.clean.droppedZeroArea +
            report.clean.droppedDuplicate ==
        0);
  const bspc::Mesh kept = withoutCoveredFaces(mesh, report.edges.droppedCovered);
  CHECK(compiled.world.triangles().size() == kept.triangles.size());
  checkSameTriangles(kept, compiled.world);
}

TEST_CASE("face, edge and cap planes of arena.obj contain and face their triangle",
          "[compiler][compile]") {
  checkTrianglePlanes(arenaBuild().world);
}

TEST_CASE("face, edge and cap planes of an oblique mesh contain and face their triangle",
          "[compiler][compile]") {
  checkTrianglePlanes(viewBlob(bspf::test::compile(mixedMesh())).world);
}

// ==================================================================== leaves

TEST_CASE("every leaf of arena.obj lists every triangle that overlaps its cell",
          "[compiler][compile]") {
  SECTION("default settings") { checkLeavesCoverTriangles(arenaBuild().world); }
  SECTION("small leaves, oblique triangle-plane splits") {
    bspc::CompileSettings settings;
    settings.tree.maxLeafTriangles = 2;
    settings.tree.queryReach = 0;
    settings.tree.candidates = bspc::SplitCandidates::Triangle;
    bspc::CompileReport report;
    const bspc::Mesh imported = bspc::importMesh(arenaObj(), {});
    const ViewedWorld compiled =
        viewBlob(bspc::compileMesh(imported, settings, "arena.obj", report));
    CHECK(compiled.world.leaves().size() > arenaBuild().world.leaves().size());
    checkLeavesCoverTriangles(compiled.world);
  }
}

TEST_CASE("every leaf of an oblique mesh lists every triangle that overlaps its cell",
          "[compiler][compile]") {
  bspc::CompileSettings settings;
  SECTION("default settings") {}
  SECTION("one triangle per leaf, no reach") {
    settings.tree.maxLeafTriangles = 1;
    settings.tree.queryReach = 0;
  }
  SECTION("axis-aligned candidates only") {
    settings.tree.candidates = bspc::SplitCandidates::Axis;
  }
  const ViewedWorld compiled = viewBlob(bspf::test::compile(mixedMesh(), settings));
  CHECK(compiled.world.nodes().size() > 0);
  checkLeavesCoverTriangles(compiled.world);
}

// ==================================================================== determinism

TEST_CASE("compiling the same input twice gives identical bytes", "[compiler][compile]") {
  const std::vector<std::uint8_t> first = readBytes(arenaBuild().output);

  SECTION("files: again, in another directory, and from a copy of the input elsewhere") {
    const fs::path dir = bspf::test::freshTempDir("compile-determinism");
    fs::create_directories(dir / "elsewhere" / "deeper");
    bspc::compileFile(arenaObj(), dir / "arena.bspf", {});
    CHECK(readBytes(dir / "arena.bspf") == first);
    bspc::compileFile(arenaObj(), dir / "elsewhere" / "deeper" / "other-name.bspf", {});
    CHECK(readBytes(dir / "elsewhere" / "deeper" / "other-name.bspf") == first);
    // The source is recorded by file name only, so its directory does not matter.
    fs::copy_file(arenaObj(), dir / "elsewhere" / "arena.obj");
    bspc::compileFile(dir / "elsewhere" / "arena.obj", dir / "copy.bspf", {});
    CHECK(readBytes(dir / "copy.bspf") == first);
  }
  SECTION("a mesh in memory, and compileFile equals compileMesh on the imported mesh") {
    const bspc::Mesh mesh = mixedMesh();
    CHECK(bspf::test::compile(mesh) == bspf::test::compile(mesh));
    bspc::CompileReport report;
    CHECK(bspc::compileMesh(bspc::importMesh(arenaObj(), {}), {}, "arena.obj", report) == first);
  }
}

// ==================================================================== settings

TEST_CASE("a smaller max-leaf-triangles gives at least as many leaves", "[compiler][compile]") {
  const bspc::Mesh imported = bspc::importMesh(arenaObj(), {});
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = 2;
  bspc::CompileReport report;
  const ViewedWorld small = viewBlob(bspc::compileMesh(imported, settings, "arena.obj", report));
  const bspf::World& normal = arenaBuild().world;
  CHECK(small.world.leaves().size() >= normal.leaves().size());
  CHECK(small.world.blob().build()->max_leaf_triangles() == 2);

  // The same on the in-memory mesh, over a range of sizes.
  const bspc::Mesh mesh = mixedMesh();
  std::size_t previous = 0;
  for (const std::uint32_t size : {64u, 16u, 4u, 1u}) {
    bspc::CompileSettings s;
    s.tree.maxLeafTriangles = size;
    const ViewedWorld compiled = viewBlob(bspf::test::compile(mesh, s));
    INFO("max leaf triangles " << size);
    CHECK(compiled.world.leaves().size() >= previous);
    previous = compiled.world.leaves().size();
  }
}

TEST_CASE("max-depth 1 gives a tree of depth at most 1", "[compiler][compile]") {
  bspc::CompileSettings settings;
  settings.tree.maxDepth = 1;
  settings.tree.maxLeafTriangles = 1;
  const ViewedWorld compiled = viewBlob(bspf::test::compile(mixedMesh(), settings));
  CHECK(compiled.world.treeDepth() <= 1);
  CHECK(bspf::computeTreeStats(compiled.world).depthMax <= 1);
  CHECK(compiled.world.nodes().size() <= 1);
  for (const std::vector<HalfSpace>& cell : leafCells(compiled.world)) CHECK(cell.size() <= 1);
  CHECK(compiled.world.blob().build()->max_depth() == 1);
}

TEST_CASE("up=z and up=x rotate the source's up axis onto +Y, keeping the winding",
          "[compiler][compile]") {
  const fs::path dir = bspf::test::freshTempDir("compile-up");
  // One triangle in the source plane z = 1, counter-clockwise seen from +Z.
  writeText(dir / "tri.obj", "v 0 0 1\nv 1 0 1\nv 0 1 1\nf 1 2 3\n");
  auto compileWith = [&](bspc::UpAxis up) {
    bspc::CompileSettings settings;
    settings.import.up = up;
    const fs::path output = dir / (std::string("up-") + bspc::toString(up) + ".bspf");
    bspc::compileFile(dir / "tri.obj", output, settings);
    return openFile(output);
  };
  auto hasVertex = [](const bspf::World& world, const Vector3d& p) {
    return std::any_of(
        world.vertices().begin(), world.vertices().end(),
        [&](const bspf::schema::Vec3& v) { return (toDouble(v) - p).norm() < 1e-6; });
  };
  SECTION("up=z: (x, y, z) -> (x, z, -y)") {
    const bspf::World world = compileWith(bspc::UpAxis::Z);
    CHECK(hasVertex(world, {0, 1, 0}));   // source (0, 0, 1)
    CHECK(hasVertex(world, {1, 1, 0}));   // source (1, 0, 1)
    CHECK(hasVertex(world, {0, 1, -1}));  // source (0, 1, 1)
    CHECK(world.blob().bounds_max()->y() == Approx(1.0));
    CHECK(world.blob().bounds_min()->y() == Approx(1.0));
    // The source normal +Z is now up.
    const Vector3d normal = toDouble(world.trianglePlanes()[0].face());
    CHECK(normal.y() == Approx(1.0));
    CHECK(world.blob().build()->source_up_axis() == bspf::schema::UpAxis::Z);
  }
  SECTION("up=x: (x, y, z) -> (-y, x, z)") {
    const bspf::World world = compileWith(bspc::UpAxis::X);
    CHECK(hasVertex(world, {0, 0, 1}));   // source (0, 0, 1)
    CHECK(hasVertex(world, {0, 1, 1}));   // source (1, 0, 1): +X is now up
    CHECK(hasVertex(world, {-1, 0, 1}));  // source (0, 1, 1)
    const Vector3d normal = toDouble(world.trianglePlanes()[0].face());
    CHECK(normal.z() == Approx(1.0));
    CHECK(world.blob().build()->source_up_axis() == bspf::schema::UpAxis::X);
  }
  SECTION("up=y leaves the source as it is") {
    const bspf::World world = compileWith(bspc::UpAxis::Y);
    CHECK(hasVertex(world, {0, 0, 1}));
    CHECK(hasVertex(world, {1, 0, 1}));
    CHECK(hasVertex(world, {0, 1, 1}));
  }
}

TEST_CASE("scale 0.5 halves the bounds", "[compiler][compile]") {
  const fs::path dir = bspf::test::freshTempDir("compile-scale");
  bspc::CompileSettings settings;
  settings.import.scale = 0.5;
  bspc::compileFile(arenaObj(), dir / "half.bspf", settings);
  const bspf::World half = openFile(dir / "half.bspf");
  const bspf::World& full = arenaBuild().world;
  const auto *lowHalf = half.blob().bounds_min(), *highHalf = half.blob().bounds_max();
  const auto *lowFull = full.blob().bounds_min(), *highFull = full.blob().bounds_max();
  CHECK(lowHalf->x() == Approx(0.5 * lowFull->x()));
  CHECK(lowHalf->y() == Approx(0.5 * lowFull->y()));
  CHECK(lowHalf->z() == Approx(0.5 * lowFull->z()));
  CHECK(highHalf->x() == Approx(0.5 * highFull->x()));
  CHECK(highHalf->y() == Approx(0.5 * highFull->y()));
  CHECK(highHalf->z() == Approx(0.5 * highFull->z()));
  CHECK(half.blob().build()->source_scale() == 0.5f);
  CHECK(half.triangles().size() == full.triangles().size());
}

// ==================================================================== metadata

TEST_CASE("build info records the source file name, options string and counts",
          "[compiler][compile]") {
  SECTION("default settings") {
    const ArenaBuild& build = arenaBuild();
    const bspc::Mesh imported = bspc::importMesh(arenaObj(), {});
    const bspf::schema::BuildInfo* info = build.world.blob().build();
    REQUIRE(info != nullptr);
    REQUIRE(info->source_file() != nullptr);
    CHECK(info->source_file()->str() == "arena.obj");
    REQUIRE(info->options() != nullptr);
    CHECK(info->options()->str() == bspc::describeOptions({}));
    REQUIRE(info->compiler_version() != nullptr);
    CHECK_THAT(info->compiler_version()->str(), Catch::StartsWith("bspc "));
    CHECK(info->input_triangles() == imported.triangles.size());
    CHECK(info->input_vertices() == imported.vertices.size());
    CHECK(info->welded_vertices() == build.report.clean.weldedVertices);
    CHECK(info->welded_vertices() > 0);  // the sample's solids share corners
    CHECK(info->dropped_degenerate() == build.report.clean.droppedDegenerate);
    CHECK(info->dropped_zero_area() == build.report.clean.droppedZeroArea);
    CHECK(info->dropped_duplicate() == build.report.clean.droppedDuplicate);
    CHECK(info->max_leaf_triangles() == 8);
    CHECK(info->max_depth() == 40);
    CHECK(info->source_up_axis() == bspf::schema::UpAxis::Y);
    CHECK(info->source_scale() == 1.0f);
    CHECK(build.world.blob().format_version() == bspf::kFormatVersion);
    CHECK(build.report.triangles == build.world.triangles().size());
    CHECK(build.report.outputBytes == fs::file_size(build.output));
    CHECK(build.report.clean.outputVertices == build.world.vertices().size());
  }
  SECTION("other settings and a mesh with dropped triangles") {
    const fs::path dir = bspf::test::freshTempDir("compile-metadata");
    // Vertex 5 repeats vertex 1; triangle 2 is degenerate, 3 collinear, 4 a
    // duplicate of 1 after the weld.
    writeText(dir / "odd.obj",
              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\nv 1 0 0\n"
              "f 1 2 3\nf 1 3 4\nf 1 1 2\nf 1 2 5\nf 6 3 1\n");
    bspc::CompileSettings settings;
    settings.import.up = bspc::UpAxis::Z;
    settings.import.scale = 2;
    settings.tree.maxDepth = 7;
    settings.tree.maxLeafTriangles = 3;
    const bspc::CompileReport report =
        bspc::compileFile(dir / "odd.obj", dir / "odd.bspf", settings);
    const bspf::World world = openFile(dir / "odd.bspf");
    const bspf::schema::BuildInfo* info = world.blob().build();
    REQUIRE(info != nullptr);
    CHECK(info->source_file()->str() == "odd.obj");
    CHECK(info->options()->str() == bspc::describeOptions(settings));
    CHECK_THAT(info->options()->str(), Catch::Contains("up=z") && Catch::Contains("scale=2") &&
                                           Catch::Contains("max-depth=7") &&
                                           Catch::Contains("max-leaf-triangles=3"));
    CHECK(info->input_triangles() == 5);
    CHECK(info->input_vertices() == report.clean.inputVertices);
    CHECK(info->welded_vertices() == report.clean.weldedVertices);
    CHECK(info->dropped_degenerate() == 1);
    CHECK(info->dropped_zero_area() == 1);
    CHECK(info->dropped_duplicate() == 1);
    CHECK(world.triangles().size() == 2);
    CHECK(info->max_depth() == 7);
    CHECK(info->max_leaf_triangles() == 3);
    CHECK(info->source_up_axis() == bspf::schema::UpAxis::Z);
    CHECK(info->source_scale() == 2.0f);
  }
}

TEST_CASE("bspc --stats-json writes a JSON report with the stage times", "[compiler][compile]") {
  const fs::path dir = bspf::test::freshTempDir("compile-stats");
  const fs::path input = bspf::test::samplesDir() / "box_room.obj";
  const bspf::test::CommandResult r =
      bspf::test::run(bspcCommand() + " " + quoted(input) + " -o " + quoted(dir / "room.bspf") +
                      " --stats-json " + quoted(dir / "stats.json"));
  INFO(r.err);
  REQUIRE(r.status == 0);
  const std::string text = readText(dir / "stats.json");
  INFO(text);
  const auto json = FlatJson::parse(text);
  REQUIRE(json.has_value());
  for (const char* stage : {"import", "clean", "build_tree", "planes", "write"}) {
    const std::string key = std::string("seconds.") + stage;
    INFO(key);
    REQUIRE(json->count(key) == 1);
    CHECK(std::stod(json->at(key)) >= 0);
  }
  const bspf::World world = openFile(dir / "room.bspf");
  CHECK(json->at("triangles") == std::to_string(world.triangles().size()));
  CHECK(json->at("output_bytes") == std::to_string(fs::file_size(dir / "room.bspf")));
  CHECK(json->at("clean.input_triangles") ==
        std::to_string(world.blob().build()->input_triangles()));
  CHECK(json->at("tree.leaves") == std::to_string(world.leaves().size()));
  CHECK(json->at("tree.nodes") == std::to_string(world.nodes().size()));
  CHECK(json->count("tree.depth_max") == 1);

  // toJson directly: valid JSON too, for a default report.
  CHECK(FlatJson::parse(bspc::toJson({})).has_value());
  // And no tmp file left beside the report.
  for (const auto& entry : fs::directory_iterator(dir))
    CHECK_THAT(entry.path().filename().string(), !Catch::Contains(".tmp-"));
}

TEST_CASE("bspc --info prints the tree figures of a compiled file", "[compiler][compile]") {
  const ArenaBuild& build = arenaBuild();
  const bspf::test::CommandResult r =
      bspf::test::run(bspcCommand() + " --info " + quoted(build.output));
  INFO(r.out << r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.empty());
  std::map<std::string, std::string> lines = infoLines(r.out);
  const bspf::TreeStats stats = bspf::computeTreeStats(build.world);
  for (const char* name : {"nodes", "leaves", "depth", "triangles per leaf", "references per tri",
                           "size", "triangles", "source", "options"}) {
    INFO(name);
    CHECK(lines.count(name) == 1);
  }
  CHECK(lines["nodes"] == std::to_string(stats.nodes));
  CHECK(lines["nodes"] == std::to_string(build.world.nodes().size()));
  CHECK_THAT(lines["leaves"], Catch::StartsWith(std::to_string(stats.leaves)));
  CHECK_THAT(lines["depth"],
             Catch::StartsWith("max " + std::to_string(stats.depthMax) + ", mean "));
  const std::string mean = lines["depth"].substr(lines["depth"].find("mean ") + 5);
  CHECK(std::stod(mean) == Approx(stats.depthMean).margin(0.006));
  CHECK_THAT(lines["triangles per leaf"],
             Catch::StartsWith("max " + std::to_string(stats.trianglesPerLeafMax) + ", mean "));
  CHECK(std::stod(lines["references per tri"]) ==
        Approx(stats.referencesPerTriangle).margin(0.006));
  CHECK_THAT(lines["size"],
             Catch::StartsWith(std::to_string(fs::file_size(build.output)) + " bytes, ") &&
                 Catch::EndsWith(" per triangle"));
  const std::string perTriangle = lines["size"].substr(lines["size"].find(", ") + 2);
  CHECK(std::stod(perTriangle) == Approx(stats.bytesPerTriangle).margin(0.006));
  CHECK(lines["triangles"] == std::to_string(build.world.triangles().size()));
  CHECK(lines["source"] == "arena.obj");
}

TEST_CASE("bspc --version prints the compiler and format version", "[compiler][compile]") {
  const bspf::test::CommandResult r = bspf::test::run(bspcCommand() + " --version");
  INFO(r.out << r.err);
  REQUIRE(r.status == 0);
  // The same compiler version the blobs record, then the format version.
  const std::string recorded = arenaBuild().world.blob().build()->compiler_version()->str();
  CHECK_THAT(r.out, Catch::StartsWith(recorded + " ") &&
                        Catch::Contains("format version " + std::to_string(bspf::kFormatVersion)));
  CHECK_THAT(recorded, Catch::Matches(R"(bspc \d+\.\d+\.\d+.*)"));
  CHECK(std::count(r.out.begin(), r.out.end(), '\n') == 1);
}
