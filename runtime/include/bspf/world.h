// SPDX-License-Identifier: MIT
// bspf/world.h: a compiled level (.bspf), mapped read-only and verified.
//
// A World never copies geometry: every accessor returns a view into the file
// mapping or into the caller's bytes. A World is immutable after it is opened,
// so one World may be shared by any number of threads without locking.
//
// Typical use:
//
//   bspf::OpenResult opened = bspf::openWorld("level.bspf");
//   if (!opened) { log(opened.message); return; }
//   const bspf::World& world = *opened.world;
#pragma once

#include <bspf/bspf_generated.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

namespace bspf {

/// The blob format version this runtime reads. bspc writes it; the loader
/// refuses any other value with LoadStatus::WrongVersion.
inline constexpr std::uint32_t kFormatVersion = 3;

/// The four-character file identifier after the size prefix.
inline constexpr const char* kFileIdentifier = "BSPF";

/// The deepest BSP tree the runtime accepts (root node at depth 0). Bounds the
/// traversal stack, so queries never allocate for it.
inline constexpr std::uint32_t kMaxTreeDepth = 64;

/// The largest magnitude, metres, of any coordinate a blob may hold: vertex
/// and bound components, leaf triangle boxes, and node split plane distances
/// (up to twice it). 100 km, a level 200 km across: larger than any
/// level a float position can serve, since beyond it floats are more than
/// 7.8 mm apart, eight times the default skin. It also keeps the step's
/// arithmetic far from float overflow: in a body's unit-sphere space
/// (coordinates divided by a radius of at least kMinBodyRadius, movement.h)
/// squared lengths stay under 1e17.
inline constexpr float kMaxCoordinate = 1e5f;

/// Whether a triangle with these float corners is one the step can use: its
/// height (twice its area over its longest edge, computed in double) is at
/// least 8 float steps (8 * 2^-23) of its largest corner coordinate
/// magnitude, taken as at least 1 m. A thinner triangle, or one that repeats
/// a corner, is a line to float precision: it has no usable normal. Real
/// levels' thinnest triangles are about 23 steps high. bspc drops triangles
/// that fail this as degenerate; the loader refuses blobs that hold one.
bool isUsableTriangle(const schema::Vec3& a, const schema::Vec3& b, const schema::Vec3& c);

/// Why a blob was refused. Each is a distinct failure a caller may react to.
enum class LoadStatus {
  Ok,
  /// The file could not be opened, sized or mapped (see the message).
  CannotOpen,
  /// Fewer bytes than the blob's size prefix announces (an interrupted copy),
  /// or fewer than the 12 bytes any blob starts with (an empty file).
  Truncated,
  /// Not a .bspf blob at all: the file identifier is not "BSPF".
  WrongIdentifier,
  /// A .bspf blob of another format version: recompile it with this bspc.
  WrongVersion,
  /// The bytes are not a well-formed blob: stray bytes after it, FlatBuffers
  /// verification failed, or a semantic check did (a missing vector, an index
  /// out of range, a node graph that is not a tree, a non-finite float, a
  /// normal not of unit length, a leaf entry's bounding box that does not
  /// hold its triangle, units other than metres with Y up, a coordinate
  /// beyond kMaxCoordinate, a degenerate triangle (isUsableTriangle), a
  /// triangle plane that disagrees with the triangle's vertices, a surface
  /// table that is missing, empty or larger than 65536, a triangle_surfaces
  /// vector of another length than the triangles, a surface id out of the
  /// table).
  Malformed,
  /// The caller's bytes are not 8-byte aligned (a broken precondition of
  /// viewWorld that is reported rather than read misaligned).
  Misaligned,
};

/// A short, stable name for a status ("truncated", "wrong version", ...).
const char* toString(LoadStatus status);

/// A verified, read-only compiled level. Cheap to copy: copies share the
/// mapping, which lives as long as the last copy.
class World {
 public:
  /// Level geometry, metres, Y up. Views into the blob.
  std::span<const schema::Vec3> vertices() const { return vertices_; }
  std::span<const schema::Triangle> triangles() const { return triangles_; }
  /// Parallel to triangles(): each triangle's face, edge and cap planes.
  std::span<const schema::TrianglePlanes> trianglePlanes() const { return planes_; }

