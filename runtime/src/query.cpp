// SPDX-License-Identifier: MIT
#include <bspf/query.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cassert>
#include <cmath>

#include "stored_box.h"

namespace bspf {

namespace {

// At one node: the child on the query's near side (where its centre or
// start lies, so always reached) and whether the far child is reached too.
struct Visit {
  bool nearIsFront;
  bool visitFar;
};

// Appends every leaf a query reaches, depth first and near side first (the
// order a path passes them), `visitOf(split)` deciding at each node.
// Near-first order pushes at most one far child per level.
template <typename VisitOf>
void collectLeaves(const World& world, std::vector<std::uint32_t>& leavesOut, VisitOf visitOf) {
  const std::span<const schema::Node> nodes = world.nodes();
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
    const Visit visit = visitOf(node.split());
    const std::int32_t nearChild = visit.nearIsFront ? node.front() : node.back();
    const std::int32_t farChild = visit.nearIsFront ? node.back() : node.front();
    if (visit.visitFar) stack[top++] = farChild;
    stack[top++] = nearChild;
  }
}

}  // namespace

void collectSweptLeaves(const World& world, const Vec3& from, const Vec3& to, EllipsoidRadii radii,
                        std::vector<std::uint32_t>& leavesOut) {
  assert(radii.xz > 0 && radii.y > 0);
  collectLeaves(world, leavesOut, [&](const schema::Plane& split) {
    const float reach = effectiveRadius(split.normal(), radii) + kSweepMarginMetres +
                        std::abs(split.distance()) * 4e-7f;
    const float startSide = signedDistance(split, from);
    const float endSide = signedDistance(split, to);
    const bool touchesFront = std::max(startSide, endSide) > -reach;
    const bool touchesBack = std::min(startSide, endSide) < reach;
    const bool startsInFront = startSide >= 0;
    // The start's side is always touched (its distance is within reach of
    // itself); the other when the path comes within reach of it.
    return Visit{startsInFront, startsInFront ? touchesBack : touchesFront};
  });
}

std::uint32_t locateLeaf(const World& world, const Vec3& p) {
  std::int32_t ref = world.root();
  while (ref >= 0) {
    const schema::Node& node = world.nodes()[ref];
    ref = signedDistance(node.split(), p) >= 0 ? node.front() : node.back();
  }
  return static_cast<std::uint32_t>(-(ref + 1));
}

void collectBoxLeaves(const World& world, const Vec3& low, const Vec3& high,
                      std::vector<std::uint32_t>& leavesOut) {
  assert((low.array() <= high.array()).all());
  const Vec3 centre = 0.5f * (low + high);
  const Vec3 half = 0.5f * (high - low);
  collectLeaves(world, leavesOut, [&](const schema::Plane& split) {
    const schema::Vec3& n = split.normal();
    // The box's extent along the normal: its support function.
    const float reach = std::abs(n.x()) * half.x() + std::abs(n.y()) * half.y() +
                        std::abs(n.z()) * half.z() + kSweepMarginMetres +
                        std::abs(split.distance()) * 4e-7f;
    const float side = signedDistance(split, centre);
    // The centre's side always overlaps the box; the far side when the
    // plane passes within the box's reach.
    return Visit{side >= 0, std::abs(side) < reach};
  });
}

// Lists each triangle of the current query's leaves (scratch.leaves) once:
// a generation stamp per triangle, so starting a query costs nothing.
class CandidateGather {
 public:
  CandidateGather(const World& world, SweepScratch& scratch) : world_(world), scratch_(scratch) {
    const std::size_t triangleCount = world.triangles().size();
    if (scratch.stamp_.size() < triangleCount) scratch.stamp_.resize(triangleCount, 0);
    if (++scratch.generation_ == 0) {  // wrapped: old stamps could collide
      std::fill(scratch.stamp_.begin(), scratch.stamp_.end(), 0);
      scratch.generation_ = 1;
    }
  }

