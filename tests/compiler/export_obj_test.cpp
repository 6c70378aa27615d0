// SPDX-License-Identifier: MIT
// bspc --export-obj: the compiled model as an OBJ that imports back to the
// same triangles, written with the safety of the other outputs.
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspc/write.h>
#include <bspf/world.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace fs = std::filesystem;

namespace {

// For the shell: the temporary directories hold no '"', '$' or '`'.
std::string quoted(const fs::path& path) {
  std::ostringstream out;
  out << std::quoted(path.string());
  return out.str();
}

std::string readText(const fs::path& path) {
  std::ostringstream out;
  out << std::ifstream(path, std::ios::binary).rdbuf();
  return out.str();
}

using Corners = std::array<std::array<float, 3>, 3>;

// Each triangle as its three corners' positions, in its winding.
std::vector<Corners> corners(const bspf::World& world) {
  std::vector<Corners> out;
  for (const auto& t : world.triangles()) {
    Corners c;
    const std::uint32_t v[3] = {t.v0(), t.v1(), t.v2()};
    for (int k = 0; k < 3; ++k) {
      const auto& p = world.vertices()[v[k]];
      c[k] = {p.x(), p.y(), p.z()};
    }
    out.push_back(c);
  }
  return out;
}

std::vector<Corners> corners(const bspc::Mesh& mesh) {
  std::vector<Corners> out;
  for (const auto& t : mesh.triangles) {
    Corners c;
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = mesh.vertices[t[k]];
      c[k] = {float(p.x()), float(p.y()), float(p.z())};
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace

TEST_CASE("an exported OBJ imports back to the blob's triangles, in order and winding",
          "[compiler][export-obj]") {
  const fs::path dir = bspf::test::freshTempDir("export-obj");
  const fs::path input = bspf::test::samplesDir() / "arena.obj";
  bspc::compileFile(input, dir / "arena.bspf", {}, {}, dir / "arena-model.obj");
  const bspf::OpenResult opened = bspf::openWorld(dir / "arena.bspf");
  REQUIRE(opened);
  const std::vector<Corners> blob = corners(*opened.world);
  REQUIRE(blob.size() > 100);

  const std::string text = readText(dir / "arena-model.obj");
  CHECK(text.rfind("# bspc ", 0) == 0);
  CHECK_THAT(text, Catch::Contains("arena.obj"));
  CHECK(std::count(text.begin(), text.end(), 'f') >= std::ptrdiff_t(blob.size()));

  bspc::ImportSettings settings;
  settings.contained = false;
  const bspc::Mesh back = bspc::importMesh(dir / "arena-model.obj", settings);
  // Shortest round-trip digits: each coordinate reads back as the float the
  // blob holds.
  CHECK(corners(back) == blob);
}

TEST_CASE("toObj writes every vertex and triangle, 1-based", "[compiler][export-obj]") {
  bspc::Mesh mesh = bspf::test::boxMesh({0, 0, 0}, {1, 0.5f, 0.25f});
  bspc::CompileReport report;
  const std::vector<std::uint8_t> blob = bspc::compileMesh(mesh, {}, "box.obj", report);
  const bspf::OpenResult opened = bspf::viewWorld(std::as_bytes(std::span(blob)));
  REQUIRE(opened);
  const std::string text = bspc::toObj(*opened.world, "a box");
  CHECK(text.rfind("# a box\nv ", 0) == 0);
  CHECK(std::count(text.begin(), text.end(), 'v') ==
        std::ptrdiff_t(opened.world->vertices().size()));
  CHECK(std::count(text.begin(), text.end(), 'f') ==
        std::ptrdiff_t(opened.world->triangles().size()));
  CHECK_THAT(text, Catch::Contains("\nv 1 0.5 0.25\n"));
  const auto t = opened.world->triangles()[0];
  CHECK_THAT(
      text, Catch::Contains("\nf " + std::to_string(t.v0() + 1) + " " + std::to_string(t.v1() + 1) +
                            " " + std::to_string(t.v2() + 1) + "\n"));
}

TEST_CASE("bspc --export-obj refuses the other files' paths and writes all outputs or none",
          "[compiler][export-obj][bad-input]") {
  const fs::path dir = bspf::test::freshTempDir("export-obj-cli");
  fs::copy_file(bspf::test::samplesDir() / "arena.obj", dir / "arena.obj");
  const std::string original = readText(dir / "arena.obj");
  const std::string files = quoted(dir / "arena.obj") + " -o " + quoted(dir / "out.bspf");
  const auto bspc = [&](const std::string& arguments) {
    return bspf::test::run(quoted(bspf::test::bspcExecutable()) + " " + files + " " + arguments);
  };
  SECTION("the input") {
    const auto r = bspc("--export-obj " + quoted(dir / "." / "arena.obj"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("arena.obj") && Catch::Contains("overwrite the input"));
    CHECK(readText(dir / "arena.obj") == original);
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("the output") {
    const auto r = bspc("--export-obj " + quoted(dir / "out.bspf"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK_THAT(r.err, Catch::Contains("overwrite the output"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("the stats file") {
    const auto r =
        bspc("--stats-json " + quoted(dir / "s.json") + " --export-obj " + quoted(dir / "s.json"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK_THAT(r.err, Catch::Contains("overwrite the stats file"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
    CHECK_FALSE(fs::exists(dir / "s.json"));
  }
  SECTION("a directory that does not exist") {
    const auto r = bspc("--export-obj " + quoted(dir / "missing" / "model.obj"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK_THAT(r.err, Catch::Contains("model.obj"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("a directory in its place") {
    fs::create_directory(dir / "model.obj");
    const auto r = bspc("--export-obj " + quoted(dir / "model.obj"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK_THAT(r.err, Catch::Contains("model.obj") && Catch::Contains("directory"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("all written, no temporaries left") {
    const auto r = bspc("-q --export-obj " + quoted(dir / "model.obj"));
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(dir / "out.bspf"));
    CHECK(readText(dir / "model.obj").rfind("# bspc ", 0) == 0);
  }
  for (const auto& entry : fs::directory_iterator(dir))
    CHECK(entry.path().filename().string().find(".tmp-") == std::string::npos);
}
