// SPDX-License-Identifier: MIT
// The narrow phases' candidate lists (private: runtime/src/workspace.h,
// candidate_blocks.cpp, slide.h): the SSE masks the step uses must give the
// same bits as the one-lane-at-a-time reference, the reference must mean
// what the narrow phases need, and a slide's list must hold every triangle
// near each box it asks for.
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <random>
#include <set>

#include "slide.h"
#include "support/test_support.h"
#include "workspace.h"

using bspf::Bounds;
using bspf::Vec3;
using bspf::detail::CandidateBlock;
using bspf::detail::FaceTest;

namespace {

Vec3 randomPoint(std::mt19937& rng, float range) {
  std::uniform_real_distribution<float> u(-range, range);
  return {u(rng), u(rng), u(rng)};
}

// A block of random candidates; some lanes left empty, some boxes sharing a
// face with the query box (touching must count), some planes through the
// start or end (side value exactly 0).
CandidateBlock randomBlock(std::mt19937& rng, int used) {
  CandidateBlock block;
  for (int lane = 0; lane < used; ++lane) {
    const Vec3 a = randomPoint(rng, 4), b = randomPoint(rng, 4);
    const Vec3 normal = randomPoint(rng, 1).normalized();
    const FaceTest face{normal, std::uniform_real_distribution<float>(-3, 3)(rng),
                        std::uniform_real_distribution<float>(0, 1.5f)(rng)};
    bspf::detail::setLane(block, lane, a.cwiseMin(b), a.cwiseMax(b), face, std::uint32_t(lane));
  }
  bspf::detail::clearLanes(block, used);
  bspf::detail::sealBlock(block);
  return block;
}

}  // namespace

TEST_CASE("the SSE and AVX block masks give the same bits as the one-lane reference") {
  // Every path this CPU runs (the step uses the widest), each against the
  // one-lane reference.
  const std::vector<bspf::detail::MaskPath> paths = bspf::detail::availableMaskPaths();
  const bspf::detail::MaskPath path = GENERATE_COPY(from_range(paths));
  INFO("mask path " << int(path) << " of " << paths.size());
  std::mt19937 rng(7);
  int boxHits = 0, planesHits = 0, exactHits = 0;
  for (int round = 0; round < 20000; ++round) {
    CandidateBlock block = randomBlock(rng, int(rng() % 9));
    const Vec3 a = randomPoint(rng, 4), b = randomPoint(rng, 4);
    Bounds box{a.cwiseMin(b), a.cwiseMax(b)};
    if (round % 5 == 0) box.low.x() = block.highX[0];  // touching
    const Vec3 start = randomPoint(rng, 4), end = randomPoint(rng, 4);
    const std::uint32_t boxBits = bspf::detail::boxMaskOn(path, block, box);
    bspf::detail::LaneSides sides, scalarSides;
    const std::uint32_t planesBits =
        bspf::detail::planesMaskOn(path, block, box, start, end, sides);
    const std::uint32_t exactBits = bspf::detail::exactMaskOn(path, block, box, start, end);
    // What the step calls runs the widest path.
    if (path == paths.back()) {
      bspf::detail::LaneSides stepSides;
      REQUIRE(bspf::detail::boxMask(block, box) == boxBits);
      REQUIRE(bspf::detail::planesMask(block, box, start, end, stepSides) == planesBits);
      REQUIRE(bspf::detail::exactMask(block, box, start, end) == exactBits);
      REQUIRE(bspf::detail::boxMaskFunction()(block, box) == boxBits);
      REQUIRE(bspf::detail::planesMaskFunction()(block, box, start, end, stepSides) == planesBits);
      REQUIRE(bspf::detail::exactMaskFunction()(block, box, start, end) == exactBits);
    }
    INFO("round " << round);
    REQUIRE(boxBits == bspf::detail::scalarBoxMask(block, box));
    REQUIRE(planesBits == bspf::detail::scalarPlanesMask(block, box, start, end, scalarSides));
    // The side values the slide reads for the lanes that pass: the same
    // bits, and the distances of start and end to the lane's plane.
    for (std::uint32_t bits = planesBits; bits != 0; bits &= bits - 1) {
      const int lane = std::countr_zero(bits);
      REQUIRE(sides.start[lane] == scalarSides.start[lane]);
      REQUIRE(sides.end[lane] == scalarSides.end[lane]);
      const Vec3 normal(block.normalX[lane], block.normalY[lane], block.normalZ[lane]);
      REQUIRE(sides.start[lane] == Approx(normal.dot(start) - block.distance[lane]).margin(1e-5));
      REQUIRE(sides.end[lane] == Approx(normal.dot(end) - block.distance[lane]).margin(1e-5));
    }
    REQUIRE(exactBits == bspf::detail::scalarExactMask(block, box, start, end));
    REQUIRE((planesBits & ~boxBits) == 0);
    REQUIRE((exactBits & ~boxBits) == 0);
    boxHits += boxBits != 0;
    planesHits += planesBits != 0;
    exactHits += exactBits != 0;
  }
  // The cases exercise every outcome, not only empty masks.
  CHECK(boxHits > 2000);
  CHECK(planesHits > 500);
  CHECK(exactHits > 500);
}

