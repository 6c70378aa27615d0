// SPDX-License-Identifier: MIT
#include <bspf/movement.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <thread>
#include <vector>

#include "support/test_support.h"

using bspf::Body;
using bspf::Vec3;

namespace {

constexpr float kDt = 1.0f / 60.0f;

using Level = bspf::test::CompiledMesh;

bspc::Mesh floorSlab() { return bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20}); }

// The floor with a 4 m wall along it whose face is the plane x = 5.
bspc::Mesh floorWithWall() {
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -20}, {6, 4, 20}));
  return mesh;
}

// The floor with a wall at x = 5 and another at z = 5: a 90 degree corner.
bspc::Mesh floorWithCorner() {
  bspc::Mesh mesh = floorWithWall();
  bspf::test::append(mesh, bspf::test::boxMesh({-20, 0, 5}, {6, 4, 6}));
  return mesh;
}

// A slab whose top face is a slope rising along +z at `degrees`, with its
// foot line at z = 0, y = 0.
bspc::Mesh slope(double degrees) {
  bspc::Mesh m = bspf::test::boxMesh({-4, -1, -20}, {4, 0, 20});
  const double angle = degrees * std::numbers::pi / 180;
  const Eigen::Matrix3d rotation =
      Eigen::AngleAxisd(-angle, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (Eigen::Vector3d& v : m.vertices) v = rotation * v;
  return m;
}

Body walker(const Vec3& at, bspf::CollisionMethod method = bspf::CollisionMethod::Planes) {
  Body b;
  b.position = at;
  b.radii = {0.45f, 0.85f};
  b.settings.method = method;
  return b;
}

// The behaviour tests run for both narrow phases.
bspf::CollisionMethod eachMethod() {
  return GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
}

const char* nameOf(bspf::CollisionMethod m) {
  return m == bspf::CollisionMethod::Planes ? "planes" : "exact";
}

void run(const bspf::World& world, Body& body, const Vec3& force, int frames,
         bspf::StepScratch& scratch, bspf::StepReport* last = nullptr) {
  for (int f = 0; f < frames; ++f) bspf::stepBody(world, body, force, kDt, scratch, last);
}

// The floor with six 0.3 m risers and 0.4 m treads going up along +x from
// x = 0 (to 1.8 m).
bspc::Mesh floorWithStairs() {
  bspc::Mesh mesh = floorSlab();
  for (int k = 0; k < 6; ++k)
    bspf::test::append(mesh, bspf::test::boxMesh({0.4 * k, 0, -2}, {15, 0.3 * (k + 1), 2}));
  return mesh;
}

// Steps `body` for `frames` frames with its horizontal velocity set to
// `horizontal` before each (a game driving its character by velocity, not
// force); returns the highest its centre rose above `startY`.
float highestRiseAtSetVelocity(const bspf::World& world, Body& body, const Vec3& horizontal,
                               int frames, float startY, bspf::StepScratch& scratch) {
  float highest = 0;
  for (int f = 0; f < frames; ++f) {
    body.velocity.x() = horizontal.x();
    body.velocity.z() = horizontal.z();
    bspf::stepBody(world, body, Vec3::Zero(), kDt, scratch);
    highest = std::max(highest, body.position.y() - startY);
  }
  return highest;
}

}  // namespace

TEST_CASE("a body dropped onto a floor lands and stays still", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorSlab());
  bspf::StepScratch scratch;
  Body body = walker({0, 3, 0}, method);
  bspf::StepReport report;
  run(level.world, body, Vec3::Zero(), 120, scratch, &report);
  REQUIRE(report.grounded);
  REQUIRE_FALSE(report.refused);
  // Resting on the floor: centre one y radius up, within the skin.
  REQUIRE(body.position.y() == Approx(0.85f).margin(2e-3));
  const Vec3 rest = body.position;
  run(level.world, body, Vec3::Zero(), 120, scratch, &report);
  REQUIRE((body.position - rest).norm() < 1e-5f);
  REQUIRE(body.velocity.norm() < 1e-4f);
}

TEST_CASE("a body hitting a wall at 45 degrees slides along it keeping its tangential velocity",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorWithWall();
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body body = walker({0, 0.851f, 0}, method);
  body.settings.groundFriction = 0;
  body.settings.maxHorizontalSpeed = 100;
  body.velocity = Vec3(4, 0, 4);  // 45 degrees into the wall
  bspf::StepReport report;
  float zBefore = 0;
  for (int f = 0; f < 120; ++f) {
    zBefore = body.position.z();
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
  }
  // Against the wall, not through it, and never refused: sliding succeeds.
  REQUIRE_FALSE(report.refused);
  REQUIRE(report.iterations >= 1);
  REQUIRE(body.position.x() == Approx(5 - 0.45f).margin(2e-3));
  // Tangential (z) speed unchanged, normal (x) speed removed.
  REQUIRE(body.velocity.z() == Approx(4.0f).epsilon(1e-4));
  REQUIRE(std::abs(body.velocity.x()) < 1e-4f);
  REQUIRE((body.position.z() - zBefore) / kDt == Approx(4.0f).epsilon(1e-3));
}

TEST_CASE("a body at 100 m/s never ends inside or beyond a 1 cm wall", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -10}, {5.01, 4, 10}));
  const Level level(mesh);
  bspf::StepScratch scratch;
  for (int trial = 0; trial < 50; ++trial) {
    Body body = walker({0, 0.851f + 0.02f * trial, -4.0f + 0.16f * trial}, method);
    body.settings.maxHorizontalSpeed = 100;
    body.velocity = Vec3(100, 0, 0.3f * (trial % 5));
    for (int f = 0; f < 30; ++f) {
      bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch);
      INFO("trial " << trial << " frame " << f << " at " << body.position.transpose());
      REQUIRE(body.position.x() <= 5 - 0.45f + 1e-3f);
    }
  }
}

TEST_CASE("a body stands still on a 30 degree slope and slides down a 60 degree one",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspf::StepScratch scratch;
  {
    const Level level(slope(30));
    Body body = walker({0, 6, 5}, method);
    run(level.world, body, Vec3::Zero(), 120, scratch);
    const Vec3 rest = body.position;
    bspf::StepReport report;
    run(level.world, body, Vec3::Zero(), 120, scratch, &report);
    REQUIRE(report.grounded);
    REQUIRE((body.position - rest).norm() < 1e-4f);
  }
  {
    const Level level(slope(60));
    Body body = walker({0, 12, 5}, method);
    run(level.world, body, Vec3::Zero(), 60, scratch);
    const Vec3 before = body.position;
    bspf::StepReport report;
    run(level.world, body, Vec3::Zero(), 30, scratch, &report);
    REQUIRE_FALSE(report.grounded);
    // It slides down the slope (towards -z and down), not through it.
    REQUIRE(body.position.y() < before.y() - 0.1f);
    REQUIRE(body.position.z() < before.z());
  }
}

TEST_CASE(
    "a body the game lifts off the ground it stood on falls back onto it and rests at the skin",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorSlab());
  bspf::StepScratch scratch;
  // Off the diagonal where the floor's two triangles meet: over the inside
  // of one.
  Body body = walker({3, 0.9f, 1}, method);
  run(level.world, body, Vec3::Zero(), 30, scratch);
  REQUIRE(body.grounded);
  REQUIRE(body.groundTriangles[0] != bspf::kNoTriangle);
  const float resting = 0.85f + body.settings.skin;
  REQUIRE(body.position.y() == Approx(resting).margin(1e-4));
  // Lifted 5 cm (the ground it stood on still its hint) and falling at
  // 6 m/s: the move reaches the floor within the frame.
  body.position.y() += 0.05f;
  body.velocity = Vec3(0, -6, 0);
  bspf::StepReport report;
  bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
  REQUIRE(report.grounded);
  REQUIRE(body.position.y() == Approx(resting).margin(1e-4));
}

TEST_CASE(
    "a grounded body the game puts 5 cm into a wall leaves it in one step, still on the floor",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithWall());
  bspf::StepScratch scratch;
  Body body = walker({3, 0.9f, 1}, method);
  run(level.world, body, Vec3::Zero(), 30, scratch);
  REQUIRE(body.grounded);
  // The wall's face is the plane x = 5.
  body.position.x() = 5 - 0.45f + 0.05f;
  bspf::StepReport report;
  bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
  REQUIRE_FALSE(report.refused);
  REQUIRE(report.grounded);
  REQUIRE(body.position.x() <= 5 - 0.45f);
  REQUIRE(body.position.y() == Approx(0.85f + body.settings.skin).margin(1e-4));
}

TEST_CASE(
    "with one slide allowed, a grounded body walking into the wall it rests against is refused, "
    "its ground and wall remembered or not",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithWall());
  bspf::StepScratch scratch;
  Body settled = walker({3, 0.9f, 1}, method);
  run(level.world, settled, Vec3(40, 0, 0), 120, scratch);
  REQUIRE(settled.grounded);
  // Against the wall at x = 5, within the skin.
  REQUIRE(settled.position.x() <= 5 - 0.45f);
  REQUIRE(settled.position.x() >= 5 - 0.45f - settled.settings.skin);
  for (const bool remembered : {true, false}) {
    INFO((remembered ? "remembered" : "forgotten"));
    Body body = settled;
    if (!remembered) {
      body.groundTriangles = bspf::kNoGroundTriangles;
      body.wallTriangles = bspf::kNoWallTriangles;
    }
    body.settings.maxIterations = 1;
    // The floor takes the one slide; the wall would need another.
    bspf::StepReport report;
    bspf::stepBody(level.world, body, Vec3(40, 0, 0), kDt, scratch, &report);
    REQUIRE(report.refused);
    REQUIRE(body.position.x() <= 5 - 0.45f);
  }
}

