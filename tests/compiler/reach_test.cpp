// SPDX-License-Identifier: MIT
#include <bspc/compile.h>
#include <bspc/reach.h>
#include <bspf/movement.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>

#include "support/test_support.h"

namespace {

using bspf::test::append;
using bspf::test::boxMesh;
using Eigen::Vector3d;

// A closed room of 0.3 m slabs around the inside [0, 6] x [0, 3] x [0, 6]:
// floor, ceiling and four walls, each a box of its own. `doorWidth` > 0 cuts
// a door, 2.2 m high, centred in the +x wall.
bspc::Mesh room(double doorWidth = 0) {
  bspc::Mesh m = boxMesh({-0.3, -0.3, -0.3}, {6.3, 0, 6.3});
  append(m, boxMesh({-0.3, 3, -0.3}, {6.3, 3.3, 6.3}));
  append(m, boxMesh({-0.3, 0, -0.3}, {0, 3, 6.3}));
  append(m, boxMesh({0, 0, -0.3}, {6, 3, 0}));
  append(m, boxMesh({0, 0, 6}, {6, 3, 6.3}));
  if (doorWidth == 0) {
    append(m, boxMesh({6, 0, -0.3}, {6.3, 3, 6.3}));
  } else {
    append(m, boxMesh({6, 0, -0.3}, {6.3, 3, 3 - doorWidth / 2}));
    append(m, boxMesh({6, 0, 3 + doorWidth / 2}, {6.3, 3, 6.3}));
    append(m, boxMesh({6, 2.2, 3 - doorWidth / 2}, {6.3, 3, 3 + doorWidth / 2}));
  }
  return m;
}

// A second room beyond the first one's +x wall: x from 6.3 to 12.
bspc::Mesh roomBeyond() {
  bspc::Mesh m = boxMesh({6.3, -0.3, -0.3}, {12.3, 0, 6.3});
  append(m, boxMesh({6.3, 3, -0.3}, {12.3, 3.3, 6.3}));
  append(m, boxMesh({12, 0, -0.3}, {12.3, 3, 6.3}));
  append(m, boxMesh({6.3, 0, -0.3}, {12, 3, 0}));
  append(m, boxMesh({6.3, 0, 6}, {12, 3, 6.3}));
  return m;
}

bspc::ReachSettings reachFrom(const Vector3d& point) {
  bspc::ReachSettings s;
  s.from = {point};
  return s;
}

Vector3d centroid(const bspc::Mesh& m, const std::array<std::uint32_t, 3>& t) {
  return (m.vertices[t[0]] + m.vertices[t[1]] + m.vertices[t[2]]) / 3;
}

Vector3d normal(const bspc::Mesh& m, const std::array<std::uint32_t, 3>& t) {
  return (m.vertices[t[1]] - m.vertices[t[0]])
      .cross(m.vertices[t[2]] - m.vertices[t[0]])
      .normalized();
}

}  // namespace

TEST_CASE("of a closed room, only the faces looking into it are kept; a box outside it is dropped",
          "[compiler][reach]") {
  bspc::Mesh mesh = room();
  append(mesh, boxMesh({10, 0, 0}, {11, 1, 1}));
  bspc::ReachReport report;
  std::vector<std::string> warnings;
  const bspc::Mesh kept =
      bspc::dropUnreachableFaces(mesh, reachFrom({3, 1.5, 3}), report, warnings);
  CHECK(report.applied);
  CHECK_FALSE(report.leaked);
  CHECK(warnings.empty());
  // The six inner faces, two triangles each: everything else is the slabs'
  // outsides, their ends buried in each other, and the lone box.
  REQUIRE(kept.triangles.size() == 12);
  CHECK(report.dropped == mesh.triangles.size() - 12);
  const Vector3d middle(3, 1.5, 3);
  for (const auto& t : kept.triangles) {
    const Vector3d c = centroid(kept, t);
    CHECK(normal(kept, t).dot(middle - c) > 0);  // faces the inside
    CHECK(c.x() >= -0.31);
    CHECK(c.x() <= 6.31);
  }
  // No vertex left over that no triangle uses.
  CHECK(kept.vertices.size() <= 3 * kept.triangles.size());
}

