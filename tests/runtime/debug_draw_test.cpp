// SPDX-License-Identifier: MIT
#include <bspf/debug_draw.h>
#include <bspf/query.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <vector>

#include "support/test_support.h"

using bspf::Vec3;

namespace {

constexpr float kDt = 1.0f / 60.0f;

// A 40 m floor slab (top at y = 0) and a wall whose face is the plane x = 5.
bspc::Mesh floorWithWall() {
  bspc::Mesh mesh = bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20});
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -20}, {6, 4, 20}));
  return mesh;
}

struct Recorded {
  std::vector<bspf::DebugCell> cells;
  std::vector<std::vector<bspf::DebugHalfSpace>> halfSpaces;  // copies: spans die after the call
  std::vector<bspf::DebugTriangle> triangles;
  std::vector<bspf::DebugContact> contacts;
  bspf::DebugDraw draw() {
    return {[this](const bspf::DebugCell& c) {
              cells.push_back(c);
              halfSpaces.emplace_back(c.halfSpaces.begin(), c.halfSpaces.end());
            },
            [this](const bspf::DebugTriangle& t) { triangles.push_back(t); },
            [this](const bspf::DebugContact& c) { contacts.push_back(c); }};
  }
};

bool insideCell(const std::vector<bspf::DebugHalfSpace>& halfSpaces, const Vec3& p) {
  return std::all_of(halfSpaces.begin(), halfSpaces.end(), [&](const bspf::DebugHalfSpace& h) {
    return h.normal.dot(p) <= h.distance + 1e-4f;
  });
}

}  // namespace

TEST_CASE("debugQuery reports the leaves and candidate triangles of the query it replays",
          "[runtime][debug-draw]") {
  const bspf::test::CompiledMesh level(floorWithWall());
  const bspf::EllipsoidRadii radii{0.45f, 0.85f};
  const Vec3 from(3, 0.9f, 0), to(4.8f, 0.8f, 1);

  Recorded recorded;
  bspf::debugQuery(level.world, from, to, radii, recorded.draw());

  std::vector<std::uint32_t> leaves;
  bspf::collectSweptLeaves(level.world, from, to, radii, leaves);
  REQUIRE(recorded.cells.size() == leaves.size());
  for (std::size_t i = 0; i < leaves.size(); ++i) REQUIRE(recorded.cells[i].leaf == leaves[i]);

  bspf::SweepScratch scratch;
  std::vector<std::uint32_t> candidates;
  bspf::collectCandidateTriangles(level.world, from, to, radii, scratch, candidates);
  REQUIRE_FALSE(candidates.empty());
  REQUIRE(recorded.triangles.size() == candidates.size());
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const bspf::DebugTriangle& t = recorded.triangles[i];
    REQUIRE(t.triangle == candidates[i]);
    const auto& stored = level.world.triangles()[t.triangle];
    REQUIRE(t.a == bspf::toVec3(level.world.vertices()[stored.v0()]));
    REQUIRE(t.c == bspf::toVec3(level.world.vertices()[stored.v2()]));
    REQUIRE(t.normal.norm() == Approx(1).margin(1e-5));
  }
  // The floor's top (normal +y) and the wall's face (normal -x) are among them.
  auto has = [&](const Vec3& normal) {
    return std::any_of(recorded.triangles.begin(), recorded.triangles.end(),
                       [&](const bspf::DebugTriangle& t) { return t.normal.dot(normal) > 0.999f; });
  };
  REQUIRE(has(Vec3::UnitY()));
  REQUIRE(has(-Vec3::UnitX()));
}

