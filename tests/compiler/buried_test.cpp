// SPDX-License-Identifier: MIT
// findBuriedFaces and the compile's buried-face rule: a face is dropped only
// when it lies, by a margin, inside another closed, convex, outward-wound
// solid; whatever cannot be decided keeps its faces.
#include <bspc/buried.h>
#include <bspc/clean.h>
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspf/movement.h>
#include <bspf/world.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>

#include "support/test_support.h"

namespace {

using bspf::test::append;
using bspf::test::boxMesh;
using bspf::test::cleaned;
using Eigen::Vector3d;

// The buried triangles of `mesh` (cleaned first), by index into the cleaned
// mesh, whose triangles keep the input's order here (nothing is dropped).
std::vector<std::uint32_t> buriedOf(const bspc::Mesh& mesh, bspc::BuriedReport& report) {
  const bspc::Mesh clean = cleaned(mesh);
  REQUIRE(clean.triangles.size() == mesh.triangles.size());
  const std::vector<bool> buried = bspc::findBuriedFaces(clean, report);
  std::vector<std::uint32_t> indices;
  for (std::uint32_t t = 0; t < buried.size(); ++t)
    if (buried[t]) indices.push_back(t);
  CHECK(report.buried == indices.size());
  return indices;
}

std::vector<std::uint32_t> range(std::uint32_t first, std::uint32_t last) {
  std::vector<std::uint32_t> out;
  for (std::uint32_t i = first; i < last; ++i) out.push_back(i);
  return out;
}

bspc::Mesh insideOut(bspc::Mesh mesh) {
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

// The 4 m box every test puts things in, as triangles 0 to 11.
bspc::Mesh bigBox() { return boxMesh({0, 0, 0}, {4, 4, 4}); }

}  // namespace

TEST_CASE("a box fully inside a bigger box has every face buried; the bigger box keeps its own",
          "[compiler][buried]") {
  bspc::Mesh mesh = bigBox();
  append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));
  bspc::BuriedReport report;
  CHECK(buriedOf(mesh, report) == range(12, 24));
  CHECK(report.closedPieces == 2);
  CHECK(report.containers == 2);
}

TEST_CASE("a box poking out of another keeps every face that reaches outside it",
          "[compiler][buried]") {
  SECTION("one end inside: only that end's two triangles are buried") {
    bspc::Mesh mesh = bigBox();
    append(mesh, boxMesh({1, 1, 3}, {2, 2, 5}));
    bspc::BuriedReport report;
    const std::vector<std::uint32_t> buried = buriedOf(mesh, report);
    REQUIRE(buried.size() == 2);
    for (const std::uint32_t t : buried) {
      const auto& tri = mesh.triangles[t];
      for (const std::uint32_t corner : tri) CHECK(mesh.vertices[corner].z() == 3);
    }
  }
  SECTION("through both sides: nothing is buried") {
    bspc::Mesh mesh = bigBox();
    append(mesh, boxMesh({1, 1, -1}, {2, 2, 5}));
    bspc::BuriedReport report;
    CHECK(buriedOf(mesh, report).empty());
  }
}

TEST_CASE("boxes touching each other or a solid's surface keep their faces", "[compiler][buried]") {
  bspc::BuriedReport report;
  SECTION("side by side") {
    bspc::Mesh mesh = bigBox();
    append(mesh, boxMesh({4, 0, 0}, {5, 1, 1}));
    CHECK(buriedOf(mesh, report).empty());
  }
  SECTION("inside, half a millimetre from the surface: only the far face is buried") {
    bspc::Mesh mesh = bigBox();
    append(mesh, boxMesh({0.0005, 1, 1}, {1, 2, 2}));
    // boxMesh's triangles 2 and 3 make its face x = high; every other
    // triangle has a corner at x = 0.0005, within the margin.
    CHECK(buriedOf(mesh, report) == std::vector<std::uint32_t>{14, 15});
  }
  SECTION("the same turned 30 degrees, where the boxes' bounds do not decide") {
    bspc::Mesh mesh = bigBox();
    append(mesh, boxMesh({0.0005, 1, 1}, {1, 2, 2}));
    const Eigen::Matrix3d turn = Eigen::AngleAxisd(0.5236, Vector3d::UnitY()).toRotationMatrix();
    for (Vector3d& v : mesh.vertices) v = turn * v;
    CHECK(buriedOf(mesh, report) == std::vector<std::uint32_t>{14, 15});
  }
  SECTION("inside, two millimetres from the surface: beyond the margin") {
    bspc::Mesh mesh = bigBox();
    append(mesh, boxMesh({0.002, 1, 1}, {1, 2, 2}));
    CHECK(buriedOf(mesh, report) == range(12, 24));
  }
}