  /// The BSP tree. Child references: >= 0 node index, < 0 leaf (-ref - 1).
  std::span<const schema::Node> nodes() const { return nodes_; }
  std::span<const schema::Leaf> leaves() const { return leaves_; }
  /// Triangle indices, in ranges owned by the leaves.
  std::span<const std::uint32_t> leafTriangles() const { return leafTriangles_; }
  /// Parallel to leafTriangles(): each entry's triangle's bounding box.
  std::span<const schema::Box> leafTriangleBounds() const { return leafTriangleBounds_; }
  /// The root child reference; -1 (leaf 0) when the tree is a single leaf.
  std::int32_t root() const { return root_; }
  /// Depth of the deepest leaf (<= kMaxTreeDepth).
  std::uint32_t treeDepth() const { return treeDepth_; }

  /// The triangles of leaf `leafIndex`. Precondition: leafIndex < leaves().size().
  std::span<const std::uint32_t> leafTriangleList(std::uint32_t leafIndex) const;

  /// The level's bounding box, metres: every vertex lies within it.
  const schema::Vec3& boundsMin() const { return *root_table_->bounds_min(); }
  const schema::Vec3& boundsMax() const { return *root_table_->bounds_max(); }

  /// Metadata: bounds, build info (compiler version, options, statistics).
  const schema::World& blob() const { return *root_table_; }
  /// The whole blob, size prefix included.
  std::span<const std::byte> bytes() const { return bytes_; }
  /// Surfaces: the source's materials (an OBJ's usemtl names, assimp's
  /// material names), as bspc kept them; docs/format.md, "Surfaces". A
  /// surface id is an index into the surface table: 0 to surfaceCount() - 1,
  /// in the order the triangles first use them. A source without materials
  /// has one surface, named "default". bspc writes each name once.
  ///
  /// Parallel to triangles(): each triangle's surface id. A view into the
  /// blob; the loader has checked every id against the table.
  std::span<const std::uint16_t> triangleSurfaces() const { return triangleSurfaces_; }
  /// The number of surfaces, at least 1 (at most 65536).
  std::uint32_t surfaceCount() const { return surfaceCount_; }
  /// The surface id of triangle `triangle` (an index into triangles(), as
  /// StepReport::contactTriangles and the queries give them). O(1).
  /// Precondition: triangle < triangles().size() (asserted: an index from
  /// this World never breaks it). kBodyContact, the triangle of a contact
  /// with another body, is no triangle: check for it first.
  std::uint32_t triangleSurface(std::uint32_t triangle) const;
  /// The name of surface `surface`: a view into the blob (UTF-8 as the
  /// source had it; may be empty if the source's material was unnamed), valid
  /// while the World or a copy lives. O(1). Precondition: surface <
  /// surfaceCount() (asserted).
  std::string_view surfaceName(std::uint32_t surface) const;
  /// The id of the surface named `name` (exact, case-sensitive), or nothing
  /// when no surface has that name. Linear in the number of surfaces: look
  /// the names a game cares about up once, after opening the level.
  std::optional<std::uint32_t> findSurface(std::string_view name) const;

  /// A number unique to this opening of a blob within the process (never 0;
  /// copies of a World share it), so caches can tell worlds apart even when
  /// a new mapping reuses an old one's address.
  std::uint64_t id() const { return id_; }

