// SPDX-License-Identifier: MIT
// cleanMesh: welding, dropping degenerate, zero-area, duplicate triangles and
// unused vertices, and refusing input it cannot make sense of.
#include <bspc/clean.h>
#include <bspc/mesh.h>
#include <bspc/settings.h>
#include <bspf/world.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <utility>
#include <vector>

namespace {

using Eigen::Vector3d;
using Triangles = std::vector<std::array<std::uint32_t, 3>>;

bspc::Mesh meshOf(std::vector<Vector3d> vertices, Triangles triangles) {
  bspc::Mesh mesh;
  mesh.vertices = std::move(vertices);
  mesh.triangles = std::move(triangles);
  return mesh;
}

bspc::CleanSettings weldingWithin(double tolerance) {
  bspc::CleanSettings settings;
  settings.weldTolerance = tolerance;
  return settings;
}

// The position of corner k of output triangle t.
Vector3d corner(const bspc::Mesh& mesh, std::size_t t, int k) {
  return mesh.vertices.at(mesh.triangles.at(t)[k]);
}

// A triangle far from everything else, with `first` as its first corner, so
// only `first` can weld with anything.
void addFan(bspc::Mesh& mesh, const Vector3d& first, double offset) {
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.push_back(first);
  mesh.vertices.push_back({offset, 10, 0});
  mesh.vertices.push_back({offset, 10, 1});
  mesh.triangles.push_back({base, base + 1, base + 2});
}

}  // namespace

// ==================================================================== weld

TEST_CASE("weld merges vertices within the tolerance and not beyond", "[compiler][clean]") {
  const double tolerance = 0.01;
  const Vector3d origin(0, 0, 0);
  // Each triangle has one corner near the origin and two far corners of its own.
  bspc::Mesh mesh;
  addFan(mesh, origin, 1);
  addFan(mesh, origin + Vector3d(0.006, 0, 0), 2);        // within: welded
  addFan(mesh, origin + Vector3d(0, -0.004, 0.005), 3);   // within (0.0064): welded
  addFan(mesh, origin + Vector3d(-0.003, 0, 0), 4);       // across a cell border: welded
  addFan(mesh, origin + Vector3d(0.014, 0, 0), 5);        // beyond: kept
  addFan(mesh, origin + Vector3d(0.007, 0.009, 0.0), 6);  // 0.0114 beyond: kept
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(tolerance), report);

  REQUIRE(clean.triangles.size() == 6);
  CHECK(report.weldedVertices == 3);
  CHECK(report.inputVertices == 18);
  CHECK(report.outputVertices == 18 - 3);
  CHECK(clean.vertices.size() == 15);
  // The welded corners share the first vertex and its position.
  for (int t : {1, 2, 3}) {
    INFO("triangle " << t);
    CHECK(clean.triangles[t][0] == clean.triangles[0][0]);
    CHECK(corner(clean, t, 0) == origin);
  }
  for (int t : {4, 5}) {
    INFO("triangle " << t);
    CHECK(clean.triangles[t][0] != clean.triangles[0][0]);
    CHECK(corner(clean, t, 0) == mesh.vertices[3 * t].cast<float>().cast<double>());
  }
}

TEST_CASE("weld with the default tolerance merges only within 0.1 mm", "[compiler][clean]") {
  bspc::Mesh mesh;
  addFan(mesh, {5, 5, 5}, 1);
  addFan(mesh, {5.00005, 5, 5}, 2);  // 0.05 mm: welded
  addFan(mesh, {5, 5, 5.0002}, 3);   // 0.2 mm: kept
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(report.weldedVertices == 1);
  CHECK(clean.triangles[1][0] == clean.triangles[0][0]);
  CHECK(clean.triangles[2][0] != clean.triangles[0][0]);
}

TEST_CASE("weld tolerance 0 merges only identical positions", "[compiler][clean]") {
  bspc::Mesh mesh;
  addFan(mesh, {1, 2, 3}, 1);
  addFan(mesh, {1, 2, 3}, 2);
  addFan(mesh, {1, 2, 3.000001}, 3);
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(0), report);
  CHECK(report.weldedVertices == 1);
  CHECK(clean.triangles[1][0] == clean.triangles[0][0]);
  CHECK(clean.triangles[2][0] != clean.triangles[0][0]);
}