TEST_CASE("a debug cell's half-spaces and box hold the points its leaf is located from",
          "[runtime][debug-draw]") {
  const bspf::test::CompiledMesh level(floorWithWall());
  REQUIRE(level.world.nodes().size() > 0);
  for (const Vec3& p : {Vec3(0, 0.5f, 0), Vec3(5.5f, 2, 3), Vec3(-10, -0.5f, 15)}) {
    INFO("point " << p.transpose());
    Recorded recorded;
    // A sweep of a tiny body staying at p reaches p's leaf among others.
    bspf::DebugDraw cellsOnly;
    cellsOnly.cell = recorded.draw().cell;
    bspf::debugQuery(level.world, p, p, {0.01f, 0.01f}, cellsOnly);
    const std::uint32_t leaf = bspf::locateLeaf(level.world, p);
    const auto found = std::find_if(recorded.cells.begin(), recorded.cells.end(),
                                    [&](const bspf::DebugCell& c) { return c.leaf == leaf; });
    REQUIRE(found != recorded.cells.end());
    const std::size_t i = std::size_t(found - recorded.cells.begin());
    REQUIRE(found->depth == recorded.halfSpaces[i].size());
    REQUIRE(found->depth >= 1);
    REQUIRE(insideCell(recorded.halfSpaces[i], p));
    REQUIRE((p.array() >= found->low.array() - 1e-4f).all());
    REQUIRE((p.array() <= found->high.array() + 1e-4f).all());
    // Every cell reached lies within the level's bounds.
    for (const bspf::DebugCell& c : recorded.cells)
      REQUIRE((c.low.array() <= c.high.array()).all());
  }
}

TEST_CASE("debugStep steps a body as stepBody does and reports where it touched the floor",
          "[runtime][debug-draw]") {
  const bspf::test::CompiledMesh level(floorWithWall());
  bspf::Body body;
  body.position = Vec3(0, 0.9f, 0);
  body.radii = {0.45f, 0.85f};
  bspf::Body twin = body;
  bspf::StepScratch scratch, twinScratch;
  Recorded recorded;
  bspf::StepReport report;
  for (int frame = 0; frame < 30; ++frame) {
    recorded = Recorded{};
    report = bspf::debugStep(level.world, body, Vec3(0, 0, 0), kDt, scratch, recorded.draw());
    bspf::StepReport twinReport;
    bspf::stepBody(level.world, twin, Vec3(0, 0, 0), kDt, twinScratch, &twinReport);
    REQUIRE(body.position == twin.position);
    REQUIRE(body.velocity == twin.velocity);
    REQUIRE(report.contactCount == twinReport.contactCount);
  }
  REQUIRE(report.grounded);
  REQUIRE(report.contactCount >= 1);
  REQUIRE(recorded.contacts.size() == std::size_t(std::min(report.contactCount, 8)));
  // Resting on the floor: the contact is below the centre, on the floor.
  const bspf::DebugContact& contact = recorded.contacts.front();
  REQUIRE(contact.normal.y() == Approx(1).margin(1e-4));
  REQUIRE(contact.point.y() == Approx(0).margin(3e-3));
  REQUIRE(contact.point.x() == Approx(body.position.x()).margin(1e-4));
  REQUIRE_FALSE(recorded.cells.empty());
  REQUIRE(std::any_of(recorded.triangles.begin(), recorded.triangles.end(),
                      [](const bspf::DebugTriangle& t) { return t.normal.y() > 0.999f; }));
}

TEST_CASE("debugContacts against a wall puts the point on the wall's face, level with the centre",
          "[runtime][debug-draw]") {
  bspf::Body body;
  body.position = Vec3(4.549f, 0.85f, 0);
  body.radii = {0.45f, 0.85f};
  bspf::StepReport report;
  report.contactCount = 1;
  report.contactNormals[0] = -Vec3::UnitX();
  std::vector<bspf::DebugContact> contacts;
  bspf::DebugDraw draw;
  draw.contact = [&](const bspf::DebugContact& c) { contacts.push_back(c); };
  bspf::debugContacts(body, report, draw);
  REQUIRE(contacts.size() == 1);
  REQUIRE(contacts[0].point.x() == Approx(4.999f).margin(1e-5));
  REQUIRE(contacts[0].point.y() == Approx(0.85f).margin(1e-5));
  // A report with invalid input draws nothing.
  report.invalidInput = bspf::InvalidInput::Position;
  bspf::debugContacts(body, report, draw);
  REQUIRE(contacts.size() == 1);
}
