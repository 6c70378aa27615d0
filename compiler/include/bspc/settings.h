// SPDX-License-Identifier: MIT
// bspc/settings.h: every knob of a compile, with its default, unit and limits.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

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
  /// Whether compileFile runs the importer in a child process
  /// (importMeshContained), so that a file which crashes or hangs assimp,
  /// or makes it take all memory, fails the compile with one line instead.
  /// false imports in this process (importMesh), for callers that contain
  /// it themselves (fuzzers, tests of the import itself).
  bool contained = true;
  /// Whether bspc reads a plain OBJ itself (importPlainObj), in this
  /// process: a file of only `v x y z` lines of decimal numbers, triangle
  /// `f a b c` lines of vertex indices (1-based or negative), comments and
  /// blank lines, as map converters write collision meshes. The mesh is the
  /// one assimp reads, bit for bit (the coordinates parsed with its
  /// parser's arithmetic), about five times sooner (oacmpctf3, 7.8 MB: no
  /// child process, no scene). Every other file (any other format, any OBJ
  /// with anything more: objects, groups, materials, texture coordinates,
  /// polygons) goes to assimp, contained or not.
  bool readPlainObj = true;
  /// Seconds of wall-clock time (and of CPU time) the contained import may
  /// take before its child is killed: "import of X took longer than N s".
  /// Finite, > 0 and at most 86400. A million-triangle OBJ imports in a few
  /// seconds; the default leaves room for the largest level a blob can hold.
  double timeoutSeconds = 120;
  /// Bytes of address space the contained import may use (RLIMIT_AS on its
  /// child); beyond it assimp's allocations fail and the compile stops with
  /// "the importer ran out of memory". 0, the default, derives the cap from
  /// the file: 1 GiB plus 64 times its size (an OBJ's import peaks at about
  /// 8 to 10 times its size: README, "Limits"). Not applied in builds with
  /// AddressSanitizer or ThreadSanitizer, whose shadow memory needs far more
  /// address space than any cap.
  std::uint64_t memoryLimitBytes = 0;
};

struct CleanSettings {
  /// Vertices closer than this, metres, are welded into the first of them.
  /// 0 welds only identical positions. Must be >= 0 and < 1. Too large a
  /// value collapses small features (thin walls thinner than it disappear).
  double weldTolerance = 1e-4;
  /// Triangles with less area, square metres, are dropped as zero-area. Must
  /// be >= 0. Slivers above it are kept: they are real collision geometry.
  double minTriangleArea = 1e-10;
  /// Surfaces (the source's materials, Mesh::surfaces) whose triangles are
  /// left out of the collision model: triggers, decoration. Each name must
  /// be a surface of the mesh (exact, case-sensitive).
  std::vector<std::string> dropSurfaces;
  /// When not empty, the only surfaces whose triangles are kept. Each name
  /// must be a surface of the mesh. Not with dropSurfaces.
  std::vector<std::string> onlySurfaces;
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
  /// Metres: the size of a typical query. A node is split only when that
  /// pays for itself: when one more plane test plus the triangles of the
  /// children, each weighted by how likely a query of this reach overlaps
  /// the child's cell, costs less than testing all the node's triangles.
  /// Larger values stop splitting sooner (fewer, fuller leaves); 0 splits as
  /// long as the cells shrink. A node of more than kDenseNodeTriangles
  /// (build_tree.h) that no split pays for at this reach is judged again at
  /// its cell's own scale, so dense clusters of tiny triangles still get
  /// small leaves. >= 0. The default, 6 m, was measured on the walkers (a
  /// body queries a padded box 2 to 4 m across and keeps it for many
  /// frames): against 1 m (the default until then, sized for one frame's
  /// swept body), 1.5 to 8% faster steps on the shared levels, 5 to 15% on
  /// the generated ones, the same trajectories, and blobs 10 to 31% smaller
  /// (docs/tree-tuning.md).
  double queryReach = 6.0;
  /// Axis-aligned candidates per axis (quantiles of centroids). 1 to 64.
  std::uint32_t axisCandidatesPerAxis = 7;
  /// Triangle-plane candidates, sampled evenly from the node. 1 to 256.
  std::uint32_t triangleCandidates = 24;
  /// Count every candidate on every triangle of every node, as bspc did up
  /// to d2c698a. Off (the default), a node of more than 128 triangles
  /// scores its candidates on an even sample of 64 of them and counts only
  /// the 4 best on all (build_tree.cpp, chooseSplit), and on the shared
  /// levels the walkers' steps cost the same (leaves per query 10% fewer to
  /// 4% more, candidates within 0.3%: docs/measurements.md, "Issue 12
  /// closed"). On: for comparison, or a level where the sample misleads;
  /// the tree takes about a fifth longer to build (oacmpctf3 108 → 129 ms
  /// on one thread).
  bool exhaustiveSplitSearch = false;
};