TEST_CASE("an open piece is never buried and buries nothing", "[compiler][buried]") {
  bspc::BuriedReport report;
  SECTION("an open container") {
    bspc::Mesh mesh = bigBox();
    mesh.triangles.pop_back();  // a hole in its top
    append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));
    CHECK(buriedOf(mesh, report).empty());
    CHECK(report.closedPieces == 1);
  }
  SECTION("an open piece inside a closed box") {
    bspc::Mesh inner = boxMesh({1, 1, 1}, {2, 2, 2});
    inner.triangles.pop_back();
    bspc::Mesh mesh = bigBox();
    append(mesh, inner);
    CHECK(buriedOf(mesh, report).empty());
    CHECK(report.containers == 1);
  }
}

TEST_CASE("an inside-out box buries nothing", "[compiler][buried]") {
  bspc::Mesh mesh = insideOut(bigBox());
  append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));
  bspc::BuriedReport report;
  CHECK(buriedOf(mesh, report).empty());
  CHECK(report.closedPieces == 2);
  CHECK(report.containers == 1);  // the inner box, which holds nothing
}

TEST_CASE("a closed piece that is not convex buries nothing", "[compiler][buried]") {
  // The big box with its top (y = 4) pushed in to a point at y = 3: closed,
  // wound outward, and dented.
  bspc::Mesh mesh = bigBox();
  // boxMesh's top (triangles 6 and 7, corners 2, 6, 7, 3) as four
  // triangles to the dent.
  mesh.triangles.erase(mesh.triangles.begin() + 6, mesh.triangles.begin() + 8);
  mesh.vertices.emplace_back(2, 3, 2);
  const std::uint32_t dent = 8;
  mesh.triangles.push_back({2, 6, dent});
  mesh.triangles.push_back({6, 7, dent});
  mesh.triangles.push_back({7, 3, dent});
  mesh.triangles.push_back({3, 2, dent});
  append(mesh, boxMesh({1, 0.5, 1}, {2, 1.5, 2}));
  bspc::BuriedReport report;
  CHECK(buriedOf(mesh, report).empty());
  CHECK(report.closedPieces == 2);
  CHECK(report.containers == 1);
}

TEST_CASE(
    "the compile drops buried faces by default, counts them apart from covered ones, and "
    "keeps them when asked",
    "[compiler][buried]") {
  // Two boxes touching each other inside a big one: their shared face is
  // covered (both sides), the rest of them buried.
  bspc::Mesh mesh = bigBox();
  append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));
  append(mesh, boxMesh({2, 1, 1}, {3, 2, 2}));
  bspc::CompileReport report;
  bspc::compileMesh(mesh, {}, "nested", report);
  CHECK(report.edges.droppedCovered == 4);
  CHECK(report.buried.buried == 24);
  CHECK(report.buried.dropped == 20);
  CHECK(report.triangles == 12);
  CHECK_THAT(bspc::toJson(report), Catch::Contains("\"buried\":{\"dropped\":20,\"buried\":24"));

  bspc::CompileSettings keep;
  keep.dropBuriedFaces = false;
  bspc::compileMesh(mesh, keep, "nested", report);
  CHECK(report.buried.dropped == 0);
  CHECK(report.triangles == 32);
  CHECK_THAT(bspc::describeOptions(keep), Catch::Contains("drop-buried-faces=0"));
  CHECK_THAT(bspc::describeOptions({}), !Catch::Contains("drop-buried-faces"));
}

TEST_CASE("buried faces are found the same on 1 and 2 threads: the same blob, byte for byte",
          "[compiler][buried][threads]") {
  // Enough triangles for the pool to share them out: boxes inside, poking
  // out of and outside a slab.
  bspc::Mesh mesh = boxMesh({-40, -2, -40}, {40, 0, 40});
  for (int i = 0; i < 60; ++i) {
    const double x = -39 + 1.3 * i, z = 0.7 * (i % 11) - 3;
    const double bottom = i % 3 == 0 ? -1.5 : i % 3 == 1 ? -0.5 : 0.5;
    append(mesh, boxMesh({x, bottom, z}, {x + 1, bottom + 1, z + 1}));
  }
  bspc::CompileSettings one, two;
  one.threads = 1;
  two.threads = 2;
  bspc::CompileReport oneReport, twoReport;
  const std::vector<std::uint8_t> a = bspc::compileMesh(mesh, one, "slab", oneReport);
  const std::vector<std::uint8_t> b = bspc::compileMesh(mesh, two, "slab", twoReport);
  CHECK(oneReport.buried.dropped == 20 * 12 + 20 * 2);
  CHECK(a == b);
}