TEST_CASE(
    "a body running off a floor onto a ramp down meets the ramp within the frame, its ground "
    "remembered or not",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // The floor for z < 0, then a ramp going down at 20 degrees along +z.
  bspc::Mesh mesh = bspf::test::boxMesh({-4, -1, -20}, {4, 0, 0});
  bspc::Mesh ramp = bspf::test::boxMesh({-4, -1, 0}, {4, 0, 20});
  const Eigen::Matrix3d down =
      Eigen::AngleAxisd(20 * std::numbers::pi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
  for (Eigen::Vector3d& v : ramp.vertices) v = down * v;
  bspf::test::append(mesh, ramp);
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body settled = walker({0, 0.9f, -0.2f}, method);
  settled.settings.maxHorizontalSpeed = 100;
  run(level.world, settled, Vec3::Zero(), 30, scratch);
  REQUIRE(settled.grounded);
  // 40 m/s towards the ramp: 0.67 m a frame, over the floor's edge.
  settled.velocity = Vec3(0, 0, 40);
  Body remembered = settled, forgotten = settled;
  forgotten.groundTriangles = bspf::kNoGroundTriangles;
  forgotten.wallTriangles = bspf::kNoWallTriangles;
  bspf::StepReport withHints, without;
  bspf::stepBody(level.world, remembered, Vec3::Zero(), kDt, scratch, &withHints);
  bspf::stepBody(level.world, forgotten, Vec3::Zero(), kDt, scratch, &without);
  INFO("remembered ends at " << remembered.position.transpose() << ", forgotten at "
                             << forgotten.position.transpose());
  REQUIRE(without.grounded);
  REQUIRE(withHints.grounded);
  REQUIRE((remembered.position - forgotten.position).norm() < 1e-3f);
}

TEST_CASE("a body walks up a ramp", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, slope(20));
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body body = walker({0, 0.9f, -3}, method);
  run(level.world, body, Vec3::Zero(), 30, scratch);
  run(level.world, body, Vec3(0, 0, 60), 120, scratch);  // walk towards +z, up the ramp
  // Two seconds at 6 m/s: well up the 20 degree ramp.
  REQUIRE(body.position.z() > 5);
  REQUIRE(body.position.y() > 0.85f + std::tan(20 * std::numbers::pi_v<float> / 180) * 4);
}

// Issue 10, part 2: the exact sweep slid in sphere space, where the ellipsoid
// is a unit sphere, and on tilted surfaces that is not the world's tangent
// projection: down this slope it slid 5.89 m of 9.66, into the ramp below it
// rose 3.52 m, and it walked up these stairs with step height off.
TEST_CASE("a body set on a 60 degree slope slides down it as far as a frictionless block would",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(slope(60));
  bspf::StepScratch scratch;
  const float angle = 60 * std::numbers::pi_v<float> / 180;
  const Vec3 normal(0, std::cos(angle), -std::sin(angle));
  // Resting against the slope 15 m up it, at rest.
  const Vec3 onSlope(0, 15 * std::sin(angle), 15 * std::cos(angle));
  Body body = walker(onSlope, method);
  body.position += normal * (bspf::effectiveRadius(normal, body.radii) + body.settings.skin);
  const Vec3 start = body.position;
  constexpr int kFrames = 90;  // 1.5 s
  run(level.world, body, Vec3::Zero(), kFrames, scratch);
  // Gravity along the slope, g sin 60, integrated as the step does (the
  // velocity first, then the move: semi-implicit Euler) gives
  // g sin 60 dt^2 N (N + 1) / 2 = 9.66 m (the continuous 1/2 g sin 60 t^2
  // is 9.56 m). 1% tolerance: the skin kept at each contact.
  const float expected = 9.81f * std::sin(angle) * kDt * kDt * kFrames * (kFrames + 1) / 2;
  const Vec3 moved = body.position - start;
  INFO("slid " << moved.norm() << " m, expected " << expected << " m");
  REQUIRE(moved.norm() == Approx(expected).epsilon(0.01));
  // Down the slope, staying on it.
  REQUIRE(moved.z() < 0);
  REQUIRE(std::abs(moved.dot(normal)) < 0.01f);
}

TEST_CASE(
    "a body driven into a 60 degree ramp at a set velocity rises no higher than its speed along "
    "the ramp carries it",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, slope(60));  // its foot along z = 0
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body body = walker({0, 0.851f, -3}, method);
  constexpr float kSpeed = 6;
  const float highest =
      highestRiseAtSetVelocity(level.world, body, Vec3(0, 0, kSpeed), 180, 0.85f, scratch);
  // Against the ramp the body keeps only its speed along it, 6 cos 60 =
  // 3 m/s, which gravity takes away: it rises (6 cos 60)^2 / 2g = 0.46 m
  // and falls back, again and again, never further up. 10% tolerance for
  // the frame steps.
  const float angle = 60 * std::numbers::pi_v<float> / 180;
  const float rise = std::pow(kSpeed * std::cos(angle), 2.0f) / (2 * 9.81f);
  INFO("rose " << highest << " m, at most " << rise << " m");
  REQUIRE(highest <= 1.1f * rise);
}

TEST_CASE(
    "with step height off a body driven into 0.3 m stairs at a set velocity does not climb them",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithStairs());
  bspf::StepScratch scratch;
  Body body = walker({-2, 0.851f, 0}, method);
  // 6 m/s for 3 s: 18 m, far past the top if nothing stopped it.
  const float highest =
      highestRiseAtSetVelocity(level.world, body, Vec3(6, 0, 0), 180, 0.85f, scratch);
  // A riser is a wall: the body stops at the first, its rounded bottom
  // against the step's edge, and never rises onto it.
  INFO("rose " << highest << " m, ends at " << body.position.transpose());
  REQUIRE(highest < 0.01f);
  REQUIRE(body.position.x() < 0);
}

TEST_CASE("with a step height a body walks up 0.3 m stairs, without one it is stopped",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithStairs());
  bspf::StepScratch scratch;
  for (const float stepHeight : {0.0f, 0.35f}) {
    INFO("step height " << stepHeight);
    Body body = walker({-2, 0.851f, 0}, method);
    body.settings.maxStepHeight = stepHeight;
    run(level.world, body, Vec3(60, 0, 0), 120, scratch);  // about 11 m
    if (stepHeight > 0) {
      // On the top step (1.8 m), standing on it.
      REQUIRE(body.position.y() == Approx(1.8f + 0.85f).margin(3e-3));
      REQUIRE(body.position.x() > 2.4f);
      REQUIRE(body.grounded);
    } else {
      REQUIRE(body.position.y() < 0.85f + 0.3f);
      REQUIRE(body.position.x() < 0);
    }
  }
}

TEST_CASE("a step height never lets a body walk up a slope too steep to walk",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, slope(50));
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body body = walker({0, 0.851f, -3}, method);
  body.settings.maxStepHeight = 0.35f;
  float highest = body.position.y();
  for (int f = 0; f < 180; ++f) {
    bspf::stepBody(level.world, body, Vec3(0, 0, 60), kDt, scratch);
    highest = std::max(highest, body.position.y());
  }
  // One lift's worth at most, never up the slope.
  REQUIRE(highest < 0.85f + 0.35f);
}

TEST_CASE("a body pushed into a 90 degree corner settles", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithCorner());
  bspf::StepScratch scratch;
  Body body = walker({0, 0.9f, 0}, method);
  const Vec3 push(40, 0, 40);
  run(level.world, body, push, 180, scratch);
  bspf::StepReport report;
  Vec3 previous = body.position;
  for (int f = 0; f < 60; ++f) {
    bspf::stepBody(level.world, body, push, kDt, scratch, &report);
    REQUIRE((body.position - previous).norm() < 1e-4f);
    previous = body.position;
  }
  REQUIRE(body.position.x() == Approx(5 - 0.45f).margin(3e-3));
  REQUIRE(body.position.z() == Approx(5 - 0.45f).margin(3e-3));
}

TEST_CASE("a crowd squeezing bodies into a corner never lifts one onto a low wall",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // A corner of 1.2 m walls (faces x = 5 and z = 5).
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -20}, {6, 1.2, 6}));
  bspf::test::append(mesh, bspf::test::boxMesh({-20, 0, 5}, {5, 1.2, 6}));
  const Level level(mesh);
  bspf::StepScratch scratch;
  // 16 bodies packed tight, some dropped a little onto others (every centre
  // below the walls' top), all pushing into the corner.
  std::vector<Body> bodies;
  for (int i = 0; i < 16; ++i)
    bodies.push_back(walker(
        {4.5f - 0.6f * float(i % 4), 0.86f + 0.14f * float(i % 3), 4.5f - 0.6f * float(i / 4)},
        method));
  const std::vector<Vec3> forces(bodies.size(), Vec3(40, 0, 40));
  float highest = 0;
  for (int f = 0; f < 600; ++f) {
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch);
    for (const Body& b : bodies) highest = std::max(highest, b.position.y());
  }
  // No centre ever rose above the walls' top; all end on the floor, in the room.
  REQUIRE(highest < 1.2f);
  for (const Body& b : bodies) {
    REQUIRE(b.position.y() == Approx(0.85f).margin(3e-3));
    REQUIRE(b.position.x() <= 5 - 0.45f + 2e-3f);
    REQUIRE(b.position.z() <= 5 - 0.45f + 2e-3f);
  }
}