TEST_CASE("weld is order-based: each vertex joins the first earlier vertex in reach",
          "[compiler][clean]") {
  const double tolerance = 0.01;
  const Vector3d a(0, 0, 0), b(0.006, 0, 0), c(0.012, 0, 0);
  bspc::CleanReport report;

  SECTION("no chaining: c is within reach of b only, and b has joined a") {
    bspc::Mesh mesh;
    addFan(mesh, a, 1);
    addFan(mesh, b, 2);
    addFan(mesh, c, 3);
    const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(tolerance), report);
    CHECK(report.weldedVertices == 1);
    CHECK(corner(clean, 1, 0) == a);
    CHECK(corner(clean, 2, 0) == c.cast<float>().cast<double>());
  }
  SECTION("the reverse order: b joins c, a stays") {
    bspc::Mesh mesh;
    addFan(mesh, c, 1);
    addFan(mesh, b, 2);
    addFan(mesh, a, 3);
    const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(tolerance), report);
    CHECK(report.weldedVertices == 1);
    CHECK(corner(clean, 1, 0) == c.cast<float>().cast<double>());
    CHECK(corner(clean, 2, 0) == a);
  }
  SECTION("in reach of two earlier vertices: the first one wins") {
    for (const bool cFirst : {false, true}) {
      bspc::Mesh mesh;
      addFan(mesh, cFirst ? c : a, 1);
      addFan(mesh, cFirst ? a : c, 2);
      addFan(mesh, b, 3);
      const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(tolerance), report);
      INFO("c first: " << cFirst);
      CHECK(report.weldedVertices == 1);
      CHECK(clean.triangles[2][0] == clean.triangles[0][0]);
      CHECK(corner(clean, 2, 0) == corner(clean, 0, 0));
    }
  }
  SECTION("deterministic: the same input gives the same output") {
    bspc::Mesh mesh;
    for (int i = 0; i < 200; ++i)
      addFan(mesh, Vector3d(0.003 * (i % 17), 0.004 * (i % 5), 0.002 * (i % 3)), i);
    bspc::CleanReport again;
    const bspc::Mesh first = bspc::cleanMesh(mesh, weldingWithin(tolerance), report);
    const bspc::Mesh second = bspc::cleanMesh(mesh, weldingWithin(tolerance), again);
    CHECK(first.vertices == second.vertices);
    CHECK(first.triangles == second.triangles);
    CHECK(report.weldedVertices == again.weldedVertices);
    CHECK(report.weldedVertices > 0);
  }
}

namespace {

// Where each vertex welds to by the definition (the first earlier kept
// vertex within the tolerance, itself if none), by comparing every pair, on
// positions rounded to float as clean rounds them; and how many welded.
std::pair<std::vector<Vector3d>, std::uint32_t> weldedByDefinition(
    const std::vector<Vector3d>& points, double tolerance) {
  std::vector<Vector3d> kept, out;
  std::uint32_t welded = 0;
  for (const Vector3d& point : points) {
    // Through a volatile float: GCC 12 at -O2 folds away a double -> float
    // -> double round trip of two coordinates at once here (vectorised).
    Vector3d p;
    for (int k = 0; k < 3; ++k) {
      volatile float rounded = static_cast<float>(point[k]);
      p[k] = rounded;
    }
    auto match = std::find_if(kept.begin(), kept.end(), [&](const Vector3d& k) {
      return (k - p).squaredNorm() <= tolerance * tolerance;
    });
    const bool found = match != kept.end();
    out.push_back(found ? *match : p);
    if (found)
      ++welded;
    else
      kept.push_back(p);
  }
  return {out, welded};
}

// Welds `points` (one fan each) and checks every one landed where the
// definition says.
void checkWeldMatchesDefinition(const std::vector<Vector3d>& points, double tolerance) {
  bspc::Mesh mesh;
  for (std::size_t i = 0; i < points.size(); ++i) addFan(mesh, points[i], 1.0 + double(i));
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(tolerance), report);
  const auto [expected, welded] = weldedByDefinition(points, tolerance);
  REQUIRE(clean.triangles.size() == points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    INFO("point " << i << " tolerance " << tolerance);
    CHECK(corner(clean, i, 0) == expected[i]);
  }
  CHECK(report.weldedVertices == welded);
  CHECK(welded > 0);
}

}  // namespace

