// SPDX-License-Identifier: MIT
// The accuracy oracle (bench/support/oracle.h) against known answers, and
// what it says of the two narrow phases.
#include "oracle.h"

#include <bspc/import.h>

#include <catch2/catch.hpp>
#include <random>

#include "brushes.h"
#include "support/test_support.h"
#include "walkers_sim.h"

using bspf::Vec3;

namespace {

struct Compiled {
  bspf::test::AlignedBytes bytes;
  bspf::World world;
  explicit Compiled(const bspc::Mesh& mesh)
      : bytes(bspf::test::compile(mesh)), world(*bspf::viewWorld(bytes.span()).world) {}
};

}  // namespace

TEST_CASE("the oracle measures an ellipsoid's penetration as a fraction of its size",
          "[bench][oracle]") {
  const Compiled floor(bspf::test::boxMesh({-5, -1, -5}, {5, 0, 5}));
  const bspf::oracle::LevelTriangles judged(floor.world);
  const bspf::EllipsoidRadii radii{0.45f, 0.85f};
  auto depth = [&](const Vec3& c) { return bspf::oracle::penetration(judged, c, radii); };
  CHECK(depth({0, 2, 0}) == 0);                                  // clear
  CHECK(depth({0, 0.85f, 0}) == Approx(0).margin(1e-6));         // touching
  CHECK(depth({0, 0.425f, 0}) == Approx(0.5).margin(1e-6));      // half way in
  CHECK(depth({4.8f, 0.425f, 0}) == Approx(0.5).margin(1e-6));   // near the edge, still the face
  CHECK(depth({5.45f, -0.5f, 0}) == Approx(0).margin(1e-6));     // touching the side face
  CHECK(depth({5.225f, -0.5f, 0}) == Approx(0.5).margin(1e-6));  // half into the side
}

TEST_CASE("the winding-number inside test agrees with the brush planes on the arena",
          "[bench][oracle]") {
  // Compiled with every face kept: dropping the faces pressed between
  // touching solids leaves the rest closed only as a union.
  bspc::CompileSettings keepAll;
  keepAll.dropCoveredFaces = false;
  const bspf::test::CompiledMesh compiled(
      bspc::importMesh(bspf::test::samplesDir() / "arena.obj", {}), keepAll);
  const bspf::World& arena = compiled.world;
  const auto brushes =
      bspf::walkers::BrushSet::load(bspf::test::samplesDir() / "arena.brushes.txt");
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> x(-21, 21), y(-2, 5);
  int inside = 0, outside = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 p(x(rng), y(rng), x(rng));
    const bool surelyInside = brushes.insideAnySolid(p, 1e-3f);
    const bool surelyOutside = !brushes.insideAnySolid(p, -1e-3f);
    if (!surelyInside && !surelyOutside) continue;  // on a face: either answer is right
    INFO("point " << p.transpose());
    REQUIRE(bspf::oracle::insideClosedMesh(arena, p) == surelyInside);
    (surelyInside ? inside : outside)++;
  }
  REQUIRE(inside > 100);
  REQUIRE(outside > 100);
}

TEST_CASE("no walker ever penetrates the arena's surfaces, with either narrow phase",
          "[bench][oracle]") {
  const bspf::World arena = bspf::test::compileSample("arena");
  const auto spawns = bspf::walkers::loadSpawns(bspf::test::samplesDir() / "arena.spawns.txt");
  REQUIRE(spawns);
  for (const auto method : {bspf::CollisionMethod::ExactSweep, bspf::CollisionMethod::Planes}) {
    for (const float speed : {6.0f, 40.0f}) {
      bspf::walkers::Options options;
      options.frames = 300;
      options.speed = speed;
      options.method = method;
      const std::vector<Vec3> starts =
          bspf::walkers::startsFromSpawns(spawns.points, options.agents);
      bspf::walkers::Simulation sim(arena, starts, options);
      const bspf::oracle::LevelTriangles judged(arena);
      std::vector<double> depths;
      for (int f = 0; f < options.frames; ++f) {
        sim.step();
        for (const bspf::Body& b : sim.bodies())
          depths.push_back(bspf::oracle::penetration(judged, b.position, b.radii));
      }
      const double worst = *std::max_element(depths.begin(), depths.end());
      const double p99 = bspf::oracle::quantile(depths, 0.99);
      INFO((method == bspf::CollisionMethod::Planes ? "planes" : "exact")
           << " at " << speed << " m/s: penetration max " << worst << ", p99 " << p99);
      // Both keep the skin between body and surface: the exact sweep by
      // construction, the planes method because its six planes over-cover
      // the rounded region (it errs by ghost contacts, not by penetration).
      // Float rounding only: a ten-thousandth of the body's size.
      CHECK(worst < 1e-4);
    }
  }
}
