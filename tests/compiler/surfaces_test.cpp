// SPDX-License-Identifier: MIT
// Surfaces: bspc keeps each triangle's source material (an OBJ's usemtl) as a
// surface id and a table of names through import, clean and the tree, shows
// them in --info, and leaves surfaces out (--drop-surface) or keeps only some
// (--only-surface); unknown names and both options together are errors.
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspf/world.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace fs = std::filesystem;
using Catch::Contains;

namespace {

using bspf::test::quoted;
using bspf::test::runBspc;
using bspf::test::writeText;

// A 10 m floor of material "grass" (2 triangles at y = 0, facing up), a wall
// of "stone" (2 triangles at z = -5, facing +z) and a ramp of "grass" again
// after the wall (2 triangles): the second use of grass must not make a
// third surface. Vertices are repeated per face (welded by clean). The
// library also names "unused", which no face uses.
fs::path writeTwoMaterialObj(const fs::path& dir) {
  writeText(dir / "two.mtl",
            "newmtl grass\nKd 0 1 0\nnewmtl stone\nKd 0.5 0.5 0.5\nnewmtl unused\nKd 1 0 0\n");
  writeText(dir / "two.obj",
            "mtllib two.mtl\n"
            "v -5 0 -5\nv 5 0 -5\nv 5 0 5\nv -5 0 5\n"
            "v -5 0 -5\nv -5 3 -5\nv 5 3 -5\nv 5 0 -5\n"
            "v 5 0 5\nv 5 0 -5\nv 8 1 -5\nv 8 1 5\n"
            "usemtl grass\nf 1 4 3\nf 1 3 2\n"
            "usemtl stone\nf 5 8 7\nf 5 7 6\n"
            "usemtl grass\nf 9 10 11\nf 9 11 12\n");
  return dir / "two.obj";
}

bspf::schema::Vec3 corner(const bspf::World& world, std::uint32_t triangle, int k) {
  const bspf::schema::Triangle& t = world.triangles()[triangle];
  return world.vertices()[k == 0 ? t.v0() : k == 1 ? t.v1() : t.v2()];
}

// Whether a triangle is one of the wall's: every corner at z = -5 and x in
// [-5, 5] (the ramp touches z = -5 along one edge only).
bool isWall(const bspf::World& world, std::uint32_t triangle) {
  for (int k = 0; k < 3; ++k)
    if (corner(world, triangle, k).z() != -5.0f || corner(world, triangle, k).x() > 5.0f)
      return false;
  return true;
}

// bspc run on two.obj with `options` into DIR/out.bspf, which must compile;
// the blob opened.
bspf::World compiledWith(const fs::path& dir, const std::string& options) {
  const auto r =
      runBspc(quoted(dir / "two.obj") + " -q " + options + " -o " + quoted(dir / "out.bspf"));
  INFO(r.err);
  REQUIRE(r.status == 0);
  const bspf::OpenResult opened = bspf::openWorld(dir / "out.bspf");
  REQUIRE(opened);
  return *opened.world;
}

}  // namespace

TEST_CASE("an OBJ with two usemtl materials keeps both surface ids through the compile",
          "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  const fs::path obj = writeTwoMaterialObj(dir);
  SECTION("the import gives each triangle its material, one surface per name") {
    bspc::ImportSettings settings;
    settings.contained = false;
    const bspc::Mesh mesh = bspc::importMesh(obj, settings);
    CHECK(mesh.surfaces == std::vector<std::string>{"grass", "stone"});
    CHECK(mesh.triangleSurfaces == std::vector<std::uint32_t>{0, 0, 1, 1, 0, 0});
    SECTION("and the contained import sends them back the same") {
      const bspc::Mesh contained = bspc::importMeshContained(obj, bspc::ImportSettings{});
      CHECK(contained.surfaces == mesh.surfaces);
      CHECK(contained.triangleSurfaces == mesh.triangleSurfaces);
    }
  }
  SECTION("the blob's table and each triangle's id follow the material") {
    bspc::compileFile(obj, dir / "two.bspf", bspc::CompileSettings{});
    const bspf::OpenResult opened = bspf::openWorld(dir / "two.bspf");
    REQUIRE(opened);
    const bspf::World& world = *opened.world;
    REQUIRE(world.surfaceCount() == 2);
    CHECK(world.surfaceName(0) == "grass");
    CHECK(world.surfaceName(1) == "stone");
    CHECK(world.findSurface("stone") == 1u);
    CHECK_FALSE(world.findSurface("unused").has_value());
    REQUIRE(world.triangles().size() == 6);
    for (std::uint32_t t = 0; t < world.triangles().size(); ++t)
      CHECK(world.triangleSurface(t) == (isWall(world, t) ? 1u : 0u));
  }
}

