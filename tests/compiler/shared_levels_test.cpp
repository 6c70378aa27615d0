// SPDX-License-Identifier: MIT
// Every real level in ../shared/levels compiles, verifies and is described.
#include <bspc/compile.h>
#include <bspf/query.h>

#include <catch2/catch.hpp>
#include <fstream>

#include "support/test_support.h"

namespace {

// Triangle count in the OBJ, counted independently of assimp ("f a b c" lines).
std::size_t countObjFaces(const std::filesystem::path& obj) {
  std::ifstream in(obj);
  std::string line;
  std::size_t faces = 0;
  while (std::getline(in, line)) faces += line.rfind("f ", 0) == 0;
  return faces;
}

}  // namespace

TEST_CASE("every shared level compiles into a blob the runtime verifies",
          "[compiler][shared-levels]") {
  BSPF_SKIP_WITHOUT_SHARED_LEVELS();
  const auto dir = bspf::test::sharedLevelsDir();
  const std::filesystem::path outDir = bspf::test::freshTempDir("levels");
  for (const std::string& name : bspf::test::sharedLevelNames()) {
    DYNAMIC_SECTION(name) {
      const std::filesystem::path obj = dir / (name + ".obj");
      const std::filesystem::path out = outDir / (name + ".bspf");
      const bspc::CompileReport report = bspc::compileFile(obj, out, {});
      const bspf::OpenResult opened = bspf::openWorld(out);
      REQUIRE(opened);
      const bspf::World& world = *opened.world;

      // Nothing is lost but what cleaning and the covered and buried faces
      // report.
      const std::size_t faces = countObjFaces(obj);
      REQUIRE(report.clean.inputTriangles == faces);
      const std::size_t cleaned = faces - report.clean.droppedDegenerate -
                                  report.clean.droppedZeroArea - report.clean.droppedDuplicate;
      REQUIRE(world.triangles().size() ==
              cleaned - report.edges.droppedCovered - report.buried.dropped);
      // Cleaning is a repair, not a rewrite: under 2% of a real level dropped.
      REQUIRE(cleaned > 0.98 * double(faces));

      const bspf::TreeStats stats = bspf::computeTreeStats(world);
      REQUIRE(stats.depthMax <= 40);
      REQUIRE(stats.leaves == stats.nodes + 1);
      REQUIRE(stats.referencesPerTriangle >= 1.0);
      REQUIRE(std::filesystem::file_size(out) == report.outputBytes);

      // Every spawn point (a body's centre 0.3 m above it) lies in some leaf
      // and the query below it finds geometry to collide with (the floor;
      // some spawns are 17 m above it, one on oacmpctf3 over the hull's floor 43 m down).
      std::ifstream spawns(dir / (name + ".spawns.txt"));
      float x, y, z;
      bspf::SweepScratch scratch;
      std::vector<std::uint32_t> candidates;
      int spawnCount = 0;
      while (spawns >> x >> y >> z) {
        const bspf::Vec3 centre(x, y + 0.3f, z);
        bspf::collectCandidateTriangles(world, centre, centre - bspf::Vec3(0, 50, 0),
                                        {0.45f, 0.85f}, scratch, candidates);
        INFO("spawn " << x << " " << y << " " << z);
        REQUIRE(!candidates.empty());
        ++spawnCount;
      }
      REQUIRE(spawnCount > 0);
    }
  }
}