TEST_CASE("weld joins each vertex to the first earlier one in reach, for every tolerance",
          "[compiler][clean]") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> step(-6, 6);
  SECTION("a lattice with jitter at the default and a large tolerance") {
    for (const double tolerance : {1e-4, 0.01, 0.5}) {
      std::vector<Vector3d> points;
      for (int i = 0; i < 600; ++i)
        points.emplace_back(Vector3d(step(rng), step(rng), step(rng)) * tolerance * 0.7);
      checkWeldMatchesDefinition(points, tolerance);
    }
  }
  SECTION("tolerance 0: exactly equal positions only, -0 equal to +0") {
    std::vector<Vector3d> points;
    for (int i = 0; i < 600; ++i)
      points.emplace_back(Vector3d(step(rng), step(rng), step(rng)) * 1e-3);
    points.emplace_back(-0.0, 0.0, -0.0);
    points.emplace_back(0.0, -0.0, 0.0);
    points.emplace_back(std::nextafter(0.0f, 1.0f), 0.0, 0.0);  // the nearest float: kept
    checkWeldMatchesDefinition(points, 0);
  }
  SECTION("tiny tolerances far from the origin: coordinates keyed by value") {
    // Near 5e4 m floats are 4 mm apart, so there only equal coordinates can
    // weld; near 0 a 1e-12 m tolerance still reaches neighbours.
    for (const double tolerance : {1e-12, 1e-30, 1e-300}) {
      std::vector<Vector3d> points;
      for (int i = 0; i < 600; ++i)
        points.emplace_back(5e4 + step(rng) * 0.002, step(rng) * 0.7e-12, -3e4 + step(rng) * 0.003);
      checkWeldMatchesDefinition(points, tolerance);
    }
  }
}

TEST_CASE("weld tolerance 0 merges the shared corners of a dense grid", "[compiler][clean]") {
  // 150 x 150 quads in one square metre, each with its own four corners (as
  // an importer that does not share vertices gives them): every corner
  // inside the grid is four equal positions, which become one.
  const int n = 150;
  bspc::Mesh mesh;
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
      for (const auto& [dx, dz] : {std::pair{0, 0}, {1, 0}, {0, 1}, {1, 1}})
        mesh.vertices.emplace_back(double(x + dx) / n, 0.001 * ((x + dx + z + dz) % 3),
                                   double(z + dz) / n);
      mesh.triangles.push_back({base, base + 2, base + 1});
      mesh.triangles.push_back({base + 1, base + 2, base + 3});
    }
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, weldingWithin(0), report);
  CHECK(clean.vertices.size() == std::size_t(n + 1) * (n + 1));
  CHECK(report.weldedVertices == 4 * n * n - (n + 1) * (n + 1));
  CHECK(clean.triangles.size() == mesh.triangles.size());
}

TEST_CASE("clean rounds positions to float as the blob stores them", "[compiler][clean]") {
  const bspc::Mesh mesh = meshOf({{0.1, 0.2, 0.3}, {1.1, 0.2, 0.3}, {0.1, 1.2, 0.3}}, {{0, 1, 2}});
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  for (int k = 0; k < 3; ++k)
    CHECK(clean.vertices[k] == mesh.vertices[k].cast<float>().cast<double>());
}

// ==================================================================== drops

TEST_CASE("degenerate triangles (a repeated index, also after the weld) are dropped and counted",
          "[compiler][clean]") {
  const bspc::Mesh mesh = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0.00001, 0, 0}},
                                 {{0, 1, 2}, {0, 0, 1}, {1, 2, 2}, {0, 1, 3}, {3, 2, 1}});
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(report.droppedDegenerate == 3);
  CHECK(report.droppedZeroArea == 0);
  CHECK(report.droppedDuplicate == 0);
  CHECK(report.weldedVertices == 1);
  REQUIRE(clean.triangles.size() == 2);
  CHECK(report.outputTriangles == 2);
  CHECK(report.inputTriangles == 5);
  // The last triangle survives with its corner 3 welded onto vertex 0.
  CHECK(clean.triangles[1][0] == clean.triangles[0][0]);
}