TEST_CASE("surface ids follow their triangles through weld, dropped triangles and a deep tree",
          "[compiler][surfaces]") {
  // Eight boxes, box b of surface "s(b % 3)"; each box's first triangle is
  // repeated (a duplicate, dropped) and a degenerate triangle of surface
  // "gone" is added (dropped: its surface must not stay in the table).
  bspc::Mesh mesh;
  mesh.surfaces = {"s0", "s1", "s2", "gone"};
  for (int b = 0; b < 8; ++b) {
    const Eigen::Vector3d low(2.0 * b, 0.25 * b, 0), high(2.0 * b + 1, 0.25 * b + 1, 1);
    bspf::test::append(mesh, bspf::test::boxMesh(low, high));
    mesh.triangleSurfaces.resize(mesh.triangles.size(), std::uint32_t(b % 3));
    mesh.triangles.push_back(mesh.triangles[mesh.triangles.size() - 12]);
    mesh.triangleSurfaces.push_back(std::uint32_t(b % 3));
  }
  mesh.triangles.push_back({0, 0, 1});
  mesh.triangleSurfaces.push_back(3);
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = 1;
  settings.tree.queryReach = 0;
  const std::vector<std::uint8_t> blob = bspf::test::compile(mesh, settings);
  const bspf::test::AlignedBytes bytes(blob);
  const bspf::OpenResult opened = bspf::viewWorld(bytes.span());
  REQUIRE(opened);
  const bspf::World& world = *opened.world;
  REQUIRE(world.triangles().size() == 8 * 12);
  REQUIRE(world.nodes().size() > 0);
  REQUIRE(world.surfaceCount() == 3);
  for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
    // The box a triangle belongs to, from its lowest x.
    const float x =
        std::min({corner(world, t, 0).x(), corner(world, t, 1).x(), corner(world, t, 2).x()});
    const int box = static_cast<int>(x / 2 + 0.25f);
    INFO("triangle " << t << ", box " << box);
    CHECK(world.surfaceName(world.triangleSurface(t)) ==
          std::string("s") + std::to_string(box % 3));
  }
  SECTION("the same input gives the same bytes") {
    CHECK(bspf::test::compile(mesh, settings) == blob);
  }
}

TEST_CASE("a mesh without materials has one surface named default", "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  writeText(dir / "plain.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 3 2\n");
  bspc::compileFile(dir / "plain.obj", dir / "plain.bspf", bspc::CompileSettings{});
  const bspf::OpenResult opened = bspf::openWorld(dir / "plain.bspf");
  REQUIRE(opened);
  REQUIRE(opened.world->surfaceCount() == 1);
  CHECK(opened.world->surfaceName(0) == "default");
  CHECK(opened.world->triangleSurface(0) == 0);
  SECTION("likewise a mesh made in memory without surfaces") {
    const bspf::test::CompiledMesh compiled(
        bspf::test::boxMesh(Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()));
    REQUIRE(compiled.world.surfaceCount() == 1);
    CHECK(compiled.world.surfaceName(0) == "default");
  }
}

