// SPDX-License-Identifier: MIT
// Hostile values at run time, in every build (asserts or not): a body with a
// NaN or infinite value, a bad dt, radii or settings out of range is not
// moved, its report says why, and no other body is affected.
#include <bspf/movement.h>
#include <bspf/thread_pool.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace bspf {
namespace {

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr float kDt = 1.0f / 60;

// A floor with a wall: the face x = 5.
const test::CompiledMesh& level() {
  static const test::CompiledMesh compiled = [] {
    bspc::Mesh mesh = test::boxMesh({-20, -1, -20}, {20, 0, 20});
    test::append(mesh, test::boxMesh({5, 0, -20}, {6, 4, 20}));
    return test::CompiledMesh(mesh);
  }();
  return compiled;
}

Body standing(float x, CollisionMethod method) {
  Body b;
  b.position = Vec3(x, 0.86f, 0);
  b.radii = {0.45f, 0.85f};
  b.settings.method = method;
  return b;
}

bool sameBits(const Body& a, const Body& b) {
  return std::memcmp(a.position.data(), b.position.data(), sizeof(float) * 3) == 0 &&
         std::memcmp(a.velocity.data(), b.velocity.data(), sizeof(float) * 3) == 0 &&
         a.grounded == b.grounded;
}

struct Hostile {
  std::string name;
  InvalidInput expected;
  void (*spoil)(Body&, Vec3& force, float& dt);
};

const std::vector<Hostile>& hostileInputs() {
  static const std::vector<Hostile> cases{
      {"NaN position", InvalidInput::Position,
       [](Body& b, Vec3&, float&) { b.position.x() = kNaN; }},
      {"infinite position", InvalidInput::Position,
       [](Body& b, Vec3&, float&) { b.position.y() = -kInf; }},
      {"NaN velocity", InvalidInput::Velocity,
       [](Body& b, Vec3&, float&) { b.velocity.z() = kNaN; }},
      {"infinite velocity", InvalidInput::Velocity,
       [](Body& b, Vec3&, float&) { b.velocity.x() = kInf; }},
      {"NaN force", InvalidInput::Force, [](Body&, Vec3& f, float&) { f.x() = kNaN; }},
      {"infinite force", InvalidInput::Force, [](Body&, Vec3& f, float&) { f.z() = kInf; }},
      {"NaN dt", InvalidInput::TimeStep, [](Body&, Vec3&, float& dt) { dt = kNaN; }},
      {"infinite dt", InvalidInput::TimeStep, [](Body&, Vec3&, float& dt) { dt = kInf; }},
      {"zero dt", InvalidInput::TimeStep, [](Body&, Vec3&, float& dt) { dt = 0; }},
      {"negative dt", InvalidInput::TimeStep, [](Body&, Vec3&, float& dt) { dt = -kDt; }},
      {"zero radius", InvalidInput::Radii, [](Body& b, Vec3&, float&) { b.radii.xz = 0; }},
      {"negative radius", InvalidInput::Radii, [](Body& b, Vec3&, float&) { b.radii.y = -1; }},
      {"NaN radius", InvalidInput::Radii, [](Body& b, Vec3&, float&) { b.radii.y = kNaN; }},
      {"huge radius", InvalidInput::Radii, [](Body& b, Vec3&, float&) { b.radii.xz = 1e30f; }},
      {"NaN gravity", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.gravity = kNaN; }},
      {"infinite gravity", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.gravity = kInf; }},
      {"maxIterations -1", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.maxIterations = -1; }},
      {"maxIterations 10^9", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.maxIterations = 1000000000; }},
      {"NaN skin", InvalidInput::Settings, [](Body& b, Vec3&, float&) { b.settings.skin = kNaN; }},
      {"NaN maxStepDown", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.maxStepDown = kNaN; }},
      {"negative maxStepDown", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.maxStepDown = -0.1f; }},
      {"maxStepDown beyond kMaxBodyRadius", InvalidInput::Settings,
       [](Body& b, Vec3&, float&) { b.settings.maxStepDown = 2e3f; }},
      {"a position beyond kMaxBodyCoordinate", InvalidInput::OutOfReach,
       [](Body& b, Vec3&, float&) { b.position.x() = 2e6f; }},
      {"a huge finite gravity", InvalidInput::OutOfReach,
       [](Body& b, Vec3&, float&) { b.settings.gravity = 1e38f; }},
      {"NaN deferred push", InvalidInput::DeferredPush,
       [](Body& b, Vec3&, float&) { b.deferredPush.y() = kNaN; }},
      {"infinite deferred push", InvalidInput::DeferredPush,
       [](Body& b, Vec3&, float&) { b.deferredPush.x() = -kInf; }},
      {"a deferred push beyond kMaxBodyCoordinate", InvalidInput::OutOfReach,
       [](Body& b, Vec3&, float&) { b.deferredPush.z() = 3e6f; }},
  };
  return cases;
}

