// SPDX-License-Identifier: MIT
// Ghost edges: what bspc's edge classification and covered-face dropping
// change for the runtime (docs/algorithm.md, "Ghost edges").
#include <bspc/build_tree.h>
#include <bspc/clean.h>
#include <bspc/planes.h>
#include <bspc/write.h>
#include <bspf/movement.h>

#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>

#include "support/test_support.h"
#include "workspace.h"

using bspf::Body;
using bspf::Vec3;

namespace {

constexpr float kDt = 1.0f / 60.0f;

Body walker(const Vec3& at, bspf::CollisionMethod method) {
  Body b;
  b.position = at;
  b.radii = {0.45f, 0.85f};
  b.settings.method = method;
  return b;
}

// Walks `body` for `frames` frames with a constant force; returns how many
// moves were refused.
int walk(const bspf::World& world, Body& body, const Vec3& force, int frames) {
  bspf::StepScratch scratch;
  bspf::StepReport report;
  int refused = 0;
  for (int f = 0; f < frames; ++f) {
    bspf::stepBody(world, body, force, kDt, scratch, &report);
    refused += report.refused;
  }
  return refused;
}

const char* nameOf(bspf::CollisionMethod m) {
  return m == bspf::CollisionMethod::Planes ? "planes" : "exact";
}

}  // namespace

TEST_CASE("a body walks across the seams of touching floor boxes as across one box",
          "[runtime][movement]") {
  const auto method = GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(nameOf(method));
  // Five 2 m floor boxes side by side: before bspc dropped their pressed
  // faces, the planes method stopped at the first seam.
  bspc::Mesh blocks;
  for (int k = 0; k < 5; ++k)
    bspf::test::append(blocks, bspf::test::boxMesh({-6.0 + 2 * k, -1, -5}, {-4.0 + 2 * k, 0, 5}));
  const bspf::test::CompiledMesh seams(blocks);
  const bspf::test::CompiledMesh plain(bspf::test::boxMesh({-6, -1, -5}, {4, 0, 5}));
  Body across = walker({-5, 0.851f, 0.3f}, method), reference = across;
  const Vec3 force(60, 0, 10);
  CHECK(walk(seams.world, across, force, 80) == 0);
  walk(plain.world, reference, force, 80);
  CHECK((across.position - reference.position).norm() < 0.01f);
  CHECK(across.position.x() > 1.5f);  // crossed three seams
}

TEST_CASE("a body slides along a wall of touching blocks as along one block",
          "[runtime][movement]") {
  const auto method = GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(nameOf(method));
  bspc::Mesh blocks = bspf::test::boxMesh({-10, -1, -10}, {10, 0, 10});
  for (int k = 0; k < 8; ++k)
    bspf::test::append(blocks, bspf::test::boxMesh({2, 0, -8.0 + 2 * k}, {3, 3, -6.0 + 2 * k}));
  bspc::Mesh one = bspf::test::boxMesh({-10, -1, -10}, {10, 0, 10});
  bspf::test::append(one, bspf::test::boxMesh({2, 0, -8}, {3, 3, 8}));
  const bspf::test::CompiledMesh seams(blocks), plain(one);
  // Pushing into the wall at 27 degrees while sliding along it past 5 seams.
  Body slider = walker({1.3f, 0.851f, -7}, method), reference = slider;
  const Vec3 force = Vec3(1, 0, 2).normalized() * 60;
  CHECK(walk(seams.world, slider, force, 100) == 0);
  walk(plain.world, reference, force, 100);
  CHECK((slider.position - reference.position).norm() < 0.01f);
  CHECK(slider.position.z() > 2);
}

TEST_CASE("the planes method treats a plane the blob marks unmeetable as always holding",
          "[runtime][movement]") {
  // A unit square floor, its diagonal's edge plane marked unmeetable in each
  // triangle (as meetablePlanes(..., skipMirrored) marks it); outer edges kept.
  bspc::Mesh square;
  square.vertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}};
  square.triangles = {{0, 1, 2}, {0, 2, 3}};
  const bspc::CompileSettings settings;
  bspc::CleanReport clean;
  const bspc::Mesh mesh = bspc::cleanMesh(square, settings.clean, clean);
  const std::vector<std::uint8_t> masks{0b111011, 0b111110};
  const bspf::test::AlignedBytes bytes(
      bspc::serializeWorld(mesh, bspc::computeTrianglePlanes(mesh, masks),
                           bspc::buildTree(mesh, settings.tree, {}), {"square", settings, clean}));
  const bspf::OpenResult opened = bspf::viewWorld(bytes.span());
  REQUIRE(opened);
  const bspf::World& world = *opened.world;
  REQUIRE(world.triangles().size() == 2);
  for (std::uint32_t t = 0; t < 2; ++t) {
    INFO("triangle " << t);
    CHECK(world.trianglePlanes()[t].meetable() == masks[t]);
    bspf::detail::GrownTriangle grown;
    bspf::detail::growPlanes(world, t, {0.1f, 0.1f}, grown);
    // Over the other triangle, beyond this one's diagonal by more than the
    // body's size: inside, the diagonal's plane skipped.
    const Vec3 otherSide = t == 0 ? Vec3(0.8f, 0.1f, 0.2f) : Vec3(0.2f, 0.1f, 0.8f);
    CHECK(grown.inside(otherSide));
    CHECK(grown.insideOneByOne(otherSide));
    // Beyond an outer edge by more than the body's size: outside.
    const Vec3 beyond = t == 0 ? Vec3(-0.3f, 0.1f, 0.5f) : Vec3(1.3f, 0.1f, 0.5f);
    CHECK_FALSE(grown.inside(beyond));
  }
  // As bspc compiles the same square: every plane kept, so the diagonal bounds it.
  const bspf::test::CompiledMesh compiled(square);
  bspf::detail::GrownTriangle grown;
  bspf::detail::growPlanes(compiled.world, 0, {0.1f, 0.1f}, grown);
  CHECK(compiled.world.trianglePlanes()[0].meetable() == 0b111111);
  CHECK_FALSE(grown.inside(Vec3(0.8f, 0.1f, 0.2f)));
}

