// bspc/settings.h: every knob of a compile, with its default, unit and limits.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

namespace bspc {

/// The axis that points up in the source file. The compiled level is Y up.
enum class UpAxis { X, Y, Z };

/// Where the tree builder looks for split planes.
enum class SplitCandidates {
  Axis,      ///< axis-aligned planes at quantiles of the triangle centroids
  Triangle,  ///< the planes of a sample of the node's triangles
  Both,      ///< both sets; the better score wins
};

struct ImportSettings {
  /// Up axis of the source: Z for most CAD and Blender exports without
  /// conversion. Rotation only, so winding is kept.
  UpAxis up = UpAxis::Y;
  /// Metres per source unit (0.03125 for Quake units). Must be finite and > 0.
  double scale = 1.0;
};

struct CleanSettings {
  /// Vertices closer than this, metres, are welded into the first of them.
  /// 0 welds only identical positions. Must be >= 0 and < 1. Too large a
  /// value collapses small features (thin walls thinner than it disappear).
  double weldTolerance = 1e-4;
  /// Triangles with less area, square metres, are dropped as zero-area. Must
  /// be >= 0. Slivers above it are kept: they are real collision geometry.
  double minTriangleArea = 1e-10;
};

struct TreeSettings {
  /// A node with at most this many triangles becomes a leaf. 1 to 4096.
  /// Smaller leaves mean fewer candidates per query but a deeper, larger tree
  /// and more references to triangles that straddle split planes.
  std::uint32_t maxLeafTriangles = 8;
  /// Nodes at this depth become leaves whatever their size. 1 to 64 (the
  /// runtime's kMaxTreeDepth).
  std::uint32_t maxDepth = 40;
  /// Score = balanceWeight * |front - back| / n + splitWeight * straddling / n;
  /// the lowest-scoring candidate splits the node. Both must be >= 0. The
  /// defaults (1 and 8) were measured on the shared levels against other
  /// settings (docs/tree-tuning.md, scripts/tune_tree.sh): straddling costs
  /// more than imbalance, because every straddler is listed twice and queries
  /// visit more leaves; 8 halves the leaves per query of 2 at equal candidates.
  double balanceWeight = 1.0;
  double splitWeight = 8.0;
  SplitCandidates candidates = SplitCandidates::Both;
  /// Metres: the size of a typical query (body radius plus one frame's
  /// travel). A node is split only when that pays for itself: when one more
  /// plane test plus the triangles of the children, each weighted by how
  /// likely a query of this reach overlaps the child's cell, costs less than
  /// testing all the node's triangles. Larger values stop splitting sooner
  /// (fewer, fuller leaves); 0 splits as long as the cells shrink. >= 0.
  double queryReach = 1.0;
  /// Axis-aligned candidates per axis (quantiles of centroids). 1 to 64.
  std::uint32_t axisCandidatesPerAxis = 7;
  /// Triangle-plane candidates, sampled evenly from the node. 1 to 256.
  std::uint32_t triangleCandidates = 24;
};

struct CompileSettings {
  ImportSettings import;
  CleanSettings clean;
  TreeSettings tree;
  /// Drop the faces lying against an opposite face of another solid
  /// (dropCoveredFaces, bspc/edges.h). Off (`--keep-covered-faces`): every
  /// cleaned face is kept, and a level of closed solids stays a union of
  /// closed meshes (what a winding-number inside test needs).
  bool dropCoveredFaces = true;
  /// Called with a one-line status now and then during long stages; may be
  /// empty. bspc prints it on stderr when that is a terminal.
  std::function<void(std::string_view)> progress;
};

/// Throws CompileError naming the first setting out of range.
void validate(const CompileSettings& settings);

/// The settings that shape the output, as one canonical line stored in the
/// blob ("up=y scale=1 weld=0.0001 ...").
std::string describeOptions(const CompileSettings& settings);

const char* toString(UpAxis axis);
const char* toString(SplitCandidates candidates);

}  // namespace bspc