TEST_CASE("two bodies pushed together end apart and neither inside a wall", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorWithWall();
  const Level level(mesh);
  bspf::StepScratch scratch;
  std::vector<Body> bodies{walker({3, 0.9f, 0}, method), walker({4, 0.9f, 0.1f}, method)};
  const std::vector<Vec3> forces{Vec3(60, 0, 0), Vec3(60, 0, 0)};  // both into the wall
  for (int f = 0; f < 240; ++f) bspf::stepBodies(level.world, bodies, forces, kDt, scratch);
  for (const Body& b : bodies) REQUIRE(b.position.x() <= 5 - 0.45f + 1e-3f);
  const Vec3 apart = bodies[0].position - bodies[1].position;
  const Vec3 direction = apart.normalized();
  const float touching = bspf::effectiveRadius(direction, bodies[0].radii) +
                         bspf::effectiveRadius(direction, bodies[1].radii);
  REQUIRE(apart.norm() >= touching - 0.02f);
}

TEST_CASE("a ball with restitution 0.5 rebounds to a quarter of its drop height",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorSlab());
  bspf::StepScratch scratch;
  Body ball;
  ball.radii = {0.25f, 0.25f};
  ball.settings.restitution = 0.5f;
  ball.settings.method = method;
  const float dropHeight = 4.0f;  // of the ball's bottom above the floor
  ball.position = Vec3(0, 0.25f + dropHeight, 0);
  float peakAfterBounce = 0;
  bool bounced = false;
  for (int f = 0; f < 240; ++f) {
    const float vy = ball.velocity.y();
    bspf::stepBody(level.world, ball, Vec3::Zero(), kDt, scratch);
    if (vy < 0 && ball.velocity.y() > 0) bounced = true;
    if (bounced) peakAfterBounce = std::max(peakAfterBounce, ball.position.y() - 0.25f);
    if (bounced && ball.velocity.y() < 0) break;
  }
  REQUIRE(bounced);
  // Tolerance: 10% of the ideal quarter, for the frame-sized error at impact.
  REQUIRE(peakAfterBounce == Approx(dropHeight / 4).epsilon(0.10));
}

TEST_CASE("a body starting within a wall's offset surface is pushed out, not let through",
          "[runtime][movement]") {
  // The article's pre-check, (startSide - r) * (endSide - r) < 0, is false
  // when both sides are within r: such a body passed through the wall.
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -10}, {5.01, 4, 10}));
  const Level level(mesh);
  bspf::StepScratch scratch;
  for (const float inside : {0.001f, 0.02f, 0.2f, 0.44f}) {
    Body body = walker({5 - 0.45f + inside, 0.851f, 0});
    body.settings.maxHorizontalSpeed = 100;
    body.velocity = Vec3(100, 0, 0);
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch);
    INFO("started " << inside << " m within the offset surface");
    REQUIRE(body.position.x() <= 5 - 0.45f + 2e-3f);
  }
}

TEST_CASE("a fast oblique body cannot pass a small panel", "[runtime][movement]") {
  // The six planes must be tested where the centre crosses the offset plane:
  // tested at the end, this move's end lies beside the grown panel and the
  // body would pass through it.
  const Level level(bspf::test::boxMesh({5, -0.5, -0.5}, {5.01, 0.5, 0.5}));
  bspf::StepScratch scratch;
  Body body = walker({3, 0, -2});
  body.settings.gravity = 0;
  body.settings.maxHorizontalSpeed = 300;
  body.velocity = Vec3(200, 0, 200);
  bspf::StepReport report;
  bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
  REQUIRE(report.iterations >= 1);
  REQUIRE(body.position.x() <= 5 - 0.45f + 2e-3f);
}

TEST_CASE("friction stops a sliding body without reversing it", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // The article subtracts the friction coefficient from the acceleration
  // vector, a scalar from a vector; here friction decelerates the horizontal
  // speed and stops at zero.
  const Level level(floorSlab());
  bspf::StepScratch scratch;
  Body body = walker({0, 0.851f, 0}, method);
  run(level.world, body, Vec3::Zero(), 10, scratch);
  REQUIRE(body.grounded);
  const Vec3 initial(3, 0, -4);  // 5 m/s
  body.velocity = initial;
  int frames = 0;
  while (body.velocity.norm() > 0 && frames < 600) {
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch);
    REQUIRE(body.velocity.dot(initial) >= 0);
    ++frames;
  }
  // 5 m/s at 20 m/s^2 stops in 0.25 s: 15 frames.
  REQUIRE(frames == 15);
  const Vec3 stopped = body.position;
  run(level.world, body, Vec3::Zero(), 60, scratch);
  REQUIRE((body.position - stopped).norm() < 1e-6f);
}

namespace {

// Ground snapping (MovementSettings::maxStepDown): what a body walking down
// a slope or stairs does, frame by frame.
struct Descent {
  int frames = 0;
  int grounded = 0;         // frames ending grounded
  int longestAirborne = 0;  // most frames in a row not grounded
  float highestFloat = 0;   // metres above its resting height over the slope (slopes only)
  float slowest = 1e9f;     // horizontal speed of the position, m/s
  float fastest = 0;
};

// Steps `body` for `frames` frames pushed along `force`, recording its
// descent; `restingY(position)` is where it would rest at that place (NaN
// when not measured).
template <typename RestingY>
Descent descend(const bspf::World& world, Body& body, const Vec3& force, int frames,
                bspf::StepScratch& scratch, RestingY restingY) {
  Descent d;
  int airborne = 0;
  for (int f = 0; f < frames; ++f) {
    const Vec3 before = body.position;
    bspf::stepBody(world, body, force, kDt, scratch);
    ++d.frames;
    d.grounded += body.grounded;
    airborne = body.grounded ? 0 : airborne + 1;
    d.longestAirborne = std::max(d.longestAirborne, airborne);
    const float rest = restingY(body.position);
    if (!std::isnan(rest)) d.highestFloat = std::max(d.highestFloat, body.position.y() - rest);
    const Vec3 step = body.position - before;
    const float speed = std::hypot(step.x(), step.z()) / kDt;
    d.slowest = std::min(d.slowest, speed);
    d.fastest = std::max(d.fastest, speed);
  }
  return d;
}

const float kTan30 = std::tan(30 * std::numbers::pi_v<float> / 180);

// A body standing on the 30 degree slope(30) at z = 14, settled; returns
// its resting height above the slope's surface.
float settleOnSlope(const bspf::World& world, Body& body, bspf::StepScratch& scratch) {
  body.position = Vec3(0, 14 * kTan30 + 1.5f, 14);
  run(world, body, Vec3::Zero(), 60, scratch);
  return body.position.y() - body.position.z() * kTan30;
}

// Walks a body down the 30 degree slope at 6 m/s for one second.
Descent walkDownSlope(bspf::CollisionMethod method, float maxStepDown) {
  const Level level(slope(30));
  bspf::StepScratch scratch;
  Body body = walker(Vec3::Zero(), method);
  body.settings.maxStepDown = maxStepDown;
  const float offset = settleOnSlope(level.world, body, scratch);
  body.velocity = Vec3(0, 0, -6);
  return descend(level.world, body, Vec3(0, 0, -60), 60, scratch,
                 [&](const Vec3& p) { return p.z() * kTan30 + offset; });
}

// Stairs rising along +x from x = 0: `steps` risers of `riser` metres,
// 0.3 m treads, on the floor slab; the top tread runs on to x = 15.
bspc::Mesh stairs(int steps, double riser) {
  bspc::Mesh mesh = floorSlab();
  for (int k = 0; k < steps; ++k)
    bspf::test::append(mesh, bspf::test::boxMesh({0.3 * k, 0, -2}, {15, riser * (k + 1), 2}));
  return mesh;
}

// Walks a body from the top of 8 stairs of 0.2 m risers down to the floor at
// 4 m/s; the descent is measured until it reaches the floor (x < -0.5).
Descent walkDownStairs(bspf::CollisionMethod method, float maxStepDown, Body* end = nullptr) {
  const Level level(stairs(8, 0.2));
  bspf::StepScratch scratch;
  Body body = walker({5, 1.6f + 0.86f, 0}, method);
  body.settings.maxStepDown = maxStepDown;
  body.settings.maxHorizontalSpeed = 4;
  run(level.world, body, Vec3::Zero(), 30, scratch);
  body.velocity = Vec3(-4, 0, 0);
  Descent d;
  int airborne = 0;
  while (d.frames < 120 && body.position.x() > -0.5f) {
    bspf::stepBody(level.world, body, Vec3(-60, 0, 0), kDt, scratch);
    ++d.frames;
    d.grounded += body.grounded;
    airborne = body.grounded ? 0 : airborne + 1;
    d.longestAirborne = std::max(d.longestAirborne, airborne);
  }
  if (end) *end = body;
  return d;
}

}  // namespace

