// SPDX-License-Identifier: MIT
// bspc's limits on size: an input whose blob or compile would be too large
// fails early with one line naming the file; the blob size estimate is a
// true lower bound; dense input still gets leaves of the size asked for.
#include <bspc/build_tree.h>
#include <bspc/clean.h>
#include <bspc/compile.h>
#include <bspc/write.h>
#include <bspf/world.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace fs = std::filesystem;

namespace {

// An n x n grid of quads over `size` metres, gently bumped, as an OBJ.
void writeGridObj(const fs::path& path, int n, double size) {
  std::ofstream out(path);
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x)
      out << "v " << x * size / n << " " << ((x * 7 + z * 13) % 5) * size / n * 0.2 << " "
          << z * size / n << "\n";
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const int a = z * (n + 1) + x + 1, b = a + 1, c = a + n + 1, d = c + 1;
      out << "f " << a << " " << c << " " << b << "\nf " << b << " " << c << " " << d << "\n";
    }
  REQUIRE(out);
}

// Compiles `input` with `settings`, recording the stages it reached (the
// progress lines' stage names, "build tree" of "47% build tree"); the
// error's text, empty when it succeeded.
std::string compileError(const fs::path& input, const fs::path& output,
                         bspc::CompileSettings settings, std::vector<std::string>& stages) {
  settings.progress = [&](std::string_view line) {
    const std::size_t space = line.find("% ");
    REQUIRE(space != std::string_view::npos);
    stages.emplace_back(line.substr(space + 2));
  };
  try {
    bspc::compileFile(input, output, settings);
  } catch (const bspc::CompileError& e) {
    return e.what();
  }
  return {};
}

}  // namespace

TEST_CASE("a mesh whose blob would exceed the size limit fails before the tree is built",
          "[compiler][limits]") {
  const fs::path dir = bspf::test::freshTempDir("limits-blob");
  writeGridObj(dir / "grid.obj", 40, 10.0);  // 3,200 triangles, 1,681 vertices
  bspc::CompileSettings settings;
  // Every triangle takes at least 158 bytes and every vertex 12: 525,816
  // bytes at least.
  REQUIRE(bspc::minimumBlobBytes(1681, 3200) == 525816);
  settings.limits.maxBlobBytes = 400000;
  std::vector<std::string> stages;
  const std::string error = compileError(dir / "grid.obj", dir / "grid.bspf", settings, stages);
  INFO(error);
  CHECK_THAT(error, Catch::Contains("grid.obj") && Catch::Contains("too large") &&
                        Catch::Contains("at least") && Catch::Contains("400000 bytes") &&
                        Catch::Contains("3200 triangles"));
  CHECK(error.find('\n') == std::string::npos);
  CHECK(std::find(stages.begin(), stages.end(), "clean") != stages.end());
  CHECK(std::find(stages.begin(), stages.end(), "build tree") == stages.end());
  CHECK_FALSE(fs::exists(dir / "grid.bspf"));

  // Above the least it can take, but below the blob the tree makes: fails
  // once the tree is known, still before the blob is made.
  settings.limits.maxBlobBytes = 510000;
  stages.clear();
  const std::string late = compileError(dir / "grid.obj", dir / "grid.bspf", settings, stages);
  CHECK_THAT(late, Catch::Contains("grid.obj") && Catch::Contains("too large"));
  CHECK(std::find(stages.begin(), stages.end(), "serialise") == stages.end());
  CHECK_FALSE(fs::exists(dir / "grid.bspf"));

  settings.limits = {};
  CHECK(compileError(dir / "grid.obj", dir / "grid.bspf", settings, stages).empty());
  CHECK(fs::exists(dir / "grid.bspf"));
}

TEST_CASE("a mesh whose compile would exceed the memory limit fails right after import",
          "[compiler][limits]") {
  const fs::path dir = bspf::test::freshTempDir("limits-memory");
  writeGridObj(dir / "grid.obj", 40, 10.0);
  bspc::CompileSettings settings;
  settings.limits.maxMemoryBytes = 3200 * bspc::kPeakBytesPerTriangle - 1;
  std::vector<std::string> stages;
  const std::string error = compileError(dir / "grid.obj", dir / "grid.bspf", settings, stages);
  INFO(error);
  CHECK_THAT(error, Catch::Contains("grid.obj") && Catch::Contains("too large") &&
                        Catch::Contains("memory"));
  CHECK(std::find(stages.begin(), stages.end(), "clean") == stages.end());
  CHECK_FALSE(fs::exists(dir / "grid.bspf"));
  settings.limits.maxMemoryBytes = 3200 * bspc::kPeakBytesPerTriangle;
  CHECK(compileError(dir / "grid.obj", dir / "grid.bspf", settings, stages).empty());
}

TEST_CASE("the blob size estimate is below the blob, within its tables and build info",
          "[compiler][limits]") {
  for (const bspc::Mesh& mesh :
       {bspf::test::boxMesh({0, 0, 0}, {1, 1, 1}), [] {
          bspc::Mesh m = bspf::test::boxMesh({0, 0, 0}, {4, 1, 4});
          for (int i = 0; i < 30; ++i)
            bspf::test::append(m, bspf::test::boxMesh({i * 0.3, 1, 0}, {i * 0.3 + 0.2, 2, 0.5}));
          return m;
        }()}) {
    bspc::CompileReport report;
    const std::vector<std::uint8_t> blob = bspc::compileMesh(mesh, {}, "box.obj", report);
    const bspf::test::AlignedBytes bytes(blob);
    const bspf::World world = *bspf::viewWorld(bytes.span()).world;
    const std::uint64_t triangles = world.triangles().size();
    const std::uint64_t vertices = world.vertices().size();
    const std::uint64_t estimate =
        bspc::estimateBlobBytes(vertices, triangles, world.nodes().size(), world.leaves().size(),
                                world.leafTriangles().size());
    INFO("blob " << blob.size() << " estimate " << estimate);
    CHECK(bspc::minimumBlobBytes(vertices, triangles) <= estimate);
    CHECK(estimate <= blob.size());
    CHECK(blob.size() <= estimate + 1024);
  }
}

TEST_CASE("a dense grid of tiny triangles gets leaves of at most kDenseNodeTriangles",
          "[compiler][limits]") {
  // 120 x 120 quads of 1 mm (28,800 triangles in 12 cm): no split pays for
  // itself at the 1 m query reach once a cell is under 6 cm, so the old
  // builder stopped at 4 leaves of up to 7,442 triangles (8,192 for two million
  // such triangles in a square metre).
  const int n = 120;
  bspc::Mesh mesh;
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x)
      mesh.vertices.emplace_back(x * 1e-3, ((x * 7 + z * 13) % 5) * 2e-4, z * 1e-3);
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const auto a = static_cast<std::uint32_t>(z * (n + 1) + x), b = a + 1, c = a + n + 1,
                 d = c + 1;
      mesh.triangles.push_back({a, c, b});
      mesh.triangles.push_back({b, c, d});
    }
  bspc::CompileReport report;
  const std::vector<std::uint8_t> blob = bspc::compileMesh(mesh, {}, "dense.obj", report);
  INFO("leaves " << report.tree.leaves << ", depth " << report.tree.depthMax
                 << ", references per triangle " << report.tree.referencesPerTriangle);
  CHECK(report.triangles == 2 * n * n);
  CHECK(report.tree.trianglesPerLeafMax <= bspc::kDenseNodeTriangles);
  // Split where it helps, not everywhere: no more than about two references
  // a triangle (a 1 mm quad straddles few planes).
  CHECK(report.tree.referencesPerTriangle < 2.0);
}