TEST_CASE(
    "a room behind a door narrower than the body is out of reach, behind a wide one it is not",
    "[compiler][reach]") {
  const auto keptBeyond = [](double doorWidth) {
    bspc::Mesh mesh = room(doorWidth);
    append(mesh, roomBeyond());
    bspc::ReachReport report;
    std::vector<std::string> warnings;
    const bspc::Mesh kept =
        bspc::dropUnreachableFaces(mesh, reachFrom({3, 1.5, 3}), report, warnings);
    int beyond = 0;
    for (const auto& t : kept.triangles) beyond += centroid(kept, t).x() > 6.5;
    return beyond;
  };
  // The default body is 0.9 m wide: a 0.6 m door stops it, a 1.2 m one not.
  CHECK(keptBeyond(0.6) == 0);
  CHECK(keptBeyond(1.2) >= 10);  // the far room's floor, ceiling and walls
}

TEST_CASE("a larger body keeps fewer faces: it cannot pass where a small one can",
          "[compiler][reach]") {
  bspc::Mesh mesh = room(1.2);
  append(mesh, roomBeyond());
  std::vector<std::string> warnings;
  bspc::ReachReport small, large;
  bspc::ReachSettings settings = reachFrom({3, 1.5, 3});
  const std::size_t smallKept =
      bspc::dropUnreachableFaces(mesh, settings, small, warnings).triangles.size();
  // 1.6 m wide: not through a 1.2 m door (the grid may count an opening up
  // to a fifth narrower than the body as passable, never a narrower one).
  settings.radiusXZ = 0.8;
  const std::size_t largeKept =
      bspc::dropUnreachableFaces(mesh, settings, large, warnings).triangles.size();
  CHECK(largeKept < smallKept);
}

TEST_CASE("points a body cannot be at are refused with the point named", "[compiler][reach]") {
  const bspc::Mesh mesh = room();
  bspc::ReachReport report;
  std::vector<std::string> warnings;
  SECTION("outside the level's bounds") {
    CHECK_THROWS_WITH(bspc::dropUnreachableFaces(mesh, reachFrom({30, 1, 3}), report, warnings),
                      Catch::Contains("point 1") && Catch::Contains("outside the level's bounds"));
  }
  SECTION("closer to the floor than the body's height") {
    CHECK_THROWS_WITH(bspc::dropUnreachableFaces(mesh, reachFrom({3, 0.2, 3}), report, warnings),
                      Catch::Contains("point 1") && Catch::Contains("within a body's size"));
  }
}

TEST_CASE(
    "reach points files: one x y z a line, comments and blank lines skipped, errors name the "
    "line",
    "[compiler][reach]") {
  const auto dir = bspf::test::freshTempDir("reach");
  const auto write = [&](const std::string& name, const std::string& text) {
    std::ofstream(dir / name) << text;
    return dir / name;
  };
  const auto points = bspc::readReachPoints(write("good.txt", "# spawns\n1 2 3\n\n  4 5 6\n"));
  REQUIRE(points.size() == 2);
  CHECK(points[1] == Vector3d(4, 5, 6));
  CHECK_THROWS_WITH(bspc::readReachPoints(write("bad.txt", "1 2 3\n1 2\n")),
                    Catch::Contains("bad.txt:2") && Catch::Contains("three finite numbers"));
  CHECK_THROWS_WITH(bspc::readReachPoints(write("nan.txt", "1 nan 3\n")),
                    Catch::Contains("nan.txt:1"));
  CHECK_THROWS_WITH(bspc::readReachPoints(write("extra.txt", "1 2 3 4\n")),
                    Catch::Contains("extra.txt:1"));
  CHECK_THROWS_WITH(bspc::readReachPoints(write("empty.txt", "# nothing\n")),
                    Catch::Contains("no points"));
  CHECK_THROWS_WITH(bspc::readReachPoints(dir / "missing.txt"), Catch::Contains("missing.txt"));
}

