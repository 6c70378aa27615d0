// SPDX-License-Identifier: MIT
// The checks the fuzz targets run on a World the loader accepted
// (world_checks.h).
#include "world_checks.h"

#include <bspf/movement.h>
#include <bspf/query.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

namespace bspf::fuzz {

void require(bool holds, const char* what) {
  if (holds) return;
  std::fprintf(stderr, "fuzz: broken promise: %s\n", what);
  std::abort();
}

namespace {

bool finite(const bspf::Vec3& v) { return v.allFinite(); }

// Query results: every leaf and triangle index in range, each triangle once.
void checkQueries(const bspf::World& world, bspf::SweepScratch& scratch) {
  // The blob's bounds, in order: the loader checks that they are finite and
  // within kMaxCoordinate, not that they hold the vertices (docs/format.md).
  const bspf::Vec3 a = bspf::toVec3(*world.blob().bounds_min());
  const bspf::Vec3 b = bspf::toVec3(*world.blob().bounds_max());
  const bspf::Vec3 low = a.cwiseMin(b), high = a.cwiseMax(b);
  const std::size_t leafCount = world.leaves().size();
  const std::size_t triangleCount = world.triangles().size();

  require(bspf::locateLeaf(world, (low + high) / 2) < leafCount, "locateLeaf in range");
  require(bspf::locateLeaf(world, low) < leafCount, "locateLeaf at the low corner in range");

  std::vector<std::uint32_t> leaves;
  bspf::collectBoxLeaves(world, low, high, leaves);
  for (std::uint32_t leaf : leaves) require(leaf < leafCount, "collectBoxLeaves in range");
  leaves.clear();
  bspf::collectSweptLeaves(world, low, high, bspf::EllipsoidRadii{}, leaves);
  for (std::uint32_t leaf : leaves) require(leaf < leafCount, "collectSweptLeaves in range");

  std::vector<bspf::CandidateTriangle> boxed;
  bspf::collectBoxCandidates(world, low, high, scratch, boxed);
  std::vector<bool> seen(triangleCount);
  for (const auto& c : boxed) {
    require(c.triangle < triangleCount, "collectBoxCandidates in range");
    require(!seen[c.triangle], "collectBoxCandidates lists a triangle once");
    seen[c.triangle] = true;
  }
  std::vector<std::uint32_t> swept;
  bspf::collectCandidateTriangles(world, high, low, {0.3f, 0.6f}, scratch, swept);
  std::fill(seen.begin(), seen.end(), false);
  for (std::uint32_t t : swept) {
    require(t < triangleCount, "collectCandidateTriangles in range");
    require(!seen[t], "collectCandidateTriangles lists a triangle once");
    seen[t] = true;
  }
  const bspf::TreeStats stats = bspf::computeTreeStats(world);
  require(stats.leaves == leafCount, "computeTreeStats counts the leaves");
}

// Up to kBodies bodies, each just off a triangle spread over the level, on
// the side its face normal points to, moving along the triangle's plane.
constexpr std::size_t kBodies = 6;
constexpr int kFrames = 4;
constexpr float kDt = 1.0f / 60.0f;

std::vector<bspf::Body> bodiesNearTriangles(const bspf::World& world,
                                            bspf::CollisionMethod method) {
  std::vector<bspf::Body> bodies;
  const auto triangles = world.triangles();
  const auto vertices = world.vertices();
  const std::size_t count = std::min(kBodies, triangles.size());
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t t = i * triangles.size() / count;
    const bspf::schema::Triangle& tri = triangles[t];
    const bspf::Vec3 centroid =
        (bspf::toVec3(vertices[tri.v0()]) + bspf::toVec3(vertices[tri.v1()]) +
         bspf::toVec3(vertices[tri.v2()])) /
        3;
    const bspf::Vec3 normal = bspf::toVec3(world.trianglePlanes()[t].face().normal());
    bspf::Body body;
    body.settings.method = method;
    body.radii = i % 2 ? bspf::EllipsoidRadii{0.3f, 0.3f} : bspf::EllipsoidRadii{};
    body.position = centroid + normal * (body.radii.y + 0.01f);
    // Along the plane, plus a little into it: a body that slides and lands.
    body.velocity = normal.cross(bspf::Vec3::UnitY()) * 3.0f - normal * 0.5f;
    if (!finite(body.velocity)) body.velocity = -normal;
    body.settings.maxStepHeight = i % 3 == 0 ? 0.35f : 0.0f;
    bodies.push_back(body);
  }
  return bodies;
}

void checkBodies(const bspf::World& world, const std::vector<bspf::Body>& bodies,
                 const std::vector<bspf::StepReport>& reports) {
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    require(finite(bodies[i].position), "a stepped body's position stays finite");
    require(finite(bodies[i].velocity), "a stepped body's velocity stays finite");
    // Each body starts within reach, with valid radii and settings.
    require(reports[i].invalidInput == bspf::InvalidInput::None, "a valid body is stepped");
    require(reports[i].contactCount >= 0 && reports[i].contactCount <= bspf::kMaxReportedContacts,
            "a report's contact count is within its array");
    for (int c = 0; c < reports[i].contactCount; ++c) {
      const std::uint32_t t = reports[i].contactTriangles[c];
      const std::uint32_t surface = reports[i].contactSurfaces[c];
      require(finite(reports[i].contactPoints[c]), "a contact point is finite");
      if (t == bspf::kBodyContact) {
        require(surface == bspf::kBodyContact, "a body contact has the body's surface sentinel");
        continue;
      }
      require(t < world.triangles().size(), "a contact's triangle is in range");
      require(surface == world.triangleSurface(t), "a contact's surface is its triangle's");
      require(surface < world.surfaceCount(), "a contact's surface is in range");
      (void)world.surfaceName(surface);
    }
  }
}

void checkSteps(const bspf::World& world, bspf::CollisionMethod method) {
  bspf::StepScratch scratch;
  // Alone, each with stepBody.
  std::vector<bspf::Body> bodies = bodiesNearTriangles(world, method);
  std::vector<bspf::StepReport> reports(bodies.size());
  const bspf::Vec3 force(4.0f, 0.0f, -3.0f);
  for (int frame = 0; frame < kFrames; ++frame) {
    for (std::size_t i = 0; i < bodies.size(); ++i)
      bspf::stepBody(world, bodies[i], force, kDt, scratch, &reports[i]);
    checkBodies(world, bodies, reports);
  }
  // As a crowd: the level phase, then the body phase pushing them apart.
  // Everyone at the first body's place, so they overlap.
  std::vector<bspf::Body> crowd = bodiesNearTriangles(world, method);
  for (std::size_t i = 1; i < crowd.size(); ++i)
    crowd[i].position = crowd[0].position + bspf::Vec3(0.05f * static_cast<float>(i), 0, 0);
  std::vector<bspf::Vec3> forces(crowd.size(), force);
  reports.assign(crowd.size(), {});
  for (int frame = 0; frame < kFrames; ++frame) {
    bspf::stepBodies(world, crowd, forces, kDt, scratch, reports);
    checkBodies(world, crowd, reports);
  }
}

}  // namespace

void checkWorld(const bspf::World& world) {
  bspf::SweepScratch scratch;
  checkQueries(world, scratch);
  checkSteps(world, bspf::CollisionMethod::Planes);
  checkSteps(world, bspf::CollisionMethod::ExactSweep);
}

}  // namespace bspf::fuzz