TEST_CASE("zero-area (collinear) and too-small triangles are dropped and counted; slivers kept",
          "[compiler][clean]") {
  const bspc::Mesh mesh =
      meshOf({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0.5, 2e-12, 0}, {0.3, 2e-5, 0}, {0, 1, 0}},
             {{0, 1, 2},    // collinear
              {0, 1, 3},    // area 1e-12, below the 1e-10 default
              {0, 1, 4},    // area 1e-5, a sliver 20 um high (the runtime needs 1 um): kept
              {0, 1, 5}});  // ordinary
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(report.droppedZeroArea == 2);
  CHECK(report.droppedDegenerate == 0);
  REQUIRE(clean.triangles.size() == 2);
  CHECK(corner(clean, 0, 2) == mesh.vertices[4].cast<float>().cast<double>());
  CHECK(corner(clean, 1, 2) == mesh.vertices[5]);

  SECTION("the minimum area is a setting") {
    bspc::CleanSettings settings;
    settings.minTriangleArea = 1e-4;
    const bspc::Mesh stricter = bspc::cleanMesh(mesh, settings, report);
    CHECK(report.droppedZeroArea == 3);
    CHECK(stricter.triangles.size() == 1);
  }
  SECTION("minimum area 0 still drops exactly collinear corners") {
    bspc::CleanSettings settings;
    settings.minTriangleArea = 0;
    const bspc::Mesh lenient = bspc::cleanMesh(mesh, settings, report);
    CHECK(report.droppedZeroArea == 1);
    // The 2e-12 m high one still goes, as too thin for the runtime (it
    // needs 8 float steps of height: isUsableTriangle).
    CHECK(report.droppedDegenerate == 1);
    CHECK(lenient.triangles.size() == 2);
  }
}

TEST_CASE("duplicate triangles with the same winding (any rotation) are dropped",
          "[compiler][clean]") {
  const bspc::Mesh mesh =
      meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}},
             {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 1, 2}, {4, 5, 3}});  // last: copies, welded
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(report.droppedDuplicate == 4);
  REQUIRE(clean.triangles.size() == 1);
  CHECK(clean.vertices.size() == 3);
  CHECK(report.weldedVertices == 3);
}

TEST_CASE("the same corners with opposite winding are kept (a two-sided surface)",
          "[compiler][clean]") {
  const bspc::Mesh mesh =
      meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}});
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  // (2, 1, 0) and (1, 0, 2) are rotations of the back face (0, 2, 1).
  CHECK(report.droppedDuplicate == 2);
  REQUIRE(clean.triangles.size() == 2);
  const Vector3d front =
      (corner(clean, 0, 1) - corner(clean, 0, 0)).cross(corner(clean, 0, 2) - corner(clean, 0, 0));
  const Vector3d back =
      (corner(clean, 1, 1) - corner(clean, 1, 0)).cross(corner(clean, 1, 2) - corner(clean, 1, 0));
  CHECK(front.dot(back) < 0);
  CHECK(front.z() > 0);
}

TEST_CASE("unused vertices are dropped; the order of what remains is kept", "[compiler][clean]") {
  // Vertex 0 is unused, vertex 4 only used by a degenerate triangle.
  const bspc::Mesh mesh = meshOf({{9, 9, 9}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {5, 5, 5}, {0, 0, 1}},
                                 {{1, 2, 3}, {4, 4, 1}, {5, 3, 2}});
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(report.inputVertices == 6);
  CHECK(report.outputVertices == 4);
  REQUIRE(clean.vertices.size() == 4);
  for (const Vector3d& v : clean.vertices) {
    CHECK(v != Vector3d(9, 9, 9));
    CHECK(v != Vector3d(5, 5, 5));
  }
  REQUIRE(clean.triangles.size() == 2);
  CHECK(corner(clean, 0, 0) == mesh.vertices[1]);
  CHECK(corner(clean, 0, 1) == mesh.vertices[2]);
  CHECK(corner(clean, 0, 2) == mesh.vertices[3]);
  CHECK(corner(clean, 1, 0) == mesh.vertices[5]);
  CHECK(corner(clean, 1, 1) == mesh.vertices[3]);
  CHECK(corner(clean, 1, 2) == mesh.vertices[2]);
  for (const auto& t : clean.triangles)
    for (const std::uint32_t v : t) CHECK(v < clean.vertices.size());
}

// ==================================================================== errors

TEST_CASE("a non-finite coordinate is a CompileError", "[compiler][clean]") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const double bad : {nan, inf, -inf, 1e39, -1e39, 1e300}) {
    for (int axis = 0; axis < 3; ++axis) {
      bspc::Mesh mesh =
          meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}}, {{0, 1, 2}, {0, 2, 3}});
      mesh.vertices[2][axis] = bad;
      bspc::CleanReport report;
      INFO("coordinate " << bad << " on axis " << axis);
      CHECK_THROWS_AS(bspc::cleanMesh(mesh, {}, report), bspc::CompileError);
      CHECK_THROWS_WITH(bspc::cleanMesh(mesh, {}, report), Catch::Contains("vertex 2"));
    }
  }
}