TEST_CASE("a body whose walkable slope is lowered below its ground's slope slides down it",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(slope(30));
  bspf::StepScratch scratch;
  Body body = walker(Vec3::Zero(), method);
  settleOnSlope(level.world, body, scratch);
  REQUIRE(body.grounded);
  const Vec3 rested = body.position;
  // The game makes the ground too steep to stand on (a slippery surface):
  // the hints of the ground it stood on must not hold it there.
  body.settings.walkableSlopeDegrees = 20;
  bspf::StepReport report;
  run(level.world, body, Vec3::Zero(), 30, scratch, &report);
  REQUIRE_FALSE(report.grounded);
  REQUIRE(body.position.z() < rested.z() - 0.05f);
  REQUIRE(body.position.y() < rested.y());
}

TEST_CASE(
    "ground snapping: a body walking down a 30 degree slope at 6 m/s is grounded every frame, "
    "keeps its horizontal speed and never floats",
    "[runtime][movement][snap]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Descent d = walkDownSlope(method, bspf::MovementSettings{}.maxStepDown);
  CHECK(d.grounded == d.frames);
  CHECK(d.slowest > 6 * 0.999f);
  CHECK(d.fastest < 6 * 1.001f);
  CHECK(d.highestFloat < 2e-3f);
}

TEST_CASE(
    "ground snapping: a body walking down 0.2 m stairs at 4 m/s is grounded every frame and "
    "ends on the floor",
    "[runtime][movement][snap]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  Body end;
  const Descent d = walkDownStairs(method, bspf::MovementSettings{}.maxStepDown, &end);
  INFO("grounded " << d.grounded << " of " << d.frames << " frames, end "
                   << end.position.transpose());
  CHECK(d.grounded == d.frames);
  CHECK(end.position.x() < -0.5f);
  CHECK(end.position.y() == Approx(0.85f).margin(3e-3));
}

TEST_CASE("ground snapping never holds down a jumping body, on a floor or walking down a slope",
          "[runtime][movement][snap]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspf::StepScratch scratch;
  auto jump = [&](const bspf::World& world, Body& body, const Vec3& force) {
    REQUIRE(body.grounded);
    const float start = body.position.y();
    body.velocity.y() = 5;  // about 1.3 m high
    float highest = start;
    for (int f = 0; f < 20; ++f) {
      bspf::stepBody(world, body, force, kDt, scratch);
      INFO("frame " << f);
      CHECK_FALSE(body.grounded);
      highest = std::max(highest, body.position.y());
    }
    CHECK(highest > start + 1.0f);
  };
  {
    const Level level(floorSlab());
    Body body = walker({0, 0.851f, 0}, method);
    run(level.world, body, Vec3::Zero(), 10, scratch);
    jump(level.world, body, Vec3::Zero());
  }
  {
    const Level level(slope(30));
    Body body = walker(Vec3::Zero(), method);
    settleOnSlope(level.world, body, scratch);
    body.velocity = Vec3(0, 0, -6);
    run(level.world, body, Vec3(0, 0, -60), 10, scratch);
    jump(level.world, body, Vec3(0, 0, -60));
  }
}

TEST_CASE(
    "ground snapping sets a body walking off a ledge down onto the floor when the ledge is "
    "within maxStepDown, and lets it fall from a higher one",
    "[runtime][movement][snap]") {
  const bspf::CollisionMethod method = eachMethod();
  const float stepDown = bspf::MovementSettings{}.maxStepDown;
  for (const float height : {stepDown - 0.05f, stepDown + 0.1f}) {
    INFO("method " << nameOf(method) << ", ledge " << height << " m");
    bspc::Mesh mesh = floorSlab();
    bspf::test::append(mesh, bspf::test::boxMesh({0, 0, -5}, {10, height, 5}));
    const Level level(mesh);
    bspf::StepScratch scratch;
    Body body = walker({3, height + 0.86f, 0}, method);
    run(level.world, body, Vec3::Zero(), 30, scratch);
    body.velocity = Vec3(-6, 0, 0);
    const Descent d = descend(level.world, body, Vec3(-60, 0, 0), 60, scratch,
                              [](const Vec3&) { return std::nanf(""); });
    // Either way it ends on the floor below, 3 m past the ledge.
    CHECK(body.position.x() < -2);
    CHECK(body.position.y() == Approx(0.85f).margin(3e-3));
    if (height <= stepDown) {
      CHECK(d.grounded == d.frames);
    } else {
      // 0.45 m falls in 0.3 s: about 18 frames.
      CHECK(d.longestAirborne >= 12);
    }
  }
}

TEST_CASE("ground snapping lets a body walking over a gap wider than itself fall into it",
          "[runtime][movement][snap]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // A 2.5 m wide, 3 m deep trench across the floor, from x = 0; the body is
  // 0.9 m wide.
  bspc::Mesh mesh = bspf::test::boxMesh({-20, -4, -20}, {0, 0, 20});
  bspf::test::append(mesh, bspf::test::boxMesh({2.5, -4, -20}, {20, 0, 20}));
  bspf::test::append(mesh, bspf::test::boxMesh({0, -4, -20}, {2.5, -3, 20}));
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body body = walker({-2, 0.851f, 0}, method);
  body.settings.maxHorizontalSpeed = 3;
  run(level.world, body, Vec3::Zero(), 10, scratch);
  REQUIRE(body.grounded);
  body.velocity = Vec3(3, 0, 0);
  run(level.world, body, Vec3(60, 0, 0), 120, scratch);
  // In the trench, standing on its bottom against its far wall.
  CHECK(body.position.y() == Approx(-3 + 0.85f).margin(3e-3));
  CHECK(body.position.x() == Approx(2.5f - 0.45f).margin(3e-3));
}

TEST_CASE("the same inputs give the same trajectory, and a step leaves the world unchanged",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // The article's perpendicular-plane loop writes the offset into the stored
  // plane distance, so testing a triangle changes it for the next test. The
  // World here is read-only; repeating a scene must repeat it bit for bit.
  bspc::Mesh mesh = floorWithWall();
  bspf::test::append(mesh, slope(25));
  const Level level(mesh);
  const std::vector<std::uint8_t> before(
      reinterpret_cast<const std::uint8_t*>(level.world.bytes().data()),
      reinterpret_cast<const std::uint8_t*>(level.world.bytes().data()) +
          level.world.bytes().size());
  auto simulate = [&] {
    bspf::StepScratch scratch;
    std::vector<Body> bodies;
    std::vector<Vec3> forces;
    for (int i = 0; i < 12; ++i) {
      bodies.push_back(walker({-3.0f + 0.7f * i, 1.0f + 0.1f * i, -2.0f + 0.3f * i}, method));
      forces.emplace_back(std::cos(float(i)) * 60, 0, std::sin(float(i)) * 60);
    }
    std::vector<Vec3> trace;
    for (int f = 0; f < 300; ++f) {
      bspf::stepBodies(level.world, bodies, forces, kDt, scratch);
      for (const Body& b : bodies) trace.push_back(b.position);
    }
    return trace;
  };
  const std::vector<Vec3> first = simulate();
  const std::vector<Vec3> second = simulate();
  REQUIRE(first.size() == second.size());
  for (std::size_t i = 0; i < first.size(); ++i)
    REQUIRE((first[i].array() == second[i].array()).all());
  REQUIRE(std::equal(before.begin(), before.end(),
                     reinterpret_cast<const std::uint8_t*>(level.world.bytes().data())));
}

namespace {

// A room corner: walls whose faces are the planes x = 5 and z = 5, appended
// in the order given (so the first one's triangles have the lower indices).
bspc::Mesh corner(bool xWallFirst) {
  bspc::Mesh mesh = floorSlab();
  const bspc::Mesh xWall = bspf::test::boxMesh({5, 0, -20}, {6, 4, 6});
  const bspc::Mesh zWall = bspf::test::boxMesh({-20, 0, 5}, {6, 4, 6});
  bspf::test::append(mesh, xWallFirst ? xWall : zWall);
  bspf::test::append(mesh, xWallFirst ? zWall : xWall);
  return mesh;
}

// A body without gravity, floating where it is put, free to move fast.
Body floating(const Vec3& at, bspf::CollisionMethod method) {
  Body body = walker(at, method);
  body.settings.gravity = 0;
  body.settings.maxHorizontalSpeed = 100;
  return body;
}

// A triangle 12 m in radius around `centre`, with unit normal `normal` (by
// its winding): a wall much larger than the body.
void appendPlane(bspc::Mesh& mesh, const Eigen::Vector3d& centre, const Eigen::Vector3d& normal) {
  const Eigen::Vector3d u = normal.unitOrthogonal(), v = normal.cross(u);
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  for (int k = 0; k < 3; ++k) {
    const double angle = 2 * std::numbers::pi * k / 3;
    mesh.vertices.push_back(centre + 12 * (std::cos(angle) * u + std::sin(angle) * v));
  }
  mesh.triangles.push_back({base, base + 1, base + 2});
}

// The centre of an ellipsoid resting against every plane (unit normal n_i
// through the origin) at once: n_i . c = effectiveRadius(n_i) + skin.
Vec3 restingCentre(const std::vector<Eigen::Vector3d>& normals, bspf::EllipsoidRadii radii,
                   float skin) {
  Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < normals.size(); ++i) {
    m.row(int(i)) = normals[i].transpose();
    rhs(int(i)) = bspf::effectiveRadius(Vec3(normals[i].cast<float>()), radii) + skin;
  }
  if (normals.size() == 2) m.row(2) = Eigen::Vector3d::UnitY().transpose();  // stay at y = 0
  return m.colPivHouseholderQr().solve(rhs).cast<float>();
}

}  // namespace