/// The most a blob can hold: FlatBuffers' limit, 2^31 - 1 bytes (just under
/// 2 GiB). The loader refuses anything larger.
inline constexpr std::uint64_t kMaxBlobBytes = (std::uint64_t(1) << 31) - 1;

/// Peak memory of a compile (import excluded: it has its own cap, see
/// ImportSettings::memoryLimitBytes), bytes per input triangle: 952
/// measured with /usr/bin/time -v on the 2-million-triangle grid of
/// scripts/make_grid.py (README, "Limits"), rounded up. The bspc tool keeps
/// freed memory in the heap for reuse (fewer page faults, 15% more peak);
/// a library caller with the allocator's defaults peaks lower (823 there).
/// The estimate LimitSettings::maxMemoryBytes is checked against.
inline constexpr std::uint64_t kPeakBytesPerTriangle = 1000;

/// Limits checked early, so an input too large fails in seconds with one
/// line, not after minutes of work (README, "Limits").
struct LimitSettings {
  /// Largest blob to write, bytes: 1 to kMaxBlobBytes (the default). Checked
  /// right after clean against the bytes every triangle and vertex takes in
  /// a blob whatever the tree (minimumBlobBytes in write.h: about 158 a
  /// triangle plus 12 a vertex, so about 13.5 million triangles at most),
  /// again once the tree is built, and on the blob itself.
  std::uint64_t maxBlobBytes = kMaxBlobBytes;
  /// Largest peak memory the compile may take, bytes; 0, the default, sets
  /// no limit beyond what maxBlobBytes implies (about 14 GB at the
  /// largest blob). Checked right after import against
  /// kPeakBytesPerTriangle times the imported triangles.
  std::uint64_t maxMemoryBytes = 0;
};

/// The reach rule (`--reach-from`, `--body-radii`). Off while `from` is
/// empty: a level whose playable space is not known keeps every face.
struct ReachSettings {
  /// Body centres in the level's free space, metres, in the compiled level's
  /// frame (after --up and --scale): spawn points lifted to where a body's
  /// centre is. A point within the body's size of a surface is an error.
  std::vector<Eigen::Vector3d> from;
  /// The smallest body the level must hold, metres: its horizontal and
  /// vertical radii (the README's player: 0.45 and 0.85). A face is kept
  /// when a body of these radii (or any larger) can touch it from somewhere
  /// connected to `from`. Each > 0.01 and finite; their ratio at most 8.
  double radiusXZ = 0.45;
  double radiusY = 0.85;
  /// Most grid cells the flood may use (1 bit each, twice: 64 MiB at the
  /// default). A level that needs more at cellOfRadius gets larger cells (up
  /// to 0.6 of the smaller radius: fewer faces dropped); one that needs more
  /// even then (about 230 x 100 x 230 m for the default body) is left whole,
  /// with a warning. 1 to 2^32.
  std::uint64_t maxCells = std::uint64_t(1) << 28;
  /// The grid's cell, as a fraction of the smaller radius: 0.05 to 0.4.
  /// Smaller cells drop more faces (the flood and the keep test are within
  /// a cell of exact) and take longer: the cells near surfaces grow as its
  /// inverse square.
  double cellOfRadius = 0.2;
};

struct CompileSettings {
  ImportSettings import;
  CleanSettings clean;
  TreeSettings tree;
  LimitSettings limits;
  ReachSettings reach;
  /// Threads the stages after clean (the face rules, the reach flood's
  /// distance passes, the tree build, the planes) run on; 0, the default,
  /// takes every core (std::thread::hardware_concurrency). 0 to 1024. Only
  /// the speed depends on it: the blob is the same, byte for byte, for any
  /// count, so it is not recorded in the blob's options.
  unsigned threads = 0;
  /// Drop the faces lying against an opposite face of another solid
  /// (dropCoveredFaces, bspc/edges.h). Off (`--keep-covered-faces`): every
  /// cleaned face is kept, and a level of closed solids stays a union of
  /// closed meshes (what a winding-number inside test needs).
  bool dropCoveredFaces = true;
  /// Drop the faces lying inside another closed solid, every corner at
  /// least kBuriedMargin (1 mm) inside it (findBuriedFaces, bspc/buried.h).
  /// Off (`--keep-buried-faces`): they are kept, as a level of closed solids
  /// overlapping one another needs for a winding-number inside test.
  bool dropBuriedFaces = true;
  /// Called with a one-line status, a stage's name and how far it is
  /// ("build tree 42%"), as the compile goes on; may be empty. From the
  /// compiling thread or the tree build's, one call at a time. bspc prints
  /// it on stderr when that is a terminal.
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