TEST_CASE("coordinates up to the runtime's bound are accepted", "[compiler][clean]") {
  const double big = bspf::kMaxCoordinate;
  const bspc::Mesh mesh = meshOf({{0, 0, 0}, {big, 0, 0}, {0, -big, 0}}, {{0, 1, 2}});
  bspc::CleanReport report;
  bspc::Mesh clean;
  CHECK_NOTHROW(clean = bspc::cleanMesh(mesh, {}, report));
  CHECK(clean.triangles.size() == 1);
}

TEST_CASE("a finite coordinate beyond the runtime's bound is a CompileError naming the vertex",
          "[compiler][clean]") {
  // 1e19 m and 3e38 m are finite floats; the step's arithmetic on them is not.
  for (const double big : {1.000001e5, 1e19, 3.0e38}) {
    INFO(big);
    const bspc::Mesh mesh =
        meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {big, 0, 0}}, {{0, 1, 2}, {0, 3, 2}});
    bspc::CleanReport report;
    CHECK_THROWS_WITH(bspc::cleanMesh(mesh, {}, report),
                      Catch::Contains("vertex 3") && Catch::Contains("bound"));
  }
}

TEST_CASE("a triangle that is a line to float precision is dropped as degenerate",
          "[compiler][clean]") {
  // Area 0.05 m^2, far above the default minimum, but its 0.1 mm height is
  // under two float steps at 1000 m: no usable normal.
  const bspc::Mesh mesh = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1000, 0, 0}, {500, 1e-4, 0}},
                                 {{0, 1, 2}, {0, 3, 4}});
  bspc::CleanReport report;
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(clean.triangles.size() == 1);
  CHECK(report.droppedDegenerate == 1);
  CHECK(report.droppedZeroArea == 0);
}

TEST_CASE("a vertex index out of range is a CompileError", "[compiler][clean]") {
  for (const std::uint32_t bad : {3u, 4u, 0xFFFFFFFFu}) {
    const bspc::Mesh mesh = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, bad, 1}});
    bspc::CleanReport report;
    INFO("index " << bad);
    CHECK_THROWS_AS(bspc::cleanMesh(mesh, {}, report), bspc::CompileError);
    CHECK_THROWS_WITH(bspc::cleanMesh(mesh, {}, report),
                      Catch::Contains("triangle 1") && Catch::Contains("range"));
  }
}

TEST_CASE("a mesh with no triangle left after cleaning is a CompileError saying so",
          "[compiler][clean]") {
  bspc::CleanReport report;
  SECTION("all degenerate or zero-area") {
    const bspc::Mesh mesh = meshOf({{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {0.00001, 0, 0}},
                                   {{0, 1, 2}, {0, 0, 1}, {0, 3, 1}});
    CHECK_THROWS_AS(bspc::cleanMesh(mesh, {}, report), bspc::CompileError);
    CHECK_THROWS_WITH(bspc::cleanMesh(mesh, {}, report), Catch::Contains("no triangle"));
  }
  SECTION("no triangles at all") {
    const bspc::Mesh mesh = meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {});
    CHECK_THROWS_AS(bspc::cleanMesh(mesh, {}, report), bspc::CompileError);
    CHECK_THROWS_WITH(bspc::cleanMesh(mesh, {}, report), Catch::Contains("no triangle"));
  }
  SECTION("everything welds into one point") {
    const bspc::Mesh mesh =
        meshOf({{0, 0, 0}, {0.00002, 0, 0}, {0, 0.00002, 0}}, {{0, 1, 2}, {2, 1, 0}});
    CHECK_THROWS_WITH(bspc::cleanMesh(mesh, {}, report), Catch::Contains("no triangle"));
  }
}

TEST_CASE("the clean report counts what went in and what came out", "[compiler][clean]") {
  const bspc::Mesh mesh =
      meshOf({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {2, 0, 0}, {0, 0, 0}, {7, 7, 7}},
             {{0, 1, 2}, {0, 2, 3}, {0, 0, 1}, {0, 1, 4}, {5, 1, 2}, {2, 1, 0}});
  bspc::CleanReport report;
  report.droppedDuplicate = 99;  // stale values are reset
  const bspc::Mesh clean = bspc::cleanMesh(mesh, {}, report);
  CHECK(report.inputVertices == 7);
  CHECK(report.inputTriangles == 6);
  CHECK(report.weldedVertices == 1);
  CHECK(report.droppedDegenerate == 1);
  CHECK(report.droppedZeroArea == 1);
  CHECK(report.droppedDuplicate == 1);
  CHECK(report.outputTriangles == 3);
  CHECK(report.outputVertices == 4);
  CHECK(clean.triangles.size() == 3);
  CHECK(clean.vertices.size() == 4);
}