TEST_CASE("a block mask keeps exactly the lanes whose box and side values pass") {
  CandidateBlock block;
  const FaceTest floor{Vec3::UnitY(), 0.0f, 0.85f};  // the plane y = 0, reach 0.85 m
  const Vec3 low(-1, 0, -1), high(1, 0, 1);
  bspf::detail::setLane(block, 0, low, high, floor, 0);
  bspf::detail::setLane(block, 1, low + Vec3(5, 0, 0), high + Vec3(5, 0, 0), floor, 1);  // far
  bspf::detail::setLane(block, 2, low, high, {-Vec3::UnitY(), 0.0f, 0.85f}, 2);  // facing down
  bspf::detail::clearLanes(block, 3);
  bspf::detail::sealBlock(block);
  const Bounds swept{Vec3(-0.5f, -0.1f, -0.5f), Vec3(0.5f, 1.8f, 0.5f)};
  const Vec3 start(0, 0.9f, 0), end(0, 0.8f, 0);  // a body settling onto the floor

  CHECK(bspf::detail::boxMask(block, swept) == 0b101u);
  // Planes: the end within reach of the floor, the start in front of it;
  // the downward-facing plane has the start behind it.
  bspf::detail::LaneSides sides;
  CHECK(bspf::detail::planesMask(block, swept, start, end, sides) == 0b001u);
  CHECK(sides.start[0] == Approx(0.9f));
  CHECK(sides.end[0] == Approx(0.8f));
  CHECK(bspf::detail::exactMask(block, swept, start, end) == 0b001u);
  // Moving away, out of reach: the planes method needs the end within reach.
  CHECK(bspf::detail::planesMask(block, swept, Vec3(0, 0.9f, 0), Vec3(0, 1.0f, 0), sides) == 0u);
  // The exact sweep keeps a path that starts within reach.
  CHECK(bspf::detail::exactMask(block, swept, Vec3(0, 0.8f, 0), Vec3(0, 1.0f, 0)) == 0b001u);
  // Unused lanes never pass, even for a box around everything.
  CHECK(bspf::detail::boxMask(block, {Vec3::Constant(-100), Vec3::Constant(100)}) == 0b111u);
  CHECK(bspf::detail::scalarBoxMask(block, {Vec3::Constant(-100), Vec3::Constant(100)}) == 0b111u);
  // A box merely touching the lane's box counts.
  CHECK(bspf::detail::boxMask(block, {Vec3(1, 0, 1), Vec3(2, 1, 2)}) == 0b101u);
}

TEST_CASE("the block box test a scan makes before a block's mask agrees with boxesOverlap") {
  // Random blocks against random boxes, a fifth touching along one axis, a
  // few with a NaN bound (which no test lets through); every outcome counted.
  std::mt19937 rng(11);
  int met = 0, missed = 0, touching = 0;
  for (int round = 0; round < 20000; ++round) {
    const int used = 1 + int(rng() % 8);
    CandidateBlock block = randomBlock(rng, used);
    const Vec3 a = randomPoint(rng, 5), b = randomPoint(rng, 5);
    Bounds box{a.cwiseMin(b), a.cwiseMax(b)};
    const int axis = int(rng() % 3);
    if (round % 5 == 1) box.low[axis] = block.high[axis];  // touching from above
    if (round % 5 == 2) box.high[axis] = block.low[axis];  // touching from below
    if (round % 97 == 0) box.high[axis] = std::numeric_limits<float>::quiet_NaN();
    const bool expected = bspf::boxesOverlap(block.low, block.high, box.low, box.high);
    INFO("round " << round);
    REQUIRE(bspf::detail::BlockBoxTest(box).meets(block) == expected);
    // A block it passes over has no lane the masks would keep.
    if (!expected) REQUIRE(bspf::detail::scalarBoxMask(block, box) == 0);
    met += expected;
    missed += !expected;
    touching += expected && (round % 5 == 1 || round % 5 == 2);
  }
  CHECK(met > 2000);
  CHECK(missed > 2000);
  CHECK(touching > 1000);
}