 private:
  friend struct WorldAccess;
  std::shared_ptr<const void> owner_;  // the mapping, or null for caller bytes
  std::span<const std::byte> bytes_;
  const schema::World* root_table_ = nullptr;
  std::span<const schema::Vec3> vertices_;
  std::span<const schema::Triangle> triangles_;
  std::span<const schema::TrianglePlanes> planes_;
  std::span<const schema::Node> nodes_;
  std::span<const schema::Leaf> leaves_;
  std::span<const std::uint32_t> leafTriangles_;
  std::span<const schema::Box> leafTriangleBounds_;
  std::span<const std::uint16_t> triangleSurfaces_;
  std::uint32_t surfaceCount_ = 0;
  std::int32_t root_ = -1;
  std::uint32_t treeDepth_ = 0;
  std::uint64_t id_ = 0;
};

/// The outcome of opening a blob: a World, or a status and a one-line message
/// naming the file (or "<memory>") and what is wrong.
struct OpenResult {
  std::optional<World> world;
  LoadStatus status = LoadStatus::Ok;
  std::string message;
  explicit operator bool() const { return world.has_value(); }
};

/// Maps `path` read-only and verifies it (FlatBuffers verifier, then semantic
/// checks: see LoadStatus::Malformed). Cost: one pass over the blob, no copy of
/// geometry. Never throws for bad bytes; returns a status instead. A missing
/// or unreadable file is CannotOpen with the system's reason; a directory,
/// FIFO, device or socket is CannotOpen, "not a regular file", refused
/// without waiting for a writer. The message names the path in UTF-8.
///
/// POSIX systems map the file with mmap. Windows maps it with CreateFileW,
/// CreateFileMappingW and MapViewOfFile: the path's native UTF-16 form is
/// opened, so any Unicode name works (make the path from UTF-8 text through
/// std::u8string or char8_t: MSVC reads a plain std::string in the active
/// code page). A console, NUL or pipe there is "not a regular file". A
/// platform with no file mapping can read the file itself and use viewWorld.
///
/// Contract: the file must not be modified in place while a World made from
/// it (or any copy) is alive. The World reads the mapped pages of the file
/// itself, verified once at open: a file truncated under it kills the
/// process with SIGBUS on the next read (POSIX), and bytes written into it change
/// the level under the running game, unverified. Replace a level instead,
/// the way bspc writes one: write the new file beside it and rename() it
/// over the old path. The open World keeps the old file's pages (the old
/// inode lives until its last mapping goes), and the next openWorld of the
/// path sees the new level. Safe reload: open the new World, and swap it in
/// only when the open succeeded (keep the old one otherwise); release the
/// old World once no thread steps against it. Copying a level with `cp`
/// onto an open path writes in place: copy to a temporary name, then `mv`.
///
/// On Windows the World keeps the file open while it or any copy lives,
/// shared with readers and deleters but not writers: a program that opens
/// the file to write it fails (sharing violation), so the level cannot
/// change under the game. Windows refuses to truncate a mapped file, and may
/// refuse to delete or replace it (wine allows deleting: the name then stays
/// until the last copy is gone). Reload from a new file name, or release
/// every World of the level before replacing its file.
OpenResult openWorld(const std::filesystem::path& path);

/// Verifies caller-owned bytes and views them in place. The bytes must stay
/// alive and unchanged while the World or any copy of it is used, and must be
/// 8-byte aligned (else LoadStatus::Misaligned).
OpenResult viewWorld(std::span<const std::byte> bytes);

/// Tree shape figures, as `bspc --info` prints them.
struct TreeStats {
  std::uint32_t nodes = 0;
  std::uint32_t leaves = 0;
  std::uint32_t emptyLeaves = 0;
  std::uint32_t depthMax = 0;
  double depthMean = 0;  // over leaves
  std::uint32_t trianglesPerLeafMax = 0;
  double trianglesPerLeafMean = 0;   // over leaves
  double referencesPerTriangle = 0;  // leaf list entries / triangles
  double bytesPerTriangle = 0;       // whole blob / triangles
};

/// Walks the tree once. Precondition: `world` was opened by this runtime.
TreeStats computeTreeStats(const World& world);

}  // namespace bspf