TEST_CASE("a level too large for the reach grid keeps every face, with a warning",
          "[compiler][reach]") {
  const bspc::Mesh mesh = room();
  bspc::ReachSettings settings = reachFrom({3, 1.5, 3});
  settings.maxCells = 1000;
  bspc::ReachReport report;
  std::vector<std::string> warnings;
  const bspc::Mesh kept = bspc::dropUnreachableFaces(mesh, settings, report, warnings);
  CHECK_FALSE(report.applied);
  CHECK(kept.triangles.size() == mesh.triangles.size());
  REQUIRE(warnings.size() == 1);
  CHECK_THAT(warnings[0], Catch::Contains("every face is kept"));
}

// The guarantee that matters: no body ever touches a dropped face, so both
// narrow phases move every body exactly as they do with the whole level.
TEST_CASE("bodies move bit for bit the same with and without the faces --reach-from drops",
          "[compiler][reach]") {
  const auto dir = bspf::test::freshTempDir("reach-arena");
  const auto source = bspf::test::samplesDir() / "arena.obj";
  // The reach rule alone: on the arena every face it drops is also a covered
  // face (lying against another solid), which the default drops first.
  bspc::CompileSettings whole;
  whole.dropCoveredFaces = false;
  bspc::CompileSettings reach = whole;
  reach.reach.from = bspc::readReachPoints(bspf::test::samplesDir() / "arena.spawns.txt");
  const bspc::CompileReport wholeReport = bspc::compileFile(source, dir / "whole.bspf", whole);
  const bspc::CompileReport reachReport = bspc::compileFile(source, dir / "reach.bspf", reach);
  REQUIRE(reachReport.reach.dropped > 0);
  CHECK(reachReport.triangles + reachReport.reach.dropped == wholeReport.triangles);
  const bspf::OpenResult a = bspf::openWorld(dir / "whole.bspf");
  const bspf::OpenResult b = bspf::openWorld(dir / "reach.bspf");
  REQUIRE(a);
  REQUIRE(b);
  for (const bspf::CollisionMethod method :
       {bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep}) {
    std::vector<bspf::Body> bodies;
    for (std::size_t i = 0; i < reach.reach.from.size(); ++i) {
      bspf::Body body;
      body.position = reach.reach.from[i].cast<float>() + bspf::Vec3(0, 0.3f, 0);
      body.radii = {0.45f, 0.85f};
      body.settings.method = method;
      bodies.push_back(body);
    }
    const int differing = bspf::test::differingWalkSteps(*a.world, *b.world, bodies, 400);
    CHECK(differing == 0);
  }
}

TEST_CASE("the faces --reach-from keeps keep their surfaces, and a surface left unused goes",
          "[compiler][reach][surfaces]") {
  bspc::Mesh mesh = room();
  mesh.surfaces = {"stone", "lava"};
  mesh.triangleSurfaces.assign(mesh.triangles.size(), 0);
  append(mesh, boxMesh({10, 0, 0}, {11, 1, 1}));
  mesh.triangleSurfaces.resize(mesh.triangles.size(), 1);  // the box outside
  bspc::ReachReport report;
  std::vector<std::string> warnings;
  const bspc::Mesh kept =
      bspc::dropUnreachableFaces(mesh, reachFrom({3, 1.5, 3}), report, warnings);
  CHECK(kept.surfaces == std::vector<std::string>{"stone"});
  CHECK(kept.triangleSurfaces == std::vector<std::uint32_t>(kept.triangles.size(), 0));
}

TEST_CASE("the reach stage keeps the same faces on any number of threads",
          "[compiler][reach][threads]") {
  bspc::Mesh mesh = room(1.2);
  append(mesh, roomBeyond());
  append(mesh, boxMesh({20, 0, 0}, {21, 1, 1}));
  std::vector<std::string> warnings;
  bspc::ReachReport report;
  const bspc::Mesh alone =
      bspc::dropUnreachableFaces(mesh, reachFrom({3, 1.5, 3}), report, warnings);
  for (const int threads : {1, 2, 3}) {
    bspf::ThreadPool pool(threads);
    const bspc::Mesh shared =
        bspc::dropUnreachableFaces(mesh, reachFrom({3, 1.5, 3}), report, warnings, &pool);
    CHECK(shared.triangles == alone.triangles);
    CHECK(shared.vertices == alone.vertices);
  }
  CHECK(alone.triangles.size() < mesh.triangles.size());
}