TEST_CASE("a move still blocked after exactly maxIterations slides is refused",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // Diagonally into a corner: one slide per wall, so one slide is too few
  // and two are enough.
  const Level level(corner(true));
  bspf::StepScratch scratch;
  const Vec3 start(4, 2, 4);
  const Vec3 velocity(60, 0, 60);  // 1 m a frame along each axis
  for (const int slides : {1, 2}) {
    INFO("maxIterations " << slides);
    Body body = floating(start, method);
    body.settings.maxIterations = slides;
    body.velocity = velocity;
    bspf::StepReport report;
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
    // Planes: a move its planes leave blocked is made by the exact sweep
    // (its own slides counted too), which refuses it here as well.
    const bool handedOn = method == bspf::CollisionMethod::Planes && slides == 1;
    REQUIRE(report.iterations == (handedOn ? 2 * slides : slides));
    REQUIRE(report.refused == (slides == 1));
    if (slides == 2) {
      // Slid into the corner, against both walls.
      REQUIRE(body.position.x() == Approx(5 - 0.45f).margin(2e-3));
      REQUIRE(body.position.z() == Approx(5 - 0.45f).margin(2e-3));
    } else {
      // Refused: the body stops at its last contact, touching a wall, clear of both.
      REQUIRE(std::max(body.position.x(), body.position.z()) == Approx(5 - 0.45f).margin(2e-3));
      REQUIRE(body.position.x() <= 5 - 0.45f + 1e-4f);
      REQUIRE(body.position.z() <= 5 - 0.45f + 1e-4f);
      REQUIRE((body.position - start).norm() > 0.5f);
    }
  }
}

TEST_CASE(
    "a body starting inside a wall's offset surface is pushed out to it, and the report "
    "gives the wall's outward normal",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -10}, {5.5, 4, 10}));
  const Level level(mesh);
  bspf::StepScratch scratch;
  for (const float inside : {0.001f, 0.05f, 0.2f, 0.4f}) {
    INFO("started " << inside << " m within the offset surface");
    // Moving along the wall, not into it.
    Body body = floating({5 - 0.45f + inside, 2, 0}, method);
    body.velocity = Vec3(0, 0, 3);
    bspf::StepReport report;
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
    REQUIRE_FALSE(report.refused);
    // Out, and clear of the wall by part of the skin at least (the exact
    // sweep keeps it in sphere units: less than the skin along a short radius).
    REQUIRE(body.position.x() <= 5 - 0.45f - 0.4f * body.settings.skin);
    REQUIRE(body.position.x() >= 5 - 0.45f - 3e-3f);
    REQUIRE(report.contactCount >= 1);
    const Vec3 normal = report.contactNormals[0];
    REQUIRE(normal.norm() == Approx(1).margin(1e-5));
    REQUIRE(normal.x() == Approx(-1).margin(1e-4));
  }
}

TEST_CASE(
    "a step-up never lifts a body more than maxStepHeight, even under a low ceiling or "
    "onto a walkable slope above the step",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const float stepHeight = 0.35f;
  SECTION("a 0.3 m step under a ceiling 0.15 m above the head: lifts 0.15 at most, stays") {
    bspc::Mesh mesh = floorSlab();
    bspf::test::append(mesh, bspf::test::boxMesh({0, 0, -2}, {4, 0.3, 2}));
    bspf::test::append(mesh, bspf::test::boxMesh({-4, 1.85, -2}, {4, 2.5, 2}));
    const Level level(mesh);
    bspf::StepScratch scratch;
    Body body = walker({-1, 0.851f, 0}, method);
    body.settings.maxStepHeight = stepHeight;
    run(level.world, body, Vec3::Zero(), 10, scratch);
    REQUIRE(body.grounded);
    float highest = body.position.y();
    for (int f = 0; f < 120; ++f) {
      bspf::stepBody(level.world, body, Vec3(60, 0, 0), kDt, scratch);
      highest = std::max(highest, body.position.y());
    }
    // Never through the ceiling, never onto the step (a rounded body may
    // lean on the step's edge, a little above the floor).
    REQUIRE(highest <= 1.85f - 0.85f);
    REQUIRE(body.position.x() < 0);
    REQUIRE(body.position.y() < 0.3f + 0.85f);
  }
  SECTION("a 0.3 m step topped by a 44 degree ramp: no frame rises more than the step height") {
    bspc::Mesh mesh = floorSlab();
    bspf::test::append(mesh, bspf::test::boxMesh({0, 0, -2}, {4, 0.3, 2}));
    // A ramp rising along +x from the step's edge.
    bspc::Mesh ramp = bspf::test::boxMesh({0, -1, -2}, {6, 0, 2});
    const Eigen::Matrix3d tilt =
        Eigen::AngleAxisd(44 * std::numbers::pi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    for (Eigen::Vector3d& v : ramp.vertices) v = tilt * v + Eigen::Vector3d(0, 0.3, 0);
    bspf::test::append(mesh, ramp);
    const Level level(mesh);
    bspf::StepScratch scratch;
    Body body = walker({-1, 0.851f, 0}, method);
    body.settings.maxStepHeight = stepHeight;
    body.settings.maxHorizontalSpeed = 30;  // half a metre a frame
    run(level.world, body, Vec3::Zero(), 10, scratch);
    REQUIRE(body.grounded);
    // Walking up the ramp at 30 m/s rises more than that a frame; a frame
    // that starts on the floor, at the step, is a step-up.
    int stepFrames = 0;
    for (int f = 0; f < 30; ++f) {
      const float before = body.position.y();
      bspf::stepBody(level.world, body, Vec3(3000, 0, 0), kDt, scratch);
      INFO("frame " << f << " at " << body.position.transpose());
      if (before > 0.85f + 0.01f) continue;
      ++stepFrames;
      REQUIRE(body.position.y() - before <= stepHeight + body.settings.skin);
    }
    REQUIRE(stepFrames > 0);
  }
}

TEST_CASE(
    "a body pushed into a sharp V-shaped crease or a pyramid's tip reaches the point touching "
    "every wall, never refused, and the planes method meets the walls itself",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // Walls meeting at the origin, the body pushed along +x into where they
  // meet. Their normals are more than 90 degrees apart, so moving the body
  // out of one wall moves it into the others: a sharp wedge, and a pyramid's
  // tip seen from inside (none of its walls walkable).
  const double b = std::sqrt(1 - 0.4 * 0.4);
  auto pyramidWall = [&](double degrees) {
    const double angle = degrees * std::numbers::pi / 180;
    return Eigen::Vector3d(-0.4, b * std::cos(angle), b * std::sin(angle));
  };
  for (const bool pyramid : {false, true}) {
    const std::vector<Eigen::Vector3d> normals =
        pyramid ? std::vector{pyramidWall(60), pyramidWall(180), pyramidWall(300)}
                : std::vector{Eigen::Vector3d(-0.6, 0, 0.8), Eigen::Vector3d(-0.6, 0, -0.8)};
    INFO((pyramid ? "corner of three" : "V crease"));
    bspc::Mesh mesh;
    for (const Eigen::Vector3d& n : normals) appendPlane(mesh, Eigen::Vector3d::Zero(), n);
    const Level level(mesh);
    bspf::StepScratch scratch;
    Body body = floating({-4, pyramid ? 0.2f : 0.0f, 0.3f}, method);
    const Vec3 goal = restingCentre(normals, body.radii, body.settings.skin);
    bspf::StepReport report;
    for (int f = 0; f < 120; ++f) {
      const Vec3 towards = (goal - body.position) * 600;
      bspf::stepBody(level.world, body, Vec3(towards.x(), 0, towards.z()), kDt, scratch, &report);
      if (pyramid) body.velocity.y() = (goal.y() - body.position.y()) * 30;
      INFO("frame " << f << " at " << body.position.transpose());
      REQUIRE_FALSE(report.refused);
      // Where the walls meet (meetConstraints), not bounced between until
      // the iterations run out and the exact sweep makes the move instead
      // (which would add its own iterations to these).
      if (method == bspf::CollisionMethod::Planes)
        REQUIRE(report.iterations <= body.settings.maxIterations);
    }
    INFO("goal " << goal.transpose() << ", at " << body.position.transpose());
    REQUIRE((body.position - goal).norm() < 3e-3f);
  }
}

TEST_CASE(
    "a body moving along a sharp vertical crease while pushed into it keeps its speed along the "
    "crease, in no more slides than the crease's two walls",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  // Two walls 23 degrees apart along +x, meeting on the y axis. Slid along
  // one wall, the move goes into the other; slid along that one alone, back
  // into the first, its push into the crease shrinking by only 8% a slide.
  // Only a move that follows the crease line (the exact sweep's cross
  // product of the normals, the planes method's meetConstraints) keeps its
  // vertical part in two slides.
  const std::vector<Eigen::Vector3d> normals{Eigen::Vector3d(-0.2, 0, 0.98).normalized(),
                                             Eigen::Vector3d(-0.2, 0, -0.98).normalized()};
  bspc::Mesh mesh;
  for (const Eigen::Vector3d& n : normals) appendPlane(mesh, Eigen::Vector3d::Zero(), n);
  const Level level(mesh);
  bspf::StepScratch scratch;
  Body body = floating(Vec3::Zero(), method);
  body.position = restingCentre(normals, body.radii, body.settings.skin);
  const Vec3 velocity(3, 2, 0);
  bspf::StepReport report;
  for (int f = 0; f < 30; ++f) {
    body.velocity = velocity;
    const Vec3 before = body.position;
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
    INFO("frame " << f << " from " << before.transpose() << " to " << body.position.transpose()
                  << ", " << report.iterations << " slides");
    REQUIRE_FALSE(report.refused);
    REQUIRE(report.iterations <= 2);
    // Air friction slows the body a little within the step.
    REQUIRE(body.position.y() - before.y() > 0.9f * velocity.y() * kDt);
    for (const Eigen::Vector3d& n : normals) {
      const Vec3 normal = n.cast<float>();
      REQUIRE(normal.dot(body.position) >= bspf::effectiveRadius(normal, body.radii));
    }
  }
}

TEST_CASE(
    "of two blocking walls the planes method slides first against the one faced more "
    "directly, and in a tie against the lower-numbered triangle",
    "[runtime][movement]") {
  bspf::StepScratch scratch;
  for (const bool xWallFirst : {true, false}) {
    INFO((xWallFirst ? "x wall first" : "z wall first"));
    const Level level(corner(xWallFirst));
    struct Case {
      Vec3 velocity;
      Vec3 firstNormal;
    };
    const Vec3 xWall(-1, 0, 0), zWall(0, 0, -1);
    for (const Case& c : {Case{{90, 0, 60}, xWall}, Case{{60, 0, 90}, zWall},
                          Case{{60, 0, 60}, xWallFirst ? xWall : zWall}}) {
      INFO("velocity " << c.velocity.transpose());
      Body body = floating({4, 2, 4}, bspf::CollisionMethod::Planes);
      body.velocity = c.velocity;
      bspf::StepReport report;
      bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch, &report);
      REQUIRE(report.contactCount == 2);
      REQUIRE((report.contactNormals[0] - c.firstNormal).norm() < 1e-6f);
    }
  }
}

