#include <bspf/query.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>

namespace bspf {

void collectSweptLeaves(const World& world, const Vec3& from, const Vec3& to, EllipsoidRadii radii,
                        std::vector<std::uint32_t>& leavesOut) {
  assert(radii.xz > 0 && radii.y > 0);
  const std::span<const schema::Node> nodes = world.nodes();
  // Near-first depth-first order pushes at most one far child per level.
  std::array<std::int32_t, kMaxTreeDepth + 2> stack;
  std::size_t top = 0;
  stack[top++] = world.root();
  while (top > 0) {
    const std::int32_t ref = stack[--top];
    if (ref < 0) {
      leavesOut.push_back(static_cast<std::uint32_t>(-(ref + 1)));
      continue;
    }
    const schema::Node& node = nodes[ref];
    const schema::Plane& split = node.split();
    const float reach = effectiveRadius(split.normal(), radii) + kSweepMarginMetres +
                        std::abs(split.distance()) * 4e-7f;
    const float startSide = signedDistance(split, from);
    const float endSide = signedDistance(split, to);
    const bool touchesFront = std::max(startSide, endSide) > -reach;
    const bool touchesBack = std::min(startSide, endSide) < reach;
    const bool startsInFront = startSide >= 0;
    const std::int32_t nearChild = startsInFront ? node.front() : node.back();
    const std::int32_t farChild = startsInFront ? node.back() : node.front();
    const bool visitNear = startsInFront ? touchesFront : touchesBack;
    const bool visitFar = startsInFront ? touchesBack : touchesFront;
    if (visitFar) stack[top++] = farChild;
    if (visitNear) stack[top++] = nearChild;
  }
}

std::uint32_t locateLeaf(const World& world, const Vec3& p) {
  std::int32_t ref = world.root();
  while (ref >= 0) {
    const schema::Node& node = world.nodes()[ref];
    ref = signedDistance(node.split(), p) >= 0 ? node.front() : node.back();
  }
  return static_cast<std::uint32_t>(-(ref + 1));
}

void collectCandidateTriangles(const World& world, const Vec3& from, const Vec3& to,
                               EllipsoidRadii radii, SweepScratch& scratch,
                               std::vector<std::uint32_t>& trianglesOut) {
  trianglesOut.clear();
  scratch.leaves.clear();
  collectSweptLeaves(world, from, to, radii, scratch.leaves);

  const std::size_t triangleCount = world.triangles().size();
  if (scratch.stamp_.size() < triangleCount) scratch.stamp_.resize(triangleCount, 0);
  if (++scratch.generation_ == 0) {  // wrapped: old stamps could collide
    std::fill(scratch.stamp_.begin(), scratch.stamp_.end(), 0);
    scratch.generation_ = 1;
  }
  const std::uint32_t generation = scratch.generation_;
  for (const std::uint32_t leaf : scratch.leaves) {
    for (const std::uint32_t triangle : world.leafTriangleList(leaf)) {
      if (scratch.stamp_[triangle] == generation) continue;
      scratch.stamp_[triangle] = generation;
      trianglesOut.push_back(triangle);
    }
  }
}

}  // namespace bspf
