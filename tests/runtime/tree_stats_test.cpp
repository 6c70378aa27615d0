// SPDX-License-Identifier: MIT
// bspf::computeTreeStats against figures counted independently: a recursive
// walk of the tree written here, and worlds whose shape is known by
// construction.
#include <bspf/world.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <vector>

#include "support/test_support.h"

namespace {

struct CompiledWorld {
  bspf::test::AlignedBytes bytes;
  bspf::World world;
  CompiledWorld(const bspc::Mesh& mesh, const bspc::CompileSettings& settings)
      : bytes(bspf::test::compile(mesh, settings)), world(*bspf::viewWorld(bytes.span()).world) {}
};

// What a walk from the root sees, leaf by leaf.
struct WalkCounts {
  std::vector<int> nodeVisits, leafVisits;
  std::vector<std::uint32_t> leafDepths, leafSizes;
};

void walk(const bspf::World& world, std::int32_t ref, std::uint32_t depth, WalkCounts& counts) {
  if (ref >= 0) {
    ++counts.nodeVisits.at(std::size_t(ref));
    walk(world, world.nodes()[std::size_t(ref)].front(), depth + 1, counts);
    walk(world, world.nodes()[std::size_t(ref)].back(), depth + 1, counts);
    return;
  }
  const auto leaf = std::uint32_t(-ref - 1);
  ++counts.leafVisits.at(leaf);
  counts.leafDepths.push_back(depth);
  counts.leafSizes.push_back(std::uint32_t(world.leafTriangleList(leaf).size()));
}

double mean(const std::vector<std::uint32_t>& values) {
  double sum = 0;
  for (const std::uint32_t v : values) sum += v;
  return sum / double(values.size());
}

// Every field alike (the means up to rounding).
void checkSameStats(const bspf::TreeStats& actual, const bspf::TreeStats& expected) {
  CHECK(actual.nodes == expected.nodes);
  CHECK(actual.leaves == expected.leaves);
  CHECK(actual.emptyLeaves == expected.emptyLeaves);
  CHECK(actual.depthMax == expected.depthMax);
  CHECK(actual.depthMean == Approx(expected.depthMean).epsilon(1e-12));
  CHECK(actual.trianglesPerLeafMax == expected.trianglesPerLeafMax);
  CHECK(actual.trianglesPerLeafMean == Approx(expected.trianglesPerLeafMean).epsilon(1e-12));
  CHECK(actual.referencesPerTriangle == Approx(expected.referencesPerTriangle).epsilon(1e-12));
  CHECK(actual.bytesPerTriangle == Approx(expected.bytesPerTriangle).epsilon(1e-12));
}

// Every field of computeTreeStats equals the walk's count.
void requireStatsMatchAWalk(const bspf::World& world) {
  WalkCounts counts;
  counts.nodeVisits.assign(world.nodes().size(), 0);
  counts.leafVisits.assign(world.leaves().size(), 0);
  walk(world, world.root(), 0, counts);
  // The walk reaches every node and leaf once: its figures cover the arrays.
  REQUIRE(std::all_of(counts.nodeVisits.begin(), counts.nodeVisits.end(),
                      [](int n) { return n == 1; }));
  REQUIRE(std::all_of(counts.leafVisits.begin(), counts.leafVisits.end(),
                      [](int n) { return n == 1; }));

  std::uint32_t references = 0, emptyLeaves = 0;
  for (const std::uint32_t size : counts.leafSizes) {
    references += size;
    emptyLeaves += size == 0;
  }
  const double triangles = double(world.triangles().size());
  bspf::TreeStats walked;
  walked.nodes = std::uint32_t(counts.nodeVisits.size());
  walked.leaves = std::uint32_t(counts.leafDepths.size());
  walked.emptyLeaves = emptyLeaves;
  walked.depthMax = *std::max_element(counts.leafDepths.begin(), counts.leafDepths.end());
  walked.depthMean = mean(counts.leafDepths);
  walked.trianglesPerLeafMax = *std::max_element(counts.leafSizes.begin(), counts.leafSizes.end());
  walked.trianglesPerLeafMean = mean(counts.leafSizes);
  walked.referencesPerTriangle = references / triangles;
  walked.bytesPerTriangle = double(world.bytes().size()) / triangles;
  checkSameStats(bspf::computeTreeStats(world), walked);
}

// Boxes on a grid, some touching, some apart: a tree with empty leaves,
// straddling triangles and uneven depths.
bspc::Mesh boxField(int perSide) {
  bspc::Mesh mesh;
  for (int i = 0; i < perSide; ++i)
    for (int k = 0; k < perSide; ++k) {
      const Eigen::Vector3d low(3.0 * i, 0.5 * ((i + k) % 3), 2.5 * k);
      bspf::test::append(mesh, bspf::test::boxMesh(low, low + Eigen::Vector3d(2, 1 + i, 2.5)));
    }
  return mesh;
}

bspc::CompileSettings treeSettings(std::uint32_t maxLeafTriangles, std::uint32_t maxDepth = 40) {
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = maxLeafTriangles;
  settings.tree.maxDepth = maxDepth;
  return settings;
}

}  // namespace

TEST_CASE("tree statistics of a one-leaf world: no node, one leaf at depth 0 holding everything",
          "[runtime][stats]") {
  // The box's 12 triangles fit one leaf.
  const CompiledWorld box(bspf::test::boxMesh({0, 0, 0}, {1, 2, 3}), treeSettings(12));
  REQUIRE(box.world.root() < 0);
  const bspf::TreeStats stats = bspf::computeTreeStats(box.world);
  checkSameStats(stats, {.nodes = 0,
                         .leaves = 1,
                         .emptyLeaves = 0,
                         .depthMax = 0,
                         .depthMean = 0,
                         .trianglesPerLeafMax = 12,
                         .trianglesPerLeafMean = 12,
                         .referencesPerTriangle = 1,
                         .bytesPerTriangle = double(box.world.bytes().size()) / 12});
  requireStatsMatchAWalk(box.world);
}

TEST_CASE("tree statistics of a tree cut at depth 1: one node, two leaves, both at depth 1",
          "[runtime][stats]") {
  const CompiledWorld field(boxField(3), treeSettings(1, 1));
  const bspf::TreeStats stats = bspf::computeTreeStats(field.world);
  CHECK(stats.nodes == 1);
  CHECK(stats.leaves == 2);
  CHECK(stats.depthMax == 1);
  CHECK(stats.depthMean == 1);
  requireStatsMatchAWalk(field.world);
}

TEST_CASE("tree statistics of deeper trees equal an independent walk's counts",
          "[runtime][stats]") {
  for (const std::uint32_t leafSize : {1u, 2u, 8u}) {
    const CompiledWorld field(boxField(4), treeSettings(leafSize));
    INFO("leaf size " << leafSize);
    REQUIRE(field.world.treeDepth() >= 3);  // deep enough for uneven leaf depths
    requireStatsMatchAWalk(field.world);
  }
  const bspf::World arena = bspf::test::compileSample("arena");
  requireStatsMatchAWalk(arena);
}