namespace {

// A planes-method body falling 0.1 m through the offset plane of a floor
// triangle's sharp corner, its centre `beyond` metres past the corner's cap
// plane's offset along `tip` (unit, out of the corner): met (one slide, on
// the offset plane) when it is within, missed when it is beyond.
void requireCutByCapPlane(const bspf::World& world, const Vec3& tip,
                          std::initializer_list<float> beyonds) {
  bspf::StepScratch scratch;
  for (const float beyond : beyonds) {
    INFO("centre " << beyond << " m beyond the cap plane's offset");
    Body body = floating((0.45f + beyond) * tip + Vec3(0, 0.9f, 0), bspf::CollisionMethod::Planes);
    body.velocity = Vec3(0, -6, 0);  // 0.1 m this frame, through the offset plane at 0.85
    bspf::StepReport report;
    bspf::stepBody(world, body, Vec3::Zero(), kDt, scratch, &report);
    if (beyond < 0) {
      REQUIRE(report.iterations == 1);
      REQUIRE(body.position.y() == Approx(0.851f).margin(1e-4));
    } else {
      REQUIRE(report.iterations == 0);
      REQUIRE(body.position.y() == Approx(0.8f).margin(1e-4));
    }
  }
}

// An exact-sweep body falling 1 m past a floor triangle's sharp corner, its
// centre `beyond` metres beyond the corner's reach along `tip` (unit, out of
// the corner): it touches nothing, not even the corner's edges' lines
// beyond the corner.
void requireFallsPastCorner(const bspf::World& world, const Vec3& tip,
                            std::initializer_list<float> beyonds) {
  bspf::StepScratch scratch;
  for (const float beyond : beyonds) {
    INFO("centre " << beyond << " m beyond the corner's reach");
    Body body =
        floating((0.45f + beyond) * tip + Vec3(0, 0.9f, 0), bspf::CollisionMethod::ExactSweep);
    body.velocity = Vec3(0, -60, 0);  // 1 m this frame, down past the corner
    bspf::StepReport report;
    bspf::stepBody(world, body, Vec3::Zero(), kDt, scratch, &report);
    REQUIRE(report.iterations == 0);
    REQUIRE(body.position.y() == Approx(-0.1f).margin(1e-4));
  }
}

}  // namespace

TEST_CASE(
    "the planes method's grown triangle is cut at a sharp corner by the cap plane, "
    "the body's horizontal radius beyond the corner",
    "[runtime][movement]") {
  // One floor triangle with a 11 degree corner at the origin pointing -x:
  // the edge planes alone, grown by the radius, would reach about 4.6 m
  // beyond the corner; the corner's cap plane stops them at x = -radius.
  bspc::Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {10, 0, 1}, {10, 0, -1}};
  mesh.triangles = {{0, 1, 2}};
  const Level level(mesh);
  requireCutByCapPlane(level.world, Vec3(-1, 0, 0), {-0.01f, 0.01f, 0.3f});
  SECTION("the exact sweep lets a body beyond the corner's reach fall past it") {
    requireFallsPastCorner(level.world, Vec3(-1, 0, 0), {0.01f, 0.3f});
  }
}

TEST_CASE(
    "an airborne body slows horizontally by airFriction * dt a frame, never reversing, and "
    "input never pushes it past the speed cap",
    "[runtime][movement]") {
  const Level level(floorSlab());
  bspf::StepScratch scratch;
  Body body = floating({0, 10, 0}, bspf::CollisionMethod::Planes);
  body.settings.airFriction = 3;
  body.velocity = Vec3(3, 0, -4);  // 5 m/s
  const Vec3 direction = body.velocity.normalized();
  for (int f = 1; f <= 120; ++f) {
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch);
    const float expected = std::max(0.0f, 5.0f - 3.0f * kDt * float(f));
    REQUIRE(body.velocity.norm() == Approx(expected).margin(1e-4));
    REQUIRE(body.velocity.dot(direction) >= 0);
  }
  REQUIRE(body.velocity.norm() == 0);
  body.settings.maxHorizontalSpeed = 6;
  for (int f = 0; f < 30; ++f) {
    bspf::stepBody(level.world, body, Vec3(0, 0, 1000), kDt, scratch);
    REQUIRE(Eigen::Vector2f(body.velocity.x(), body.velocity.z()).norm() <= 6 + 1e-4f);
  }
  REQUIRE(body.velocity.z() == Approx(6).margin(1e-4));
}

TEST_CASE(
    "a small and a big body overlapping across grid cells are each pushed half the overlap "
    "apart, horizontally, and lose their closing speed",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorSlab());
  bspf::StepScratch scratch;
  // The grid's cells are as wide as the widest body (4 m): these centres are
  // 2.15 m apart, in neighbouring cells, overlapping by 0.35 m.
  Body big = floating({1.9f, 3, 0}, method);
  big.radii = {2.0f, 2.0f};
  Body small = floating({4.05f, 3, 0}, method);
  small.radii = {0.5f, 0.5f};
  small.velocity = Vec3(-0.6f, 0, 0);  // closing, 1 cm this frame
  std::vector<Body> bodies{big, small};
  const std::vector<Vec3> forces(2, Vec3::Zero());
  std::vector<bspf::StepReport> reports(2);
  bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  const float overlap = 2.5f - (2.15f - 0.01f);
  const float half = 0.5f * overlap + 0.5f * big.settings.skin;
  REQUIRE(bodies[0].position.x() == Approx(1.9f - half).margin(1e-4));
  REQUIRE(bodies[1].position.x() == Approx(4.05f - 0.01f + half).margin(1e-4));
  for (int i = 0; i < 2; ++i) {
    REQUIRE(reports[i].bodyContacts == 1);
    REQUIRE(bodies[i].position.y() == 3);
    REQUIRE(bodies[i].position.z() == 0);
  }
  REQUIRE(bodies[1].velocity.x() == Approx(0).margin(1e-6));

  SECTION("centres at different heights: still pushed horizontally") {
    std::vector<Body> tilted{big, small};
    tilted[1].position.y() = 3.6f;
    tilted[1].velocity.setZero();
    bspf::stepBodies(level.world, tilted, forces, kDt, scratch, reports);
    REQUIRE(tilted[0].position.x() < 1.9f);
    REQUIRE(tilted[1].position.x() > 4.05f);
    REQUIRE(tilted[0].position.y() == 3);
    REQUIRE(tilted[1].position.y() == 3.6f);
  }
}