  // Calls emit(triangle, box) for each triangle not listed yet whose box
  // overlaps [low, high], already padded by the caller, in the order of
  // first appearance.
  //
  // Three passes with no branch on the data: the box test passes for 30 to
  // 45% of a query's entries, and 60% of those that pass are a triangle
  // listed already from another leaf, two coin tosses the branch predictor
  // lost on about every other entry (cachegrind, walkers at 40 m/s on
  // oacmpdm5). Each pass writes every entry and advances past those kept.
  // Walkers (stepBodies, each body its own rare queries): 2 to 8% faster a
  // step on the larger levels. Bodies that share one scratch and query
  // every step in the same places (bspf_sweep's stepBody) had their
  // branches learned: 3 to 10% slower there. The tree walk stays branchy
  // for that reason: made branch-free too, it cost that case 20%.
  template <typename Emit>
  void gather(const Vec3& low, const Vec3& high, Emit&& emit) {
    const std::span<const std::uint32_t> references = world_.leafTriangles();
    const std::span<const schema::Box> bounds = world_.leafTriangleBounds();
    const std::span<const schema::Leaf> leaves = world_.leaves();
    const std::uint32_t generation = scratch_.generation_;
    const detail::StoredBoxTest test(low, high);
    std::size_t entries = 0;
    for (const std::uint32_t leafIndex : scratch_.leaves) entries += leaves[leafIndex].count();
    if (scratch_.kept_.size() < entries) scratch_.kept_.resize(entries);
    std::uint32_t* const kept = scratch_.kept_.data();
    // The entries whose box overlaps, read in one run per leaf.
    std::size_t overlapping = 0;
    for (const std::uint32_t leafIndex : scratch_.leaves) {
      const schema::Leaf& leaf = leaves[leafIndex];
      const std::uint32_t end = leaf.first() + leaf.count();
      for (std::uint32_t i = leaf.first(); i < end; ++i) {
        kept[overlapping] = i;
        overlapping += test.overlaps(bounds[i]);
      }
    }
    // Of those, the first of each triangle.
    std::size_t firsts = 0;
    for (std::size_t k = 0; k < overlapping; ++k) {
      const std::uint32_t entry = kept[k];
      std::uint32_t& stamp = scratch_.stamp_[references[entry]];
      const bool unseen = stamp != generation;
      stamp = generation;
      kept[firsts] = entry;
      firsts += unseen;
    }
    for (std::size_t k = 0; k < firsts; ++k) emit(references[kept[k]], bounds[kept[k]]);
  }

 private:
  const World& world_;
  SweepScratch& scratch_;
};

void collectCandidateTriangles(const World& world, const Vec3& from, const Vec3& to,
                               EllipsoidRadii radii, SweepScratch& scratch,
                               std::vector<std::uint32_t>& trianglesOut) {
  trianglesOut.clear();
  scratch.leaves.clear();
  collectSweptLeaves(world, from, to, radii, scratch.leaves);
  const Bounds swept = sweptBounds(from, to, radii);
  CandidateGather(world, scratch)
      .gather(swept.low, swept.high,
              [&](std::uint32_t t, const schema::Box&) { trianglesOut.push_back(t); });
}

void collectBoxCandidates(const World& world, const Vec3& low, const Vec3& high,
                          SweepScratch& scratch, std::vector<CandidateTriangle>& out) {
  out.clear();
  scratch.leaves.clear();
  Vec3 paddedLow = low, paddedHigh = high;
  padBounds(paddedLow, paddedHigh);
  collectBoxLeaves(world, paddedLow, paddedHigh, scratch.leaves);
  CandidateGather(world, scratch)
      .gather(paddedLow, paddedHigh, [&](std::uint32_t t, const schema::Box& box) {
        out.push_back({t, toVec3(box.min()), toVec3(box.max())});
      });
}

void NearbyTriangles::cover(const World& world, const Vec3& low, const Vec3& high, float pad,
                            SweepScratch& scratch, const Vec3& ahead) {
  // Reused while it holds the box, unless it is far larger than a query
  // for this box would be: one long move (a big push, a fast fall) must not
  // leave the body scanning a long list for many frames after. "Far": 8
  // pads more than a fresh query's 2 (and its stretch ahead). A fast body
  // that turns or slows keeps a query larger than a fresh one by its old
  // stretch and move, each about a pad at 40 m/s: with 2 pads more, walkers
  // at 40 m/s queried again almost every step on the terrain; with 4, their
  // steps took 43% fewer instructions there, 22% on curved_room, 0 to 5% on
  // the shared levels, 2% more on cad_building (callgrind, planes; at
  // 6 m/s within 1% everywhere). With 8 (and nearbyPad's pad of 0.4 of the
  // move + 0.35 m), walkers at 40 m/s took 0.3 to 1.5% fewer on the shared
  // levels, 0.8 to 7% fewer on the detailed ones, both methods; at 6 m/s
  // 0.3 to 1.2% fewer, but for 0.1 to 0.4% more on cad_building and (exact)
  // curved_room. 10 and more pads gave the same as 8: no walker's query
  // grew that much larger than a fresh one.
  const Vec3 spare = (high_ - low_) - (high - low);
  if (holds(world, low, high) && (spare.array() <= 10 * pad + 0.1f + ahead.array().abs()).all())
    return;
  worldId_ = world.id();
  low_ = low - Vec3::Constant(pad) + ahead.cwiseMin(0.0f);
  high_ = high + Vec3::Constant(pad) + ahead.cwiseMax(0.0f);
  ++queries_;
  static std::atomic<std::uint64_t> lastQueryId{0};
  queryId_ = ++lastQueryId;
  collectBoxCandidates(world, low_, high_, scratch, list_);
}

}  // namespace bspf