TEST_CASE("a slide's candidate blocks hold every triangle near each box it asks for") {
  // A row of 40 small boxes along x: far more triangles than one query lists.
  bspc::Mesh mesh;
  for (int i = 0; i < 40; ++i)
    bspf::test::append(mesh, bspf::test::boxMesh({0.5 * i, 0, -0.1}, {0.5 * i + 0.2, 0.3, 0.1}));
  const bspf::test::CompiledMesh level(mesh);
  const bspf::World& world = level.world;
  const bspf::EllipsoidRadii radii{0.45f, 0.85f};
  bspf::StepScratch scratch;
  bspf::detail::StepWorkspace& workspace = scratch.workspace();
  bspf::LocalCandidates local(
      bspf::detail::activePlanes(workspace), workspace.listed, workspace.sorted,
      [&](std::uint32_t triangle) { return bspf::detail::planesFaceTest(world, triangle, radii); });
  // A slide's iterations ask for boxes further and further along the row
  // (as a long slide would), each outside the last one's local box.
  for (float x : {0.0f, 0.3f, 2.0f, 9.0f, 15.5f}) {
    const Vec3 from(x, 0.5f, 0), to(x + 0.2f, 0.45f, 0);
    const Bounds swept = bspf::sweptBounds(from, to, radii);
    std::set<std::uint32_t> listed;
    for (const CandidateBlock* block : local.around(world, swept, 0.2f, radii, scratch))
      for (std::uint32_t bits = bspf::detail::boxMask(*block, swept); bits; bits &= bits - 1)
        listed.insert(local.triangle(block->slot[std::countr_zero(bits)]));
    // Brute force: every triangle whose box overlaps the swept box.
    std::set<std::uint32_t> expected;
    for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
      const bspf::schema::Triangle& tri = world.triangles()[t];
      Vec3 low = bspf::toVec3(world.vertices()[tri.v0()]), high = low;
      for (const std::uint32_t v : {tri.v1(), tri.v2()}) {
        low = low.cwiseMin(bspf::toVec3(world.vertices()[v]));
        high = high.cwiseMax(bspf::toVec3(world.vertices()[v]));
      }
      if (bspf::boxesOverlap(low, high, swept.low, swept.high)) expected.insert(t);
    }
    INFO("swept box from x = " << x);
    CHECK(!expected.empty());
    for (const std::uint32_t t : expected) CHECK(listed.count(t) == 1);
  }
}

TEST_CASE("the six-plane test with SSE agrees with the plane-by-plane reference") {
  std::mt19937 rng(11);
  int inside = 0;
  for (int round = 0; round < 20000; ++round) {
    bspf::detail::GrownTriangle grown;
    for (int k = 0; k < 6; ++k)
      grown.set(k, randomPoint(rng, 1).normalized(),
                std::uniform_real_distribution<float>(-3, 0.5f)(rng));
    for (int k = 6; k < 8; ++k) grown.set(k, Vec3::Zero(), -std::numeric_limits<float>::infinity());
    const Vec3 p = randomPoint(rng, 2);
    INFO("round " << round);
    REQUIRE(grown.inside(p) == grown.insideOneByOne(p));
    inside += grown.inside(p);
  }
  CHECK(inside > 1000);  // both outcomes exercised
  CHECK(inside < 19000);
}

TEST_CASE("a push's four-lane clearance box has the bits of the swept box grown by the margin",
          "[runtime][bodies]") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> unit(-1, 1);
  int moved = 0;
  for (int round = 0; round < 20000; ++round) {
    // Coordinates from centimetres to 100 km (the pad grows with them), a
    // push of up to a metre, none at all, or between +0 and -0.
    const float scale = std::pow(10.0f, float(round % 8) - 2);
    const bspf::Vec3 from(scale * unit(rng), scale * unit(rng), scale * unit(rng));
    bspf::Vec3 to = from + bspf::Vec3(unit(rng), 0.1f * unit(rng), unit(rng));
    if (round % 5 == 0) to = from;
    const bool zeros = round % 7 == 0;
    const bspf::Vec3 zeroFrom(0.0f, -0.0f, 0.0f), zeroTo(-0.0f, 0.0f, -0.0f);
    const bspf::EllipsoidRadii radii{0.2f + 0.5f * std::abs(unit(rng)),
                                     0.3f + 0.8f * std::abs(unit(rng))};
    const float margin = 0.25f * 0.02f * (1 + std::abs(unit(rng)));
    const bspf::Vec3& a = zeros ? zeroFrom : from;
    const bspf::Vec3& b = zeros ? zeroTo : to;
    bspf::Bounds expected = bspf::sweptBounds(a, b, radii);
    expected.low.array() -= margin;
    expected.high.array() += margin;
    const bspf::Bounds box = bspf::detail::pushBounds(a, b, radii, margin);
    INFO("round " << round);
    REQUIRE((box.low.array() == expected.low.array()).all());
    REQUIRE((box.high.array() == expected.high.array()).all());
    moved += !(a == b);
  }
  CHECK(moved > 10000);  // most boxes are of a move, not of a point
}