TEST_CASE(
    "threads stepping separate bodies on one shared World, each with its own scratch, get "
    "the sequential results",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorWithWall();
  bspf::test::append(mesh, slope(25));
  const Level level(mesh);
  constexpr int kThreads = 4, kPerThread = 6, kFrames = 120;
  auto makeGroup = [&](int group) {
    std::vector<Body> bodies;
    for (int i = 0; i < kPerThread; ++i)
      bodies.push_back(
          walker({-4.0f + 1.1f * i, 1.0f + 0.2f * group, -6.0f + 3.0f * group}, method));
    return bodies;
  };
  auto simulate = [&](std::vector<Body>& bodies, int group) {
    bspf::StepScratch scratch;
    std::vector<Vec3> forces;
    for (int i = 0; i < kPerThread; ++i)
      forces.emplace_back(std::cos(float(i + group)) * 60, 0, std::sin(float(i + group)) * 60);
    for (int f = 0; f < kFrames; ++f) bspf::stepBodies(level.world, bodies, forces, kDt, scratch);
  };
  std::vector<std::vector<Body>> sequential, threaded;
  for (int g = 0; g < kThreads; ++g) {
    sequential.push_back(makeGroup(g));
    threaded.push_back(makeGroup(g));
    simulate(sequential.back(), g);
  }
  std::vector<std::thread> threads;
  for (int g = 0; g < kThreads; ++g) threads.emplace_back([&, g] { simulate(threaded[g], g); });
  for (std::thread& t : threads) t.join();
  for (int g = 0; g < kThreads; ++g)
    for (int i = 0; i < kPerThread; ++i) {
      REQUIRE((threaded[g][i].position.array() == sequential[g][i].position.array()).all());
      REQUIRE((threaded[g][i].velocity.array() == sequential[g][i].velocity.array()).all());
    }
}

TEST_CASE(
    "the planes method's grown triangle is cut by the cap plane at a sharp corner pointing "
    "diagonally, where the triangle's box does not reject the body",
    "[runtime][movement]") {
  // The 11 degree corner of the cap-plane test above, turned 45 degrees
  // about y to point along -x -z: a body just beyond the cap plane's offset
  // there still overlaps the triangle's box, so only the cap plane stops the
  // grown edges from reaching it.
  bspc::Mesh mesh;
  // Listed from each corner in turn: each of the three cap planes cuts it.
  mesh.vertices = {{0, 0, 0}, {6.364, 0, 7.778}, {7.778, 0, 6.364}};
  for (const std::uint32_t first : {0u, 1u, 2u}) {
    INFO("the corner is listed " << (3 - first) % 3 << " in the triangle");
    mesh.triangles = {{first, (first + 1) % 3, (first + 2) % 3}};
    const Level level(mesh);
    const Vec3 tip(-std::sqrt(0.5f), 0, -std::sqrt(0.5f));
    requireCutByCapPlane(level.world, tip, {-0.01f, 0.01f, 0.1f});
    // Nor does the exact sweep meet the corner's edges beyond their ends.
    requireFallsPastCorner(level.world, tip, {0.01f, 0.1f});
  }
}

TEST_CASE(
    "a body starting within a wall's offset surface and moving along it off the wall's end is "
    "pushed out of it, not carried off inside it",
    "[runtime][movement]") {
  // The wall's face x = 5 ends at z = 10; the move ends beyond the grown
  // face, so only the test at the start sees the body within it.
  bspc::Mesh mesh = floorSlab();
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -10}, {5.01, 4, 10}));
  const Level level(mesh);
  const bspf::CollisionMethod method = eachMethod();
  INFO(nameOf(method));
  bspf::StepScratch scratch;
  for (const float inside : {0.02f, 0.2f}) {
    INFO("started " << inside << " m within the offset surface");
    Body body = floating({5 - 0.45f + inside, 2, 9.9f}, method);
    body.velocity = Vec3(0, 0, 60);  // 1 m this frame, to z = 10.9
    bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch);
    REQUIRE(body.position.x() <= 5 - 0.45f + 2e-3f);
    REQUIRE(body.position.z() > 10);
  }
}

TEST_CASE("a body running up a walkable slope under a low ceiling never ends inside the ceiling",
          "[runtime][movement]") {
  // A 40 degree slope lifts a 1 m uphill move by about 0.84 m: the planes
  // method's slide moves the end straight up onto the slope, far above the
  // box the move itself sweeps, and into a ceiling 1.3 m above the start.
  bspc::Mesh mesh = slope(40);
  const float startY = 2.62f;  // just above the slope at z = 2
  const float ceiling = startY + 1.3f;
  bspf::test::append(mesh, bspf::test::boxMesh({-4, ceiling, -20}, {4, ceiling + 1, 20}));
  const Level level(mesh);
  const bspf::CollisionMethod method = eachMethod();
  INFO(nameOf(method));
  bspf::StepScratch scratch;
  Body body = floating({0, startY, 2}, method);
  body.velocity = Vec3(0, 0, 60);  // 1 m uphill this frame
  bspf::stepBody(level.world, body, Vec3::Zero(), kDt, scratch);
  REQUIRE(body.position.y() + 0.85f <= ceiling + 2e-3f);
}

// Contacts: what a StepReport says about each (its point, its triangle and
// the triangle's surface, a sentinel for another body), and the flag a body
// that fell out of the level raises.

namespace {

// A 40 m slab whose top is "grass" and whose other faces are "dirt", and a
// wall (a box from x = 5 to 6) of "stone". boxMesh's triangles 6 and 7 are
// its top.
bspc::Mesh grassFloorWithWall() {
  bspc::Mesh mesh = bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20});
  mesh.surfaces = {"dirt", "grass", "stone"};
  mesh.triangleSurfaces.assign(12, 0);
  mesh.triangleSurfaces[6] = mesh.triangleSurfaces[7] = 1;
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -20}, {6, 4, 20}));
  mesh.triangleSurfaces.resize(mesh.triangles.size(), 2);
  return mesh;
}

// Whether `p` lies in triangle `t`'s plane (within `tolerance` metres) and
// within its box grown by the same.
bool onTriangle(const bspf::World& world, std::uint32_t t, const Vec3& p, float tolerance) {
  const bspf::schema::Plane& face = world.trianglePlanes()[t].face();
  if (std::abs(bspf::signedDistance(face, p)) > tolerance) return false;
  const bspf::schema::Triangle& tri = world.triangles()[t];
  Vec3 low = Vec3::Constant(1e30f), high = -low;
  for (const std::uint32_t v : {tri.v0(), tri.v1(), tri.v2()}) {
    low = low.cwiseMin(bspf::toVec3(world.vertices()[v]));
    high = high.cwiseMax(bspf::toVec3(world.vertices()[v]));
  }
  return (p.array() >= low.array() - tolerance).all() &&
         (p.array() <= high.array() + tolerance).all();
}

}  // namespace

TEST_CASE(
    "a body walking on a grass floor reports contacts of surface grass at points on the floor, "
    "its ground remembered or not",
    "[runtime][movement][contacts]") {
  const Level level(grassFloorWithWall());
  const bspf::World& world = level.world;
  const auto grass = world.findSurface("grass");
  REQUIRE(grass.has_value());
  const bspf::CollisionMethod method = eachMethod();
  // Forgotten, the floor is met by the narrow phase's scan, not the hint.
  const bool remembered = GENERATE(true, false);
  INFO(nameOf(method) << (remembered ? ", remembered" : ", forgotten"));
  Body body = walker(Vec3(0, 0.9f, 0), method);
  bspf::StepScratch scratch;
  bspf::StepReport report;
  int walkedOnGrass = 0;
  for (int frame = 0; frame < 60; ++frame) {
    if (!remembered) {
      body.groundTriangles = bspf::kNoGroundTriangles;
      body.wallTriangles = bspf::kNoWallTriangles;
    }
    bspf::stepBody(world, body, Vec3(0, 0, 40), kDt, scratch, &report);
    if (frame < 10) continue;  // landing
    REQUIRE(report.grounded);
    REQUIRE(report.contactCount >= 1);
    for (int c = 0; c < report.contactCount; ++c) {
      INFO("frame " << frame << ", contact " << c);
      const std::uint32_t t = report.contactTriangles[c];
      REQUIRE(t < world.triangles().size());
      CHECK(report.contactSurfaces[c] == world.triangleSurface(t));
      CHECK(report.contactSurfaces[c] == *grass);
      CHECK(world.surfaceName(report.contactSurfaces[c]) == "grass");
      const Vec3& point = report.contactPoints[c];
      // On the floor's top, under the body's centre.
      CHECK(std::abs(point.y()) <= 2e-3f);
      CHECK(onTriangle(world, t, point, 2e-3f));
      CHECK(std::hypot(point.x() - body.position.x(), point.z() - body.position.z()) < 0.5f);
      ++walkedOnGrass;
    }
  }
  CHECK(walkedOnGrass >= 50);
}

TEST_CASE("a body walking into a stone wall reports a stone contact at a point on the wall",
          "[runtime][movement][contacts]") {
  const Level level(grassFloorWithWall());
  const bspf::World& world = level.world;
  const std::uint32_t stone = *world.findSurface("stone");
  const bspf::CollisionMethod method = eachMethod();
  INFO(nameOf(method));
  Body body = walker(Vec3(3, 0.9f, 0), method);
  bspf::StepScratch scratch;
  bspf::StepReport report;
  bool metWall = false;
  for (int frame = 0; frame < 90 && !metWall; ++frame) {
    bspf::stepBody(world, body, Vec3(40, 0, 0), kDt, scratch, &report);
    for (int c = 0; c < report.contactCount; ++c) {
      if (report.contactSurfaces[c] != stone) continue;
      metWall = true;
      const Vec3& point = report.contactPoints[c];
      CHECK(report.contactNormals[c].x() < -0.99f);
      CHECK(std::abs(point.x() - 5) <= 2e-3f);
      CHECK(onTriangle(world, report.contactTriangles[c], point, 2e-3f));
      CHECK(std::abs(point.y() - body.position.y()) < 0.05f);
      CHECK(std::abs(point.z() - body.position.z()) < 0.05f);
    }
  }
  CHECK(metWall);
}