TEST_CASE("boxes touching along a face are closed pieces of their own, and buried as such",
          "[compiler][buried]") {
  // After welding the two small boxes share a face's corners and edges,
  // each edge used by four triangles.
  bspc::Mesh mesh = bigBox();
  append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));
  append(mesh, boxMesh({2, 1, 1}, {3, 2, 2}));
  bspc::BuriedReport report;
  CHECK(buriedOf(mesh, report) == range(12, 36));
  CHECK(report.closedPieces == 3);
}

// The guarantee that matters: no body outside the solids touches a buried
// face, so both narrow phases move every body exactly as they do when the
// buried faces are kept.
TEST_CASE("bodies on the arena move bit for bit the same with and without buried faces",
          "[compiler][buried]") {
  bspc::Mesh arena =
      bspc::importMesh(bspf::test::samplesDir() / "arena.obj", bspc::ImportSettings{});
  // Boxes sunk in the floor slab (y from -1 to 0) and in the north wall
  // (z from 19 to 20, up to y = 4) where the bodies walk over and into them.
  for (int i = 0; i < 8; ++i) {
    const double x = -16 + 4.0 * i;
    append(arena, boxMesh({x, -0.8, -2}, {x + 1.5, -0.1, 2}));
    append(arena, boxMesh({x, 0.5, 19.2}, {x + 1, 2, 19.8}));
  }
  if (!arena.triangleSurfaces.empty()) arena.triangleSurfaces.resize(arena.triangles.size(), 0);
  bspc::CompileSettings keep;
  keep.dropBuriedFaces = false;
  bspc::CompileReport dropReport, keepReport;
  const std::vector<std::uint8_t> dropBlob = bspc::compileMesh(arena, {}, "arena", dropReport);
  const std::vector<std::uint8_t> keepBlob = bspc::compileMesh(arena, keep, "arena", keepReport);
  REQUIRE(dropReport.buried.dropped >= 16 * 12);
  CHECK(dropReport.triangles + dropReport.buried.dropped == keepReport.triangles);
  const bspf::test::AlignedBytes dropBytes(dropBlob), keepBytes(keepBlob);
  const bspf::OpenResult a = bspf::viewWorld(keepBytes.span());
  const bspf::OpenResult b = bspf::viewWorld(dropBytes.span());
  REQUIRE(a);
  REQUIRE(b);
  std::vector<Eigen::Vector3f> spawns;
  {
    std::ifstream in(bspf::test::samplesDir() / "arena.spawns.txt");
    float x, y, z;
    while (in >> x >> y >> z) spawns.emplace_back(x, y, z);
  }
  REQUIRE(!spawns.empty());
  for (const bspf::CollisionMethod method :
       {bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep}) {
    std::vector<bspf::Body> bodies;
    for (const Eigen::Vector3f& spawn : spawns) {
      bspf::Body body;
      body.position = spawn + bspf::Vec3(0, 0.3f, 0);
      body.radii = {0.45f, 0.85f};
      body.settings.method = method;
      bodies.push_back(body);
    }
    const int differing = bspf::test::differingWalkSteps(*a.world, *b.world, bodies, 400);
    CHECK(differing == 0);
  }
}

TEST_CASE("bspc --keep-buried-faces keeps the faces the default drops", "[compiler][buried][cli]") {
  const auto dir = bspf::test::freshTempDir("buried-cli");
  bspc::Mesh mesh = bigBox();
  append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));
  std::string obj;
  for (const Vector3d& v : mesh.vertices)
    obj += "v " + std::to_string(v.x()) + " " + std::to_string(v.y()) + " " +
           std::to_string(v.z()) + "\n";
  for (const auto& t : mesh.triangles)
    obj += "f " + std::to_string(t[0] + 1) + " " + std::to_string(t[1] + 1) + " " +
           std::to_string(t[2] + 1) + "\n";
  bspf::test::writeText(dir / "nested.obj", obj);
  const auto compile = [&](const std::string& name, const std::string& option) {
    return bspf::test::runBspc(bspf::test::quoted(dir / "nested.obj") + " -o " +
                               bspf::test::quoted(dir / (name + ".bspf")) + " " + option);
  };
  const auto dropped = compile("default", "");
  const auto kept = compile("kept", "--keep-buried-faces");
  REQUIRE(dropped.status == 0);
  REQUIRE(kept.status == 0);
  CHECK_THAT(dropped.out, Catch::Contains(": 12 triangles"));
  CHECK_THAT(kept.out, Catch::Contains(": 24 triangles"));
}
