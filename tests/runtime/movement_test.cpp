#include <bspf/movement.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
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

TEST_CASE("with a step height a body walks up 0.3 m stairs, without one it is stopped",
          "[runtime][movement]") {
  const bspf::CollisionMethod method = eachMethod();
  INFO("method " << nameOf(method));
  bspc::Mesh mesh = floorSlab();
  for (int k = 0; k < 6; ++k)  // 0.3 m risers, 0.4 m treads, from x = 0
    bspf::test::append(mesh, bspf::test::boxMesh({0.4 * k, 0, -2}, {15, 0.3 * (k + 1), 2}));
  const Level level(mesh);
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
  bspc::Mesh mesh = floorWithWall();
  bspf::test::append(mesh, bspf::test::boxMesh({-20, 0, 5}, {6, 4, 6}));
  const Level level(mesh);
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
