// SPDX-License-Identifier: MIT
#include <bspf/debug_draw.h>
#include <bspf/query.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "velocity.h"

namespace bspf {

namespace {

// Where each node and leaf hangs in the tree: its parent node and whether
// it is that node's front child. The root has parent -1.
struct Parents {
  std::vector<std::int32_t> ofNode, ofLeaf;
  std::vector<bool> nodeInFront, leafInFront;

  explicit Parents(const World& world)
      : ofNode(world.nodes().size(), -1),
        ofLeaf(world.leaves().size(), -1),
        nodeInFront(world.nodes().size(), false),
        leafInFront(world.leaves().size(), false) {
    for (std::int32_t n = 0; n < std::int32_t(world.nodes().size()); ++n) {
      const schema::Node& node = world.nodes()[n];
      for (const bool front : {true, false}) {
        const std::int32_t child = front ? node.front() : node.back();
        if (child >= 0) {
          ofNode[child] = n;
          nodeInFront[child] = front;
        } else {
          ofLeaf[-(child + 1)] = n;
          leafInFront[-(child + 1)] = front;
        }
      }
    }
  }
};

// The cell of `leaf`: its half-spaces, root first, and its box.
void describeCell(const World& world, const Parents& parents, std::uint32_t leaf,
                  std::vector<DebugHalfSpace>& halfSpaces, DebugCell& cell) {
  halfSpaces.clear();
  std::int32_t node = parents.ofLeaf[leaf];
  bool inFront = parents.leafInFront[leaf];
  while (node >= 0) {
    const schema::Plane& split = world.nodes()[node].split();
    const Vec3 n = toVec3(split.normal());
    // The front side is dot(n, p) - d >= 0, that is dot(-n, p) <= -d.
    halfSpaces.push_back(inFront ? DebugHalfSpace{-n, -split.distance()}
                                 : DebugHalfSpace{n, split.distance()});
    inFront = parents.nodeInFront[node];
    node = parents.ofNode[node];
  }
  std::reverse(halfSpaces.begin(), halfSpaces.end());
  cell.leaf = leaf;
  cell.depth = std::uint32_t(halfSpaces.size());
  cell.halfSpaces = halfSpaces;
  cell.low = toVec3(*world.blob().bounds_min());
  cell.high = toVec3(*world.blob().bounds_max());
  for (const DebugHalfSpace& h : halfSpaces) {
    for (int axis = 0; axis < 3; ++axis) {
      const float along = h.normal[axis];
      if (std::abs(along) != 1.0f || h.normal.squaredNorm() != 1.0f) continue;
      if (along > 0)
        cell.high[axis] = std::min(cell.high[axis], h.distance);
      else
        cell.low[axis] = std::max(cell.low[axis], -h.distance);
    }
  }
}

}  // namespace

void debugQuery(const World& world, const Vec3& from, const Vec3& to, EllipsoidRadii radii,
                const DebugDraw& draw) {
  if (draw.cell) {
    std::vector<std::uint32_t> leaves;
    collectSweptLeaves(world, from, to, radii, leaves);
    const Parents parents(world);
    std::vector<DebugHalfSpace> halfSpaces;
    DebugCell cell{};
    for (const std::uint32_t leaf : leaves) {
      describeCell(world, parents, leaf, halfSpaces, cell);
      draw.cell(cell);
    }
  }
  if (draw.triangle) {
    SweepScratch scratch;
    std::vector<std::uint32_t> triangles;
    collectCandidateTriangles(world, from, to, radii, scratch, triangles);
    for (const std::uint32_t t : triangles) {
      const schema::Triangle& tri = world.triangles()[t];
      draw.triangle({t, toVec3(world.vertices()[tri.v0()]), toVec3(world.vertices()[tri.v1()]),
                     toVec3(world.vertices()[tri.v2()]),
                     toVec3(world.trianglePlanes()[t].face().normal())});
    }
  }
}

void debugContacts(const Body& body, const StepReport& report, const DebugDraw& draw) {
  if (!draw.contact || report.invalidInput != InvalidInput::None) return;
  const Vec3 radiiSquared(body.radii.xz * body.radii.xz, body.radii.y * body.radii.y,
                          body.radii.xz * body.radii.xz);
  const int count = std::min(report.contactCount, kMaxReportedContacts);
  for (int i = 0; i < count; ++i) {
    const Vec3& n = report.contactNormals[std::size_t(i)];
    // The support point of the ellipsoid diag(r)^2 along -n: the point of
    // its surface where the tangent plane has normal n.
    const float extent = effectiveRadius(n, body.radii);
    const Vec3 point =
        extent > 0 ? Vec3(body.position - radiiSquared.cwiseProduct(n) / extent) : body.position;
    draw.contact({point, n});
  }
}

StepReport debugStep(const World& world, Body& body, const Vec3& force, float dt,
                     StepScratch& scratch, const DebugDraw& draw) {
  const Body before = body;
  StepReport report;
  stepBody(world, body, force, dt, scratch, &report);
  if (report.invalidInput != InvalidInput::None) return report;
  Body aimed = before;
  detail::futureVelocity(aimed, force, dt);
  debugQuery(world, before.position, before.position + aimed.velocity * dt, before.radii, draw);
  debugContacts(body, report, draw);
  return report;
}

}  // namespace bspf
