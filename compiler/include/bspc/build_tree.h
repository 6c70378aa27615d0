// SPDX-License-Identifier: MIT
// bspc/build_tree.h: stage 3, the BSP tree with leaf triangle lists.
#pragma once

#include <bspc/mesh.h>
#include <bspc/settings.h>
#include <bspf/bspf_generated.h>
#include <bspf/thread_pool.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string_view>
#include <vector>

namespace bspc {

/// The tree in the blob's own layout (see docs/format.md).
struct BspTree {
  std::vector<bspf::schema::Node> nodes;
  std::vector<bspf::schema::Leaf> leaves;
  std::vector<std::uint32_t> leafTriangles;
  /// Child reference of the root: a node index, or -1 for a lone leaf.
  std::int32_t root = -1;
  std::uint32_t depth = 0;
};

/// Nodes with more triangles than this are split when a split pays for
/// itself at the cell's own scale (a quarter of its longest side), not only
/// at TreeSettings::queryReach: a dense cluster of tiny triangles, which no
/// query of that reach sees in part, still gets small leaves (2 million
/// triangles in a square metre made leaves of 8,192). 64 is the candidate
/// count the runtime aims to stay under at the 90th percentile.
inline constexpr std::size_t kDenseNodeTriangles = 64;

/// Splits space recursively with the best-scoring candidate plane (see
/// TreeSettings) until a node is small or deep enough. Triangles are never
/// split: one that straddles a plane is listed on both sides, so each leaf
/// lists every triangle that overlaps its cell; a triangle lying in the plane
/// goes to the side its normal faces. Deterministic: the same tree, to the
/// bit, whatever `pool` (null: this thread only) and its thread count.
/// `progress`, when set, is called with a percentage, 0 to 99, each time it
/// grows (the share of the triangles that reached a leaf, each node's share
/// divided between its children in proportion to their lists), from any of
/// the pool's threads, one call at a time.
/// Precondition: a cleaned mesh (cleanMesh) with at least one triangle.
BspTree buildTree(const Mesh& mesh, const TreeSettings& settings,
                  const std::function<void(int percent)>& progress = {},
                  bspf::ThreadPool* pool = nullptr);

}  // namespace bspc