TEST_CASE("the exact sweep's contact with a finely tessellated wall names the triangle it touched",
          "[runtime][movement][contacts]") {
  // The floor, and a wall facing -x at x = 5 of 0.2 m squares (two
  // triangles each), so that many of its triangles are candidates of every
  // sweep into it, and only one is met.
  bspc::Mesh mesh = floorSlab();
  constexpr double kCell = 0.2;
  for (int row = 0; row < 15; ++row)
    for (int column = 0; column < 30; ++column) {
      const double y = row * kCell, z = -3 + column * kCell;
      const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
      for (const auto& [dy, dz] : {std::pair{0.0, 0.0}, {0.0, kCell}, {kCell, kCell}, {kCell, 0.0}})
        mesh.vertices.emplace_back(5, y + dy, z + dz);
      mesh.triangles.push_back({base, base + 1, base + 2});
      mesh.triangles.push_back({base, base + 2, base + 3});
    }
  const Level level(mesh);
  const bspf::World& world = level.world;
  Body body = walker(Vec3(3, 0.9f, 0.05f), bspf::CollisionMethod::ExactSweep);
  bspf::StepScratch scratch;
  bspf::StepReport report;
  int wallContacts = 0;
  for (int frame = 0; frame < 90; ++frame) {
    bspf::stepBody(world, body, Vec3(40, 0, 12), kDt, scratch, &report);
    for (int c = 0; c < report.contactCount; ++c) {
      if (!(report.contactNormals[c].x() < -0.99f)) continue;
      INFO("frame " << frame << ", contact " << c << " at " << report.contactPoints[c].transpose()
                    << ", triangle " << report.contactTriangles[c]);
      ++wallContacts;
      CHECK(onTriangle(world, report.contactTriangles[c], report.contactPoints[c], 2e-3f));
    }
  }
  CHECK(wallContacts > 10);
}

TEST_CASE("a contact with another body says so with the kBodyContact sentinel",
          "[runtime][movement][contacts]") {
  const Level level(grassFloorWithWall());
  const bspf::World& world = level.world;
  std::vector<Body> bodies = {walker(Vec3(0, 0.9f, 0)), walker(Vec3(0.5f, 0.9f, 0))};
  const std::vector<Vec3> forces(2, Vec3::Zero());
  std::vector<bspf::StepReport> reports(2);
  bspf::StepScratch scratch;
  bspf::stepBodies(world, bodies, forces, kDt, scratch, reports);
  for (int b = 0; b < 2; ++b) {
    INFO("body " << b);
    const bspf::StepReport& r = reports[b];
    REQUIRE(r.bodyContacts == 1);
    int bodyContacts = 0;
    for (int c = 0; c < r.contactCount; ++c) {
      if (r.contactTriangles[c] != bspf::kBodyContact) {
        CHECK(r.contactSurfaces[c] != bspf::kBodyContact);
        continue;
      }
      ++bodyContacts;
      CHECK(r.contactSurfaces[c] == bspf::kBodyContact);
      // Horizontal, from the other body towards this one; the point is on
      // this body's side facing the other, where it stood before the push
      // (x = 0 and 0.5: the level phase moved them only down).
      const float towardsThis = b == 0 ? -1.0f : 1.0f;
      CHECK(r.contactNormals[c].x() == Approx(towardsThis));
      CHECK(r.contactNormals[c].y() == 0);
      CHECK(r.contactPoints[c].x() == Approx(0.5f * b - towardsThis * 0.45f).margin(1e-5));
      CHECK(r.contactPoints[c].z() == Approx(0).margin(1e-5));
    }
    CHECK(bodyContacts == 1);
  }
}

TEST_CASE("a body falling below the level's bounds is reported, and not before",
          "[runtime][movement][contacts]") {
  const Level level(grassFloorWithWall());
  const bspf::World& world = level.world;
  const float lowest = world.boundsMin().y();
  REQUIRE(lowest == -1.0f);
  const bspf::CollisionMethod method = eachMethod();
  // Beside the slab: nothing below it.
  Body body = walker(Vec3(30, 2, 0), method);
  bspf::StepScratch scratch;
  bspf::StepReport report;
  int frame = 0;
  for (; frame < 600; ++frame) {
    bspf::stepBody(world, body, Vec3::Zero(), kDt, scratch, &report);
    const bool below = body.position.y() + body.radii.y < lowest;
    REQUIRE(report.belowLevel == below);
    if (below) break;
  }
  CHECK(frame < 600);
  SECTION("a body standing on the level is never reported") {
    Body standing = walker(Vec3(0, 0.9f, 0), method);
    for (int f = 0; f < 60; ++f) {
      bspf::stepBody(world, standing, Vec3::Zero(), kDt, scratch, &report);
      CHECK_FALSE(report.belowLevel);
    }
  }
}

TEST_CASE("findSurface finds a surface by its exact name and nothing else",
          "[runtime][movement][contacts]") {
  const Level level(grassFloorWithWall());
  const bspf::World& world = level.world;
  REQUIRE(world.surfaceCount() == 3);
  for (std::uint32_t s = 0; s < world.surfaceCount(); ++s)
    CHECK(world.findSurface(world.surfaceName(s)) == s);
  CHECK_FALSE(world.findSurface("Grass").has_value());
  CHECK_FALSE(world.findSurface("").has_value());
  CHECK(world.triangleSurfaces().size() == world.triangles().size());
}

TEST_CASE(
    "a body's step records the ground triangles it met, and a walking step with them as hints "
    "ends where one without them does (the exact sweep within rounding)",
    "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithWall());
  bspf::StepScratch scratch;
  Body body = walker({0, 0.9f, 0}, method);
  CHECK(body.groundTriangles == bspf::kNoGroundTriangles);
  run(level.world, body, Vec3::Zero(), 30, scratch);
  REQUIRE(body.grounded);
  auto normalY = [&](std::uint32_t t) {
    REQUIRE(t < level.world.triangles().size());
    return level.world.trianglePlanes()[t].face().normal().y();
  };
  CHECK(normalY(body.groundTriangles[0]) == Approx(1));
  CHECK(body.groundTriangles[1] == bspf::kNoTriangle);
  // Walking into the wall at x = 5 and along it: the floor and the wall.
  const Vec3 force(40, 0, 12);
  for (int frame = 0; frame < 120; ++frame) {
    Body hinted = body, unhinted = body;
    unhinted.groundTriangles = bspf::kNoGroundTriangles;
    bspf::stepBody(level.world, hinted, force, kDt, scratch);
    bspf::stepBody(level.world, unhinted, force, kDt, scratch);
    INFO("frame " << frame);
    // Only the floor and the wall block: met first by hint or by scan,
    // they leave the same end (the wall is upright, so the order they are
    // met in does not change it). The exact sweep slides along the floor it
    // rests on from the start, where without hints its first sweep meets
    // the floor a little way along the move: the same end but for rounding.
    const float rounding = method == bspf::CollisionMethod::Planes ? 0.0f : 2e-6f;
    REQUIRE((hinted.position - unhinted.position).cwiseAbs().maxCoeff() <= rounding);
    REQUIRE((hinted.velocity - unhinted.velocity).cwiseAbs().maxCoeff() <= rounding);
    body = hinted;
  }
  CHECK(body.position.x() == Approx(5 - 0.45f).margin(2e-3));
  CHECK(normalY(body.groundTriangles[0]) == Approx(1));
  // The wall is no ground.
  CHECK(body.groundTriangles[1] == bspf::kNoTriangle);
}

TEST_CASE("wrong triangle hints never let a body into a wall or a floor", "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  const Level level(floorWithCorner());
  bspf::StepScratch scratch;
  // A body walking into the corner of the two walls, settled there.
  Body settled = walker({0, 0.9f, 0}, method);
  const Vec3 push(40, 0, 40);
  run(level.world, settled, push, 120, scratch);
  REQUIRE(settled.grounded);
  const auto triangleCount = std::uint32_t(level.world.triangles().size());
  std::vector<std::uint32_t> hints = {bspf::kNoTriangle, triangleCount, triangleCount + 7,
                                      0x7FFFFFFFu};
  for (std::uint32_t t = 0; t < triangleCount; ++t) hints.push_back(t);
  for (std::size_t k = 0; k < hints.size(); ++k) {
    // Each wrong value alone, and with three others.
    for (const bool alone : {true, false}) {
      Body body = settled;
      body.groundTriangles = bspf::kNoGroundTriangles;
      for (std::size_t j = 0; j < (alone ? 1 : 4); ++j)
        body.groundTriangles[j] = hints[(k + 5 * j) % hints.size()];
      INFO("hints " << body.groundTriangles[0] << " " << body.groundTriangles[1] << " "
                    << body.groundTriangles[2] << " " << body.groundTriangles[3]);
      for (int frame = 0; frame < 20; ++frame) {
        bspf::StepReport report;
        bspf::stepBody(level.world, body, push, kDt, scratch, &report);
        REQUIRE(!report.refused);
        // The body stays out of both walls and on the floor (skin 1 mm).
        REQUIRE(body.position.x() <= 5 - 0.45f + 1e-3f);
        REQUIRE(body.position.z() <= 5 - 0.45f + 1e-3f);
        REQUIRE(body.position.y() >= 0.85f - 1e-3f);
        REQUIRE(body.position.y() <= 0.85f + 0.01f);
        REQUIRE(body.grounded);
      }
    }
  }
}
