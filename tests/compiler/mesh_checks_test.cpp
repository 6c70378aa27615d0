// SPDX-License-Identifier: MIT
#include <bspc/clean.h>
#include <bspc/compile.h>
#include <bspc/edges.h>
#include <bspc/mesh_checks.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <fstream>

#include "support/test_support.h"

namespace {

bspc::Mesh insideOut(bspc::Mesh mesh) {
  for (auto& t : mesh.triangles) std::swap(t[1], t[2]);
  return mesh;
}

bspc::Mesh box(double x, double size) {
  return bspf::test::boxMesh({x, 0, 0}, {x + size, size, size});
}

}  // namespace

TEST_CASE("closed pieces wound inward are counted, those facing out and open surfaces are not",
          "[compiler][mesh-checks]") {
  SECTION("a box facing out") {
    const bspc::PieceCounts counts = bspc::countClosedPieces(box(0, 2));
    CHECK(counts.closedPieces == 1);
    CHECK(counts.insideOutPieces == 0);
  }
  SECTION("a box wound inward") {
    const bspc::PieceCounts counts = bspc::countClosedPieces(insideOut(box(0, 2)));
    CHECK(counts.closedPieces == 1);
    CHECK(counts.insideOutPieces == 1);
    CHECK(counts.insideOutTriangles == 12);
  }
  SECTION("three boxes, the middle one wound inward, far from the origin") {
    bspc::Mesh mesh = box(5e4, 2);
    bspf::test::append(mesh, insideOut(box(5e4 + 3, 2)));
    bspf::test::append(mesh, box(5e4 + 6, 2));
    const bspc::PieceCounts counts = bspc::countClosedPieces(mesh);
    CHECK(counts.closedPieces == 3);
    CHECK(counts.insideOutPieces == 1);
    CHECK(counts.insideOutTriangles == 12);
  }
  SECTION("a box with a face missing is open, whichever way it is wound") {
    bspc::Mesh mesh = insideOut(box(0, 2));
    mesh.triangles.resize(10);
    CHECK(bspc::countClosedPieces(mesh).closedPieces == 0);
  }
  SECTION("two boxes sharing only an edge: that edge joins four faces, so neither is counted") {
    bspc::Mesh mesh = box(0, 2);
    bspf::test::append(mesh, bspf::test::boxMesh({2, 2, 0}, {4, 4, 2}));
    bspc::CleanReport cleaned;
    mesh = bspc::cleanMesh(mesh, {}, cleaned);
    CHECK(bspc::countClosedPieces(mesh).closedPieces == 0);
  }
  SECTION("a box with one face flipped is not consistently wound: not counted") {
    bspc::Mesh mesh = box(0, 2);
    std::swap(mesh.triangles[0][1], mesh.triangles[0][2]);
    std::swap(mesh.triangles[1][1], mesh.triangles[1][2]);
    CHECK(bspc::countClosedPieces(mesh).closedPieces == 0);
  }
}

TEST_CASE("the closed pieces from the face rules' edges are those paired by vertex index",
          "[compiler][mesh-checks]") {
  bspc::Mesh shared = box(0, 2);
  bspf::test::append(shared, bspf::test::boxMesh({2, 2, 0}, {4, 4, 2}));
  bspc::CleanReport cleaned;
  shared = bspc::cleanMesh(shared, {}, cleaned);
  bspc::Mesh open = insideOut(box(0, 2));
  open.triangles.resize(10);
  bspc::Mesh flipped = box(0, 2);
  std::swap(flipped.triangles[0][1], flipped.triangles[0][2]);
  bspc::Mesh three = box(5e4, 2);
  bspf::test::append(three, insideOut(box(5e4 + 3, 2)));
  bspf::test::append(three, box(5e4 + 6, 2));
  for (const bspc::Mesh* mesh : {&shared, &open, &flipped, &three}) {
    const bspc::SolidEdges edges(*mesh);
    const bspc::ClosedPieces byIndex = bspc::findClosedPieces(*mesh);
    const bspc::ClosedPieces byEdges = bspc::findClosedPieces(*mesh, bspc::pairedNeighbours(edges));
    CHECK(byEdges.pieceOf == byIndex.pieceOf);
    CHECK(byEdges.volume6 == byIndex.volume6);
    CHECK(byEdges.across == byIndex.across);
    CHECK(bspc::meshWarnings(edges) == bspc::meshWarnings(*mesh));
  }
}

TEST_CASE("bspc warns about inside-out pieces and about a size in the wrong unit, and compiles",
          "[compiler][mesh-checks]") {
  bspc::CompileReport report;
  SECTION("a level of metres facing out: no warning") {
    bspc::Mesh mesh = box(0, 4);
    bspf::test::append(mesh, box(10, 4));
    REQUIRE_FALSE(bspf::test::compile(mesh, {}).empty());
    bspc::compileMesh(mesh, {}, "level", report);
    CHECK(report.warnings.empty());
  }
  SECTION("one of two pieces inside out: counted in one line") {
    bspc::Mesh mesh = box(0, 4);
    bspf::test::append(mesh, insideOut(box(10, 4)));
    CHECK_FALSE(bspc::compileMesh(mesh, {}, "level", report).empty());
    REQUIRE(report.warnings.size() == 1);
    CHECK_THAT(report.warnings[0], Catch::Contains("1 of 2 closed pieces (12 triangles)") &&
                                       Catch::Contains("inside out"));
  }
  SECTION("20 km across: the unit is doubted") {
    bspc::Mesh mesh = bspf::test::boxMesh({0, 0, 0}, {20000, 1, 10});
    CHECK_FALSE(bspc::compileMesh(mesh, {}, "level", report).empty());
    REQUIRE(report.warnings.size() == 1);
    CHECK_THAT(report.warnings[0], Catch::Contains("20000 m across") &&
                                       Catch::Contains("over 10 km") && Catch::Contains("--scale"));
  }
  SECTION("half a metre across: the unit is doubted") {
    CHECK_FALSE(bspc::compileMesh(box(0, 0.5), {}, "level", report).empty());
    REQUIRE(report.warnings.size() == 1);
    CHECK_THAT(report.warnings[0], Catch::Contains("0.5 m across") && Catch::Contains("under 1 m"));
  }
}

TEST_CASE("bspc prints a mesh warning as one line naming the file, and exits 0",
          "[compiler][mesh-checks]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("mesh-checks");
  const std::filesystem::path obj = dir / "tiny.obj";
  std::ofstream(obj) << "v 0 0 0\nv 0.2 0 0\nv 0 0 0.2\nf 1 3 2\n";
  const auto r = bspf::test::run(std::string("'") + bspf::test::bspcExecutable().string() + "' '" +
                                 obj.string() + "' -o '" + (dir / "tiny.bspf").string() + "' -q");
  INFO("stderr: [" << r.err << "]");
  CHECK(r.status == 0);
  CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  CHECK_THAT(r.err, Catch::StartsWith("bspc: warning: ") && Catch::Contains("tiny.obj") &&
                        Catch::Contains("under 1 m"));
  CHECK(std::filesystem::exists(dir / "tiny.bspf"));
}