TEST_CASE("bspc --drop-surface leaves out exactly the triangles of that surface",
          "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  const fs::path obj = writeTwoMaterialObj(dir);
  const bspf::World world = compiledWith(dir, "--drop-surface stone");
  CHECK(world.triangles().size() == 4);
  for (std::uint32_t t = 0; t < world.triangles().size(); ++t) CHECK_FALSE(isWall(world, t));
  REQUIRE(world.surfaceCount() == 1);
  CHECK(world.surfaceName(0) == "grass");
  CHECK(world.blob().build()->dropped_by_surface() == 2);
  SECTION("repeated, it drops each named surface") {
    const auto both = runBspc(quoted(obj) + " -q --drop-surface stone --drop-surface grass -o " +
                              quoted(dir / "none.bspf"));
    // Nothing is left: an error, and no output.
    CHECK(both.status == 1);
    CHECK_THAT(both.err, Contains("left out all 6 triangles"));
    CHECK_FALSE(fs::exists(dir / "none.bspf"));
  }
  SECTION("--info says how many the selection left out") {
    const auto info = runBspc("--info " + quoted(dir / "out.bspf"));
    REQUIRE(info.status == 0);
    CHECK_THAT(info.out, Contains("surface selection       2 triangles left out"));
  }
}

TEST_CASE("bspc --only-surface keeps only the triangles of the named surfaces",
          "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  const fs::path obj = writeTwoMaterialObj(dir);
  const bspf::World world = compiledWith(dir, "--only-surface stone");
  REQUIRE(world.triangles().size() == 2);
  for (std::uint32_t t = 0; t < 2; ++t) CHECK(isWall(world, t));
  REQUIRE(world.surfaceCount() == 1);
  CHECK(world.surfaceName(0) == "stone");
  SECTION("two names keep both") {
    const auto two = runBspc(quoted(obj) + " -q --only-surface stone --only-surface grass -o " +
                             quoted(dir / "two.bspf"));
    REQUIRE(two.status == 0);
    const bspf::OpenResult all = bspf::openWorld(dir / "two.bspf");
    REQUIRE(all);
    CHECK(all.world->triangles().size() == 6);
  }
}

TEST_CASE("an unknown surface name is a one-line error naming the file and the name",
          "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  const fs::path obj = writeTwoMaterialObj(dir);
  for (const std::string option : {"--drop-surface", "--only-surface"}) {
    INFO(option);
    const auto r = runBspc(quoted(obj) + " " + option + " lava -o " + quoted(dir / "out.bspf"));
    CHECK(r.status == 1);
    CHECK_THAT(r.err, Contains(obj.string()));
    CHECK_THAT(r.err, Contains("'lava'"));
    CHECK_THAT(r.err, Contains(option));
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("names are exact: case matters") {
    const auto r = runBspc(quoted(obj) + " --drop-surface Stone -o " + quoted(dir / "out.bspf"));
    CHECK(r.status == 1);
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("the library throws the same") {
    bspc::CompileSettings settings;
    settings.clean.dropSurfaces = {"lava"};
    CHECK_THROWS_WITH(bspc::compileFile(obj, dir / "out.bspf", settings),
                      Contains(obj.string()) && Contains("'lava'"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
}

TEST_CASE("bspc --drop-surface and --only-surface together are a usage error",
          "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  const fs::path obj = writeTwoMaterialObj(dir);
  const auto r = runBspc(quoted(obj) + " --drop-surface stone --only-surface grass -o " +
                         quoted(dir / "out.bspf"));
  CHECK(r.status == 2);
  CHECK_THAT(r.err, Contains("--drop-surface and --only-surface"));
  CHECK_FALSE(fs::exists(dir / "out.bspf"));
  bspc::CompileSettings settings;
  settings.clean.dropSurfaces = {"stone"};
  settings.clean.onlySurfaces = {"grass"};
  CHECK_THROWS_AS(bspc::validate(settings), bspc::CompileError);
}

TEST_CASE("bspc --info lists each surface with its triangle count", "[compiler][surfaces]") {
  const fs::path dir = bspf::test::freshTempDir("surfaces");
  const fs::path obj = writeTwoMaterialObj(dir);
  REQUIRE(runBspc(quoted(obj) + " -q -o " + quoted(dir / "two.bspf")).status == 0);
  const auto r = runBspc("--info " + quoted(dir / "two.bspf"));
  REQUIRE(r.status == 0);
  CHECK_THAT(r.out, Contains("surfaces                2 (id, triangles, name)\n"
                             "      0         4  \"grass\"\n"
                             "      1         2  \"stone\"\n"));
}