TEST_CASE(
    "a body with a non-finite value, a bad dt, or radii or settings out of range is not "
    "moved and its report says why",
    "[movement][hostile]") {
  const World& world = level().world;
  for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep})
    for (const Hostile& h : hostileInputs()) {
      INFO(h.name << ", method " << int(method));
      Body body = standing(4.0f, method);
      body.velocity = Vec3(6, 0, 0);  // into the wall: a blocked move
      Vec3 force(60, 0, 0);
      float dt = kDt;
      h.spoil(body, force, dt);
      const Body before = body;
      StepScratch scratch;
      StepReport report;
      report.iterations = 99;
      stepBody(world, body, force, dt, scratch, &report);
      CHECK(sameBits(body, before));
      CHECK(report.invalidInput == h.expected);
      CHECK(std::string(toString(report.invalidInput)) != "unknown");
      CHECK(report.iterations == 0);
      CHECK(report.contactCount == 0);
    }
}

TEST_CASE(
    "settings that passed the check are checked again when they change, and against each "
    "body's own radii",
    "[movement][hostile]") {
  StepScratch scratch;
  StepReport report;
  for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep}) {
    INFO("method " << int(method));
    // A step height of 1 m is in range for a body 0.85 m tall (at most
    // twice its y radius), out of range for one 0.4 m tall.
    Body tall = standing(0, method);
    tall.settings.maxStepHeight = 1.0f;
    stepBody(level().world, tall, Vec3(10, 0, 0), kDt, scratch, &report);
    CHECK(report.invalidInput == InvalidInput::None);
    Body short_ = standing(0, method);
    short_.settings = tall.settings;
    short_.radii.y = 0.4f;
    short_.position.y() = 0.41f;
    stepBody(level().world, short_, Vec3(10, 0, 0), kDt, scratch, &report);
    CHECK(report.invalidInput == InvalidInput::Settings);
    // The same body, its settings spoiled after a step that passed.
    stepBody(level().world, tall, Vec3(10, 0, 0), kDt, scratch, &report);
    CHECK(report.invalidInput == InvalidInput::None);
    tall.settings.skin = -0.001f;
    stepBody(level().world, tall, Vec3(10, 0, 0), kDt, scratch, &report);
    CHECK(report.invalidInput == InvalidInput::Settings);
  }
}

TEST_CASE("valid bodies report no invalid input", "[movement][hostile]") {
  StepScratch scratch;
  Body body = standing(0, CollisionMethod::Planes);
  StepReport report;
  stepBody(level().world, body, Vec3(10, 0, 0), kDt, scratch, &report);
  CHECK(report.invalidInput == InvalidInput::None);
  CHECK(std::string(toString(InvalidInput::None)) == "none");
}

// Three overlapping bodies, the middle one spoiled: the other two move as
// they do without it, and stay finite.
TEST_CASE("a body with hostile values affects no other body in stepBodies",
          "[movement][hostile][threads]") {
  const World& world = level().world;
  const bool pooled = GENERATE(false, true);
  for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep})
    for (const Hostile& h : hostileInputs()) {
      if (h.expected == InvalidInput::TimeStep) continue;  // dt is the frame's, not a body's
      INFO(h.name << ", method " << int(method) << (pooled ? ", thread pool" : ""));
      std::vector<Body> bodies{standing(0, method), standing(0.3f, method), standing(0.6f, method)};
      std::vector<Vec3> forces(3, Vec3(5, 0, 1));
      float dt = kDt;
      h.spoil(bodies[1], forces[1], dt);
      std::vector<Body> alone{bodies[0], bodies[2]};
      std::vector<Vec3> aloneForces{forces[0], forces[2]};
      std::vector<StepReport> reports(3), aloneReports(2);
      ThreadPool pool(2);
      std::vector<StepScratch> scratches(2);
      for (int frame = 0; frame < 10; ++frame) {
        if (pooled) {
          stepBodies(world, bodies, forces, dt, pool, scratches, reports);
        } else {
          stepBodies(world, bodies, forces, dt, scratches[0], reports);
        }
        StepScratch own;
        stepBodies(world, alone, aloneForces, dt, own, aloneReports);
        CHECK(reports[1].invalidInput == h.expected);
        for (int k = 0; k < 2; ++k) {
          const Body& b = bodies[k * 2];
          REQUIRE(b.position.allFinite());
          CHECK(b.position == alone[k].position);
          CHECK(b.velocity == alone[k].velocity);
          CHECK(reports[k * 2].bodyContacts == aloneReports[k].bodyContacts);
        }
      }
    }
}

}  // namespace
}  // namespace bspf