TEST_CASE("a body walks over a 1 cm lip as over a flat floor", "[runtime][movement]") {
  const auto method = GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(nameOf(method));
  // Two abutting slabs, the far one 1 cm higher: the lip face's top edge is
  // convex, and its squared-off plane held a planes body standing on the
  // lower slab (centre 0.851 m up, under 0.01 + 0.85 m).
  bspc::Mesh slabs = bspf::test::boxMesh({-10, -1, -5}, {0, 0, 5});
  bspf::test::append(slabs, bspf::test::boxMesh({0, -1, -5}, {10, 0.01, 5}));
  const bspf::test::CompiledMesh lip(slabs);
  const bspf::test::CompiledMesh plain(bspf::test::boxMesh({-10, -1, -5}, {10, 0, 5}));
  for (const Vec3& force : {Vec3(60, 0, 0), Vec3(Vec3(1, 0, 0.577f).normalized() * 60)}) {
    Body over = walker({-3, 0.851f, -1}, method), reference = over;
    CHECK(walk(lip.world, over, force, 90) == 0);
    walk(plain.world, reference, force, 90);
    // Its path along x, against the one on a flat floor.
    CHECK(over.position.x() > 1);  // crossed the lip at x = 0
    CHECK(over.position.x() + 3 > 0.95f * (reference.position.x() + 3));
    CHECK(over.position.y() > 0.01f + 0.85f);  // on the upper slab
  }
}

TEST_CASE("a body crosses a floor gap narrower than itself without refused moves",
          "[runtime][movement]") {
  const auto method = GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(nameOf(method));
  // Two floor blocks 0.75 m apart (the body is 0.9 m wide): the gap's side
  // faces have convex top edges whose squared planes pushed a planes body
  // standing over the gap back and forth until its moves were refused.
  bspc::Mesh floor = bspf::test::boxMesh({-10, -1, -5}, {0, 0, 5});
  bspf::test::append(floor, bspf::test::boxMesh({0.75, -1, -5}, {10, 0, 5}));
  const bspf::test::CompiledMesh gap(floor);
  for (const Vec3& force : {Vec3(60, 0, 0), Vec3(Vec3(1, 0, 0.577f).normalized() * 60),
                            Vec3(Vec3(0.2f, 0, 1).normalized() * 60)}) {
    Body body = walker({-1, 0.851f, -2}, method);
    CHECK(walk(gap.world, body, force, 60) == 0);
    CHECK(body.position.y() > 0.3f);  // held by the edges (the exact sweep dips 0.38 m)
  }
  // Walking across it.
  Body across = walker({-3, 0.851f, 0}, method);
  CHECK(walk(gap.world, across, Vec3(60, 0, 0), 90) == 0);
  CHECK(across.position.x() > 2);
}

TEST_CASE("a riser higher than a rounded body rides stays a wall for the planes method",
          "[runtime][movement]") {
  const auto method = GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(nameOf(method));
  // Steps of 0.15 m and 0.6 m: the body's rounded bottom meets their top
  // edges steep (it rides only edges under about 0.10 m), so neither method
  // climbs them without step-up (MovementSettings::maxStepHeight).
  for (const double riser : {0.15, 0.6}) {
    INFO("riser " << riser);
    bspc::Mesh steps = bspf::test::boxMesh({-10, -1, -5}, {0, 0, 5});
    bspf::test::append(steps, bspf::test::boxMesh({0, -1, -5}, {10, riser, 5}));
    const bspf::test::CompiledMesh level(steps);
    Body body = walker({-3, 0.851f, 0}, method);
    walk(level.world, body, Vec3(60, 0, 0), 90);
    CHECK(body.position.x() < 0);  // before the riser
    CHECK(body.position.y() < 0.9f);
  }
}
