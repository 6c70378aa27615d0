// SPDX-License-Identifier: MIT
// The loader: openWorld / viewWorld refuse every bad blob with the right
// status and a useful message, and view good blobs in place without copying.
#include <bspc/compile.h>
#include <bspc/planes.h>
#include <bspf/bspf_generated.h>
#include <bspf/world.h>
#include <flatbuffers/flatbuffers.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <memory>
#include <new>
#include <optional>
#include <random>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace bspf {
namespace {

namespace fs = std::filesystem;
using Blob = std::vector<std::uint8_t>;
using Catch::Contains;

constexpr LoadStatus kAllStatuses[] = {LoadStatus::Ok,           LoadStatus::CannotOpen,
                                       LoadStatus::Truncated,    LoadStatus::WrongIdentifier,
                                       LoadStatus::WrongVersion, LoadStatus::Malformed,
                                       LoadStatus::Misaligned};

// ---------------------------------------------------------------------------
// Fixtures: small compiled blobs.

/// One box: 8 vertices, 12 triangles.
const Blob& boxBlob() {
  static const Blob blob = test::compile(test::boxMesh({0, 0, 0}, {1, 1, 1}));
  return blob;
}

bspc::Mesh fourBoxes() {
  bspc::Mesh mesh;
  for (int i = 0; i < 4; ++i)
    test::append(mesh, test::boxMesh({3.0 * i, 0, 0}, {3.0 * i + 1, 1 + 0.5 * i, 1}));
  return mesh;
}

bspc::CompileSettings smallLeaves() {
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = 2;
  settings.tree.queryReach = 0;
  return settings;
}

/// Four boxes split into small leaves: a tree with several nodes.
const Blob& treeBlob() {
  static const Blob blob = test::compile(fourBoxes(), smallLeaves());
  return blob;
}

/// Exactly `size` bytes in their own 8-byte aligned allocation, so a sanitizer
/// catches any read past the end (no slack as in test::AlignedBytes).
class ExactBytes {
 public:
  explicit ExactBytes(std::span<const std::uint8_t> bytes)
      : size_(bytes.size()),
        data_(static_cast<std::uint8_t*>(
            ::operator new (std::max<std::size_t>(size_, 1), std::align_val_t{8}))) {
    if (size_ != 0) std::memcpy(data_.get(), bytes.data(), size_);
  }
  std::span<const std::byte> span() const {
    return {reinterpret_cast<const std::byte*>(data_.get()), size_};
  }
  std::uint8_t* data() { return data_.get(); }
  std::size_t size() const { return size_; }

 private:
  struct Free {
    void operator()(std::uint8_t* p) const { ::operator delete (p, std::align_val_t{8}); }
  };
  std::size_t size_;
  std::unique_ptr<std::uint8_t, Free> data_;
};

OpenResult view(std::span<const std::uint8_t> bytes) {
  const ExactBytes copy(bytes);
  OpenResult r = viewWorld(copy.span());
  r.world.reset();  // the copy dies here: callers only look at status and message
  return r;
}

void writeFile(const fs::path& path, std::span<const std::uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  REQUIRE(out.good());
}

// ---------------------------------------------------------------------------
// Byte-level access to a size-prefixed blob, to patch fields in place.

template <typename T>
T readAt(const Blob& blob, std::size_t at) {
  REQUIRE(at + sizeof(T) <= blob.size());
  T value;
  std::memcpy(&value, blob.data() + at, sizeof(T));
  return value;
}

template <typename T>
void writeAt(Blob& blob, std::size_t at, T value) {
  REQUIRE(at + sizeof(T) <= blob.size());
  std::memcpy(blob.data() + at, &value, sizeof(T));
}

/// Position in `blob` of the root table's field `vtableOffset` (found through
/// the vtable); the field must be present.
std::size_t fieldPosition(const Blob& blob, flatbuffers::voffset_t vtableOffset) {
  const std::size_t table = 4 + readAt<std::uint32_t>(blob, 4);
  const std::size_t vtable = table - readAt<std::int32_t>(blob, table);
  REQUIRE(vtableOffset < readAt<std::uint16_t>(blob, vtable));
  const auto field = readAt<std::uint16_t>(blob, vtable + vtableOffset);
  REQUIRE(field != 0);
  return table + field;
}

// ---------------------------------------------------------------------------
// A World's content as plain vectors, rebuilt into a blob with the generated
// builder: the way to craft blobs that verify as FlatBuffers but break one
// semantic rule.

struct Content {
  std::uint32_t formatVersion = kFormatVersion;
  float metresPerUnit = 1;
  schema::UpAxis upAxis = schema::UpAxis::Y;
  schema::Vec3 boundsMin, boundsMax;
  std::string compilerVersion = "loader_test";
  std::vector<schema::Vec3> vertices;
  std::vector<schema::Triangle> triangles;
  std::vector<schema::TrianglePlanes> planes;
  std::vector<schema::Node> nodes;
  std::vector<schema::Leaf> leaves;
  std::vector<std::uint32_t> leafTriangles;
  std::int32_t root = -1;
  std::uint32_t treeDepth = 0;
  bool omitLeafTriangles = false;
  /// Written as given; when empty, each entry's box is made from its
  /// triangle's vertices (an empty box where an index is out of range).
  std::vector<schema::Box> leafBounds;
  bool omitLeafBounds = false;
  /// Written as given; when empty, one surface "default".
  std::vector<std::string> surfaces;
  /// Written as given; when empty, surface 0 for every triangle.
  std::vector<std::uint16_t> triangleSurfaces;
  bool omitSurfaces = false;
  /// Writes `surfaces` even when empty.
  bool emptySurfaceTable = false;
};

// The bounding box of each leaf entry's triangle, as bspc writes it.
std::vector<schema::Box> leafBoundsOf(const Content& c) {
  std::vector<schema::Box> boxes;
  for (const std::uint32_t t : c.leafTriangles) {
    schema::Box box;
    if (t < c.triangles.size()) {
      const schema::Triangle& tri = c.triangles[t];
      bool first = true;
      for (const std::uint32_t v : {tri.v0(), tri.v1(), tri.v2()}) {
        if (v >= c.vertices.size()) continue;
        const schema::Vec3& p = c.vertices[v];
        const schema::Vec3& lo = first ? p : box.min();
        const schema::Vec3& hi = first ? p : box.max();
        box = schema::Box(
            schema::Vec3(std::min(lo.x(), p.x()), std::min(lo.y(), p.y()), std::min(lo.z(), p.z())),
            schema::Vec3(std::max(hi.x(), p.x()), std::max(hi.y(), p.y()),
                         std::max(hi.z(), p.z())));
        first = false;
      }
    }
    boxes.push_back(box);
  }
  return boxes;
}

Content contentOf(const World& world) {
  Content c;
  const schema::World& blob = world.blob();
  c.formatVersion = blob.format_version();
  c.metresPerUnit = blob.metres_per_unit();
  c.upAxis = blob.up_axis();
  c.boundsMin = *blob.bounds_min();
  c.boundsMax = *blob.bounds_max();
  if (blob.build() && blob.build()->compiler_version())
    c.compilerVersion = blob.build()->compiler_version()->str();
  c.vertices.assign(world.vertices().begin(), world.vertices().end());
  c.triangles.assign(world.triangles().begin(), world.triangles().end());
  c.planes.assign(world.trianglePlanes().begin(), world.trianglePlanes().end());
  c.nodes.assign(world.nodes().begin(), world.nodes().end());
  c.leaves.assign(world.leaves().begin(), world.leaves().end());
  c.leafTriangles.assign(world.leafTriangles().begin(), world.leafTriangles().end());
  c.leafBounds.assign(world.leafTriangleBounds().begin(), world.leafTriangleBounds().end());
  c.root = world.root();
  c.treeDepth = world.treeDepth();
  for (std::uint32_t s = 0; s < world.surfaceCount(); ++s)
    c.surfaces.emplace_back(world.surfaceName(s));
  c.triangleSurfaces.assign(world.triangleSurfaces().begin(), world.triangleSurfaces().end());
  return c;
}

Content contentOf(const Blob& blob) {
  const test::AlignedBytes bytes(blob);
  const OpenResult opened = viewWorld(bytes.span());
  REQUIRE(opened.message == "");
  REQUIRE(opened);
  return contentOf(*opened.world);  // copies everything out before `bytes` dies
}

Blob serialize(const Content& c) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.ForceDefaults(true);
  const auto build = schema::CreateBuildInfo(fbb, fbb.CreateString(c.compilerVersion));
  const auto vertices = fbb.CreateVectorOfStructs(c.vertices);
  const auto triangles = fbb.CreateVectorOfStructs(c.triangles);
  const auto planes = fbb.CreateVectorOfStructs(c.planes);
  const auto nodes = fbb.CreateVectorOfStructs(c.nodes);
  const auto leaves = fbb.CreateVectorOfStructs(c.leaves);
  const auto leafTriangles = c.omitLeafTriangles
                                 ? flatbuffers::Offset<flatbuffers::Vector<std::uint32_t>>()
                                 : fbb.CreateVector(c.leafTriangles);
  const auto leafBounds =
      c.omitLeafBounds
          ? flatbuffers::Offset<flatbuffers::Vector<const schema::Box*>>()
          : fbb.CreateVectorOfStructs(c.leafBounds.empty() ? leafBoundsOf(c) : c.leafBounds);
  using Names = flatbuffers::Offset<flatbuffers::Vector<flatbuffers::Offset<flatbuffers::String>>>;
  const auto names = c.omitSurfaces
                         ? Names()
                         : fbb.CreateVectorOfStrings(c.surfaces.empty() && !c.emptySurfaceTable
                                                         ? std::vector<std::string>{"default"}
                                                         : c.surfaces);
  const auto ids = c.omitSurfaces
                       ? flatbuffers::Offset<flatbuffers::Vector<std::uint16_t>>()
                       : fbb.CreateVector(c.triangleSurfaces.empty()
                                              ? std::vector<std::uint16_t>(c.triangles.size())
                                              : c.triangleSurfaces);
  const auto world = schema::CreateWorld(
      fbb, c.formatVersion, c.metresPerUnit, c.upAxis, &c.boundsMin, &c.boundsMax, build, vertices,
      triangles, planes, nodes, leaves, leafTriangles, c.root, c.treeDepth, leafBounds, names, ids);
  fbb.FinishSizePrefixed(world, kFileIdentifier);
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

schema::Plane unitPlane(float x, float y, float z, float distance) {
  return schema::Plane(schema::Vec3(x, y, z), distance);
}

/// The planes bspc computes for these triangles (the loader checks them
/// against the corners).
std::vector<schema::TrianglePlanes> planesOf(const std::vector<schema::Vec3>& vertices,
                                             const std::vector<schema::Triangle>& triangles) {
  bspc::Mesh mesh;
  for (const schema::Vec3& v : vertices) mesh.vertices.emplace_back(v.x(), v.y(), v.z());
  for (const schema::Triangle& t : triangles) mesh.triangles.push_back({t.v0(), t.v1(), t.v2()});
  return bspc::computeTrianglePlanes(mesh);
}

/// One triangle; a chain of `chainNodes` nodes, each with a leaf on its back
/// and the next node (or, for the last, one more leaf) on its front. The
/// deepest leaf is at depth `chainNodes`. Every leaf lists triangle 0.
Content handMadeChain(std::uint32_t chainNodes) {
  Content c;
  c.boundsMin = schema::Vec3(0, 0, 0);
  c.boundsMax = schema::Vec3(1, 0, 1);
  c.vertices = {schema::Vec3(0, 0, 0), schema::Vec3(0, 0, 1), schema::Vec3(1, 0, 0)};
  c.triangles = {schema::Triangle(0, 1, 2)};
  c.planes = planesOf(c.vertices, c.triangles);
  c.leafTriangles = {0};
  for (std::uint32_t i = 0; i < chainNodes; ++i) {
    const bool last = i + 1 == chainNodes;
    const auto front = last ? -std::int32_t(chainNodes) - 1 : std::int32_t(i + 1);
    c.nodes.emplace_back(unitPlane(1, 0, 0, float(i)), front, -std::int32_t(i) - 1);
  }
  c.leaves.assign(chainNodes + 1, schema::Leaf(0, 1));
  c.root = chainNodes == 0 ? -1 : 0;
  c.treeDepth = chainNodes;
  return c;
}

// ---------------------------------------------------------------------------
// Walking an opened World, touching every byte a query could.

template <typename T>
bool inside(std::span<const T> part, std::span<const std::byte> whole) {
  const auto* first = reinterpret_cast<const std::byte*>(part.data());
  const auto* last = first + part.size_bytes();
  return part.empty() || (first >= whole.data() && last <= whole.data() + whole.size());
}

/// Empty when every span lies in the blob, every child reference, leaf range,
/// triangle index and vertex index is in range and every vertex is finite;
/// else what is wrong.
std::string walkProblem(const World& w) {
  const auto bytes = w.bytes();
  if (!inside(w.vertices(), bytes) || !inside(w.triangles(), bytes) ||
      !inside(w.trianglePlanes(), bytes) || !inside(w.nodes(), bytes) ||
      !inside(w.leaves(), bytes) || !inside(w.leafTriangles(), bytes))
    return "a span lies outside the blob";
  if (w.trianglePlanes().size() != w.triangles().size()) return "planes not parallel";
  if (w.treeDepth() > kMaxTreeDepth) return "tree too deep";
  const std::size_t nodeCount = w.nodes().size(), leafCount = w.leaves().size();
  struct Pending {
    std::int32_t ref;
    std::uint32_t depth;
  };
  std::vector<Pending> stack{{w.root(), 0}};
  std::size_t visits = 0;
  double sum = 0;
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    if (++visits > nodeCount + leafCount) return "more visits than nodes and leaves";
    if (p.depth > w.treeDepth()) return "a leaf deeper than treeDepth()";
    if (p.ref >= 0) {
      if (std::size_t(p.ref) >= nodeCount) return "node reference out of range";
      const schema::Node& node = w.nodes()[std::size_t(p.ref)];
      sum += node.split().distance();
      stack.push_back({node.front(), p.depth + 1});
      stack.push_back({node.back(), p.depth + 1});
      continue;
    }
    const std::int64_t leaf = -(std::int64_t(p.ref) + 1);
    if (std::size_t(leaf) >= leafCount) return "leaf reference out of range";
    const schema::Leaf& l = w.leaves()[std::size_t(leaf)];
    if (std::uint64_t(l.first()) + l.count() > w.leafTriangles().size())
      return "leaf range past leafTriangles()";
    for (const std::uint32_t t : w.leafTriangleList(std::uint32_t(leaf))) {
      if (t >= w.triangles().size()) return "triangle index out of range";
      const schema::Triangle& tri = w.triangles()[t];
      for (const std::uint32_t v : {tri.v0(), tri.v1(), tri.v2()}) {
        if (v >= w.vertices().size()) return "vertex index out of range";
        const schema::Vec3& p3 = w.vertices()[v];
        if (!std::isfinite(p3.x()) || !std::isfinite(p3.y()) || !std::isfinite(p3.z()))
          return "vertex not finite";
        sum += p3.x() + p3.y() + p3.z();
      }
      sum += w.trianglePlanes()[t].face().distance();
    }
  }
  if (visits != nodeCount + leafCount) return "not every node and leaf reached";
  const TreeStats stats = computeTreeStats(w);
  if (stats.nodes != nodeCount || stats.leaves != leafCount || stats.depthMax != w.treeDepth())
    return "computeTreeStats disagrees";
  if (!std::isfinite(sum)) return "non-finite geometry";
  return "";
}

void requireSameContent(const World& world, const Content& expected) {
  CHECK(world.vertices().size() == expected.vertices.size());
  CHECK(world.triangles().size() == expected.triangles.size());
  CHECK(world.trianglePlanes().size() == expected.planes.size());
  CHECK(world.nodes().size() == expected.nodes.size());
  CHECK(world.leaves().size() == expected.leaves.size());
  CHECK(world.leafTriangles().size() == expected.leafTriangles.size());
  CHECK(world.root() == expected.root);
  CHECK(world.treeDepth() == expected.treeDepth);
}

/// Applies `change` to the tree blob's content, rebuilds it and loads it.
OpenResult loadModified(const std::function<void(Content&)>& change) {
  Content c = contentOf(treeBlob());
  change(c);
  return view(serialize(c));
}

}  // namespace

// ---------------------------------------------------------------------------
// Good blobs.

TEST_CASE("A compiled blob opens from caller bytes, viewed in place with the compiled counts",
          "[runtime][loader]") {
  bspc::CompileReport report;
  const Blob blob = bspc::compileMesh(fourBoxes(), smallLeaves(), "four-boxes", report);
  const test::AlignedBytes bytes(blob);
  const OpenResult opened = viewWorld(bytes.span());
  REQUIRE(opened.status == LoadStatus::Ok);
  REQUIRE(opened);
  CHECK(opened.message.empty());
  const World& world = *opened.world;

  CHECK(world.bytes().data() == bytes.span().data());
  CHECK(world.bytes().size() == blob.size());
  CHECK(inside(world.vertices(), bytes.span()));
  CHECK(inside(world.triangles(), bytes.span()));
  CHECK(inside(world.trianglePlanes(), bytes.span()));
  CHECK(inside(world.nodes(), bytes.span()));
  CHECK(inside(world.leaves(), bytes.span()));
  CHECK(inside(world.leafTriangles(), bytes.span()));

  CHECK(world.vertices().size() == report.clean.outputVertices);
  CHECK(world.vertices().size() == 32);
  CHECK(world.triangles().size() == report.triangles);
  CHECK(world.triangles().size() == 48);
  CHECK(world.trianglePlanes().size() == 48);
  CHECK(world.nodes().size() == report.tree.nodes);
  CHECK(world.nodes().size() >= 3);
  CHECK(world.leaves().size() == report.tree.leaves);
  CHECK(world.leaves().size() == world.nodes().size() + 1);
  CHECK(world.treeDepth() == report.tree.depthMax);
  CHECK(world.root() >= 0);
  CHECK(report.outputBytes == blob.size());
  CHECK(world.blob().format_version() == kFormatVersion);
  CHECK(walkProblem(world) == "");

  const TreeStats stats = computeTreeStats(world);
  CHECK(stats.nodes == report.tree.nodes);
  CHECK(stats.leaves == report.tree.leaves);
  CHECK(stats.depthMax == report.tree.depthMax);
}

TEST_CASE("A compiled blob opens from a file by mmap and the world views the mapping",
          "[runtime][loader]") {
  const fs::path dir = test::freshTempDir("loader-open");
  const fs::path path = dir / "box.bspf";
  writeFile(path, boxBlob());

  OpenResult opened = openWorld(path);
  REQUIRE(opened.status == LoadStatus::Ok);
  REQUIRE(opened);
  const World& world = *opened.world;
  const auto bytes = world.bytes();
  REQUIRE(bytes.size() == boxBlob().size());
  CHECK(std::memcmp(bytes.data(), boxBlob().data(), bytes.size()) == 0);
  // A fresh mapping starts on a page boundary (pages are 4 KiB or a multiple;
  // Windows views start on 64 KiB); a heap copy would not, in general.
  CHECK(reinterpret_cast<std::uintptr_t>(bytes.data()) % 4096 == 0);
  CHECK(inside(world.vertices(), bytes));
  CHECK(inside(world.triangles(), bytes));
  CHECK(inside(world.trianglePlanes(), bytes));
  CHECK(inside(world.nodes(), bytes));
  CHECK(inside(world.leaves(), bytes));
  CHECK(inside(world.leafTriangles(), bytes));
  CHECK(world.vertices().size() == 8);
  CHECK(world.triangles().size() == 12);
  CHECK(walkProblem(world) == "");
  opened.world.reset();  // Windows removes no folder holding a mapped file
  fs::remove_all(dir);
}

/// Opens `path`, which must load, and returns a copy of its World: the
/// OpenResult is gone on return.
World openedWorldOnly(const fs::path& path) {
  const OpenResult opened = openWorld(path);
  REQUIRE(opened);
  return *opened.world;
}

TEST_CASE("A World copy keeps the mapping alive after the result and the file are gone",
          "[runtime][loader]") {
  const fs::path dir = test::freshTempDir("loader-lifetime");
  const fs::path path = dir / "tree.bspf";
  writeFile(path, treeBlob());
  std::optional<World> kept = openedWorldOnly(path);
#ifndef _WIN32
  fs::remove(path);  // Windows may refuse to delete a mapped file (world.h)
#endif
  REQUIRE(kept);
  CHECK(kept->bytes().size() == treeBlob().size());
  CHECK(std::memcmp(kept->bytes().data(), treeBlob().data(), treeBlob().size()) == 0);
  CHECK(walkProblem(*kept) == "");
  kept.reset();
  fs::remove_all(dir);
}

TEST_CASE("A file whose name has non-ASCII characters opens, and messages name it in UTF-8",
          "[runtime][loader]") {
  const fs::path dir = test::freshTempDir("loader-unicode");
  const std::u8string name = u8"niveau-\u00e9t\u00e9-\u6c34.bspf";  // 2- and 3-byte UTF-8
  const fs::path path = dir / name;
  writeFile(path, boxBlob());
  {
    const OpenResult opened = openWorld(path);
    REQUIRE(opened);
    CHECK(opened.world->triangles().size() == 12);
  }
  const fs::path missing = dir / (u8"absent-\u6c34" + name);
  const OpenResult r = openWorld(missing);
  CHECK(r.status == LoadStatus::CannotOpen);
  const std::u8string expected = missing.u8string();
  CHECK_THAT(r.message, Contains(std::string(expected.begin(), expected.end())));
  fs::remove_all(dir);
}

#ifdef _WIN32
TEST_CASE("On Windows, a writer cannot open the file of a live World", "[runtime][loader]") {
  const fs::path dir = test::freshTempDir("loader-share");
  const fs::path path = dir / "box.bspf";
  writeFile(path, boxBlob());
  {
    const World world = openedWorldOnly(path);
    const World copy = world;
    std::ofstream writer(path, std::ios::binary | std::ios::app);
    CHECK_FALSE(writer.is_open());
    std::ifstream reader(path, std::ios::binary);
    CHECK(reader.is_open());
  }  // the file is closed with the last copy
  {
    std::ofstream writer(path, std::ios::binary | std::ios::app);
    CHECK(writer.is_open());
  }
  fs::remove_all(dir);
}
#endif

TEST_CASE("Rebuilding a compiled world's content with the generated builder loads the same world",
          "[runtime][loader]") {
  const Content content = contentOf(treeBlob());
  const Blob rebuilt = serialize(content);
  const test::AlignedBytes bytes(rebuilt);
  const OpenResult opened = viewWorld(bytes.span());
  REQUIRE(opened.message == "");
  REQUIRE(opened);
  requireSameContent(*opened.world, content);
  CHECK(walkProblem(*opened.world) == "");
}

TEST_CASE("A hand-made single-leaf world and a tree exactly kMaxTreeDepth deep load",
          "[runtime][loader]") {
  SECTION("single leaf: root -1, depth 0") {
    const Content c = handMadeChain(0);
    const test::AlignedBytes bytes(serialize(c));
    const OpenResult opened = viewWorld(bytes.span());
    REQUIRE(opened.message == "");
    REQUIRE(opened);
    CHECK(opened.world->root() == -1);
    CHECK(opened.world->treeDepth() == 0);
    CHECK(opened.world->nodes().empty());
    CHECK(opened.world->leafTriangleList(0).size() == 1);
    CHECK(walkProblem(*opened.world) == "");
  }
  SECTION("a chain of kMaxTreeDepth nodes") {
    const Content c = handMadeChain(kMaxTreeDepth);
    const test::AlignedBytes bytes(serialize(c));
    const OpenResult opened = viewWorld(bytes.span());
    REQUIRE(opened.message == "");
    REQUIRE(opened);
    CHECK(opened.world->treeDepth() == kMaxTreeDepth);
    CHECK(walkProblem(*opened.world) == "");
  }
}

// ---------------------------------------------------------------------------
// Truncation, identifier, stray bytes, alignment, files.

TEST_CASE("A blob truncated at every length is Truncated, never a crash", "[runtime][loader]") {
  for (const Blob* blob : {&boxBlob(), &treeBlob()}) {
    std::size_t refused = 0;
    for (std::size_t length = 0; length < blob->size(); ++length) {
      const OpenResult r = view(std::span(*blob).first(length));
      if (r.status == LoadStatus::Truncated && !r.world &&
          r.message.find("<memory>") != std::string::npos) {
        ++refused;
        continue;
      }
      INFO("length " << length << " of " << blob->size() << ": " << toString(r.status) << ": "
                     << r.message);
      CHECK(r.status == LoadStatus::Truncated);
      CHECK_FALSE(r);
      CHECK_THAT(r.message, Contains("<memory>"));
    }
    CHECK(refused == blob->size());
  }
}

TEST_CASE("A truncated file is Truncated and the message names the file", "[runtime][loader]") {
  const fs::path dir = test::freshTempDir("loader-truncated");
  const Blob& blob = treeBlob();
  for (const std::size_t length :
       {std::size_t(0), std::size_t(3), std::size_t(11), std::size_t(12), std::size_t(100),
        blob.size() / 2, blob.size() - 8, blob.size() - 1}) {
    const fs::path path = dir / ("cut-" + std::to_string(length) + ".bspf");
    writeFile(path, std::span(blob).first(length));
    const OpenResult r = openWorld(path);
    INFO("length " << length << ": " << r.message);
    CHECK(r.status == LoadStatus::Truncated);
    CHECK_FALSE(r);
    CHECK_THAT(r.message, Contains(path.string()));
    CHECK_THAT(r.message, Contains("truncated"));
  }
  fs::remove_all(dir);
}

TEST_CASE("A blob with another file identifier is WrongIdentifier", "[runtime][loader]") {
  for (const char* identifier : {"XSPF", "bspf", "\0\0\0\0", "BSP "}) {
    Blob blob = boxBlob();
    std::memcpy(blob.data() + 8, identifier, 4);
    const OpenResult r = view(blob);
    INFO("identifier '" << std::string(identifier, 4) << "': " << r.message);
    CHECK(r.status == LoadStatus::WrongIdentifier);
    CHECK_THAT(r.message, Contains("identifier"));
  }
}

TEST_CASE("A text file (an OBJ) is WrongIdentifier, a tiny one Truncated", "[runtime][loader]") {
  const fs::path obj = test::samplesDir() / "box_room.obj";
  REQUIRE(fs::is_regular_file(obj));
  const OpenResult r = openWorld(obj);
  CHECK(r.status == LoadStatus::WrongIdentifier);
  CHECK_THAT(r.message, Contains(obj.string()));

  const fs::path dir = test::freshTempDir("loader-text");
  const fs::path tiny = dir / "tiny.txt";
  const std::string hello = "hello\n";
  writeFile(tiny, std::span(reinterpret_cast<const std::uint8_t*>(hello.data()), hello.size()));
  const OpenResult t = openWorld(tiny);
  CHECK(t.status == LoadStatus::Truncated);
  CHECK_THAT(t.message, Contains(tiny.string()));
  fs::remove_all(dir);
}

TEST_CASE("A blob of another format version is WrongVersion naming both versions",
          "[runtime][loader]") {
  SECTION("re-serialised with the generated builder") {
    for (const std::uint32_t version : {0u, kFormatVersion + 1, 7u, 0xffffffffu}) {
      Content c = contentOf(boxBlob());
      c.formatVersion = version;
      const OpenResult r = view(serialize(c));
      INFO(r.message);
      CHECK(r.status == LoadStatus::WrongVersion);
      CHECK_THAT(r.message, Contains("version " + std::to_string(version)));
      CHECK_THAT(r.message, Contains("version " + std::to_string(kFormatVersion)));
    }
  }
  SECTION("patched in place through the vtable") {
    Blob blob = boxBlob();
    const std::size_t at = fieldPosition(blob, schema::World::VT_FORMAT_VERSION);
    REQUIRE(readAt<std::uint32_t>(blob, at) == kFormatVersion);
    writeAt<std::uint32_t>(blob, at, 7);
    const OpenResult r = view(blob);
    INFO(r.message);
    CHECK(r.status == LoadStatus::WrongVersion);
    CHECK_THAT(r.message, Contains("version 7"));
    CHECK_THAT(r.message, Contains("version " + std::to_string(kFormatVersion)));
  }
  SECTION("opened from a file, the message names it") {
    Content c = contentOf(boxBlob());
    c.formatVersion = kFormatVersion - 1;  // a blob of the previous bspc
    const fs::path dir = test::freshTempDir("loader-version");
    const fs::path path = dir / "old.bspf";
    writeFile(path, serialize(c));
    const OpenResult r = openWorld(path);
    CHECK(r.status == LoadStatus::WrongVersion);
    CHECK_THAT(r.message, Contains(path.string()));
    fs::remove_all(dir);
  }
}

TEST_CASE("The version is checked before the rest of the layout", "[runtime][loader]") {
  // A future format may lay out its fields differently: the loader must still
  // say "wrong version" rather than "malformed".
  SECTION("a next-version blob whose vertices vector is broken is WrongVersion") {
    Blob blob = boxBlob();
    const std::size_t vertices = fieldPosition(blob, schema::World::VT_VERTICES);
    const std::size_t vector = vertices + readAt<std::uint32_t>(blob, vertices);
    writeAt<std::uint32_t>(blob, vector, 0x7fffffffu);  // element count far past the end
    CHECK(view(blob).status == LoadStatus::Malformed);
    writeAt<std::uint32_t>(blob, fieldPosition(blob, schema::World::VT_FORMAT_VERSION),
                           kFormatVersion + 1);
    CHECK(view(blob).status == LoadStatus::WrongVersion);
  }
  SECTION("a table holding only a version") {
    for (const std::uint32_t version : {kFormatVersion, kFormatVersion + 1}) {
      flatbuffers::FlatBufferBuilder fbb;
      fbb.ForceDefaults(true);
      schema::WorldBuilder builder(fbb);
      builder.add_format_version(version);
      fbb.FinishSizePrefixed(builder.Finish(), kFileIdentifier);
      const OpenResult r =
          view(Blob(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()));
      INFO(r.message);
      if (version == kFormatVersion) {
        CHECK(r.status == LoadStatus::Malformed);
        CHECK_THAT(r.message, Contains("missing"));
      } else {
        CHECK(r.status == LoadStatus::WrongVersion);
      }
    }
  }
}

TEST_CASE("Stray bytes after the blob are Malformed", "[runtime][loader]") {
  for (const std::size_t extra : {1, 3, 8, 100}) {
    Blob blob = boxBlob();
    blob.insert(blob.end(), extra, 0);
    const OpenResult r = view(blob);
    INFO(extra << " extra: " << r.message);
    CHECK(r.status == LoadStatus::Malformed);
    CHECK_THAT(r.message, Contains("stray"));
  }
  SECTION("a size prefix smaller than the blob, likewise") {
    Blob blob = boxBlob();
    writeAt<std::uint32_t>(blob, 0, readAt<std::uint32_t>(blob, 0) - 4);
    CHECK(view(blob).status == LoadStatus::Malformed);
  }
}

TEST_CASE("Caller bytes not 8-byte aligned are Misaligned", "[runtime][loader]") {
  const Blob& blob = boxBlob();
  std::vector<std::uint64_t> storage(blob.size() / 8 + 2);
  auto* base = reinterpret_cast<std::byte*>(storage.data());
  for (std::size_t shift = 1; shift < 8; ++shift) {
    std::memcpy(base + shift, blob.data(), blob.size());
    const OpenResult r = viewWorld({base + shift, blob.size()});
    INFO("shift " << shift << ": " << r.message);
    CHECK(r.status == LoadStatus::Misaligned);
    CHECK_FALSE(r);
    CHECK_THAT(r.message, Contains("aligned"));
    // Alignment is checked first, whatever else is wrong.
    CHECK(viewWorld({base + shift, 5}).status == LoadStatus::Misaligned);
  }
  std::memcpy(base, blob.data(), blob.size());
  CHECK(viewWorld({base, blob.size()}).status == LoadStatus::Ok);
}

TEST_CASE("A missing file or a directory is CannotOpen naming the path", "[runtime][loader]") {
  const fs::path dir = test::freshTempDir("loader-cannot-open");
  const fs::path missing = dir / "no-such-level.bspf";
  const OpenResult m = openWorld(missing);
  CHECK(m.status == LoadStatus::CannotOpen);
  CHECK_FALSE(m);
  CHECK_THAT(m.message, Contains(missing.string()));

  const OpenResult d = openWorld(dir);
  CHECK(d.status == LoadStatus::CannotOpen);
  CHECK_THAT(d.message, Contains(dir.string()));

#ifdef _WIN32
  const char* const device = "NUL";  // the null device, named in every folder
  const bool hasDevice = true;
#else
  const char* const device = "/dev/null";
  const bool hasDevice = fs::exists(device);
#endif
  if (hasDevice) {  // a device, not a regular file
    const OpenResult n = openWorld(device);
    CHECK(n.status == LoadStatus::CannotOpen);
    CHECK_THAT(n.message, Contains(device));
    CHECK_THAT(n.message, Contains("not a regular file"));
  }
  fs::remove_all(dir);
}

TEST_CASE("Empty caller bytes are Truncated", "[runtime][loader]") {
  CHECK(viewWorld({}).status == LoadStatus::Truncated);
}

// ---------------------------------------------------------------------------
// Corruption.

namespace {

/// Loads `bytes` (exact allocation) and judges the outcome: empty if fine.
std::string judge(std::span<const std::uint8_t> bytes, LoadStatus& status) {
  const ExactBytes copy(bytes);
  const OpenResult r = viewWorld(copy.span());
  status = r.status;
  if (r.status == LoadStatus::Ok) {
    if (!r.world) return "Ok without a world";
    if (!r.message.empty()) return "Ok with a message";
    return walkProblem(*r.world);
  }
  if (r.world) return "a world with an error status";
  if (r.message.empty()) return "an error without a message";
  if (r.status == LoadStatus::Misaligned || r.status == LoadStatus::CannotOpen)
    return std::string("impossible status ") + toString(r.status);
  return "";
}

}  // namespace

TEST_CASE("Every single-bit flip of a small blob loads or is refused, never worse",
          "[runtime][loader]") {
  const Blob& original = treeBlob();
  // Every bit of the blob, except that of the triangle planes (two thirds of
  // the bytes, 48 alike records) only the first two records are flipped.
  constexpr std::size_t kRecord = sizeof(schema::TrianglePlanes);
  const std::size_t planeCount = contentOf(original).planes.size();
  REQUIRE(planeCount > 2);
  const std::size_t planesField = fieldPosition(original, schema::World::VT_TRIANGLE_PLANES);
  const std::size_t planesVector = planesField + readAt<std::uint32_t>(original, planesField);
  REQUIRE(readAt<std::uint32_t>(original, planesVector) == planeCount);
  const std::size_t planesBegin = planesVector + 4 + 2 * kRecord;
  const std::size_t planesEnd = planesVector + 4 + planeCount * kRecord;
  REQUIRE(planesEnd <= original.size());

  std::vector<std::size_t> byStatus(std::size(kAllStatuses));
  Blob blob = original;
  std::size_t failures = 0;
  for (std::size_t bit = 0; bit < original.size() * 8; ++bit) {
    if (bit / 8 == planesBegin) bit = planesEnd * 8;
    blob[bit / 8] ^= std::uint8_t(1u << (bit % 8));
    LoadStatus status;
    const std::string problem = judge(blob, status);
    blob[bit / 8] = original[bit / 8];
    ++byStatus[std::size_t(status)];
    if (!problem.empty() && ++failures <= 5) {
      INFO("byte " << bit / 8 << " bit " << bit % 8 << ": " << toString(status) << ": " << problem);
      CHECK(problem == "");
    }
  }
  CHECK(failures == 0);
  // The flips reach the interesting paths.
  CHECK(byStatus[std::size_t(LoadStatus::Ok)] > 0);
  CHECK(byStatus[std::size_t(LoadStatus::Malformed)] > 0);
  CHECK(byStatus[std::size_t(LoadStatus::Truncated)] > 0);
  CHECK(byStatus[std::size_t(LoadStatus::WrongIdentifier)] > 0);
  CHECK(byStatus[std::size_t(LoadStatus::WrongVersion)] > 0);
}

TEST_CASE("Thousands of random multi-bit corruptions load or are refused, never worse",
          "[runtime][loader]") {
  const Blob& original = treeBlob();
  std::mt19937 rng(20240517);
  std::uniform_int_distribution<std::size_t> position(0, original.size() - 1);
  std::uniform_int_distribution<int> flips(2, 16), bitIndex(0, 7), byteValue(0, 255), mode(0, 2);
  std::size_t failures = 0, ok = 0;
  constexpr int kTrials = 20000;
  for (int trial = 0; trial < kTrials; ++trial) {
    Blob blob = original;
    const int n = flips(rng);
    const int m = mode(rng);
    for (int i = 0; i < n; ++i) {
      const std::size_t at = position(rng);
      if (m == 0)
        blob[at] ^= std::uint8_t(1u << bitIndex(rng));
      else if (m == 1)
        blob[at] = std::uint8_t(byteValue(rng));
      else if (at / 4 * 4 + 4 <= blob.size()) {
        // An aligned 32-bit word set to a boundary value (offsets, counts, indices).
        constexpr std::uint32_t kBoundary[] = {0u,          1u,          0x7fffffffu,
                                               0x80000000u, 0xffffffffu, 0xfffffff0u};
        std::memcpy(blob.data() + at / 4 * 4, &kBoundary[at % 6], 4);
      }
    }
    LoadStatus status;
    const std::string problem = judge(blob, status);
    ok += status == LoadStatus::Ok;
    if (!problem.empty() && ++failures <= 5) {
      INFO("trial " << trial << ": " << toString(status) << ": " << problem);
      CHECK(problem == "");
    }
  }
  CHECK(failures == 0);
  CHECK(ok > 0);
  CHECK(ok < std::size_t(kTrials));
}

// ---------------------------------------------------------------------------
// Semantic checks: blobs that FlatBuffers verifies but that break a rule.

namespace {

// `planes` with its face normal replaced (distance, edges and caps kept).
schema::TrianglePlanes withFaceNormal(const schema::TrianglePlanes& planes,
                                      const schema::Vec3& normal) {
  return schema::TrianglePlanes(
      schema::Plane(normal, planes.face().distance()),
      flatbuffers::span<const schema::Plane, 3>(planes.edges()->data(), 3),
      flatbuffers::span<const schema::Plane, 3>(planes.caps()->data(), 3), planes.meetable());
}

schema::TrianglePlanes withMeetable(const schema::TrianglePlanes& planes, std::uint8_t meetable) {
  return schema::TrianglePlanes(
      planes.face(), flatbuffers::span<const schema::Plane, 3>(planes.edges()->data(), 3),
      flatbuffers::span<const schema::Plane, 3>(planes.caps()->data(), 3), meetable);
}

}  // namespace

TEST_CASE("Semantic violations are Malformed with a message saying what is wrong",
          "[runtime][loader]") {
  struct Case {
    const char* name;
    std::function<void(Content&)> change;
    const char* expected;  // in the message
  };
  const std::vector<Case> cases{
      {"leaf triangle index out of range",
       [](Content& c) { c.leafTriangles.back() = std::uint32_t(c.triangles.size()); },
       "leaf triangle entry"},
      {"triangle vertex index out of range",
       [](Content& c) {
         c.triangles[5] = schema::Triangle(0, std::uint32_t(c.vertices.size()), 1);
       },
       "triangle 5 has a vertex index out of range"},
      {"triangle first vertex index out of range",
       [](Content& c) {
         c.triangles[3] = schema::Triangle(std::uint32_t(c.vertices.size()), 0, 1);
       },
       "triangle 3 has a vertex index out of range"},
      {"triangle third vertex index out of range",
       [](Content& c) {
         c.triangles[7] = schema::Triangle(0, 1, std::uint32_t(c.vertices.size()) + 10);
       },
       "triangle 7 has a vertex index out of range"},
      {"a face normal 0.2% too long",
       [](Content& c) { c.planes[2] = withFaceNormal(c.planes[2], schema::Vec3(0, 1.002f, 0)); },
       "face plane of triangle 2 has a normal not of unit length"},
      {"a meetable bit beyond the six planes",
       [](Content& c) { c.planes[4] = withMeetable(c.planes[4], 0b1000000); },
       "meetable planes of triangle 4 set a bit beyond the six planes"},
      {"a face normal 0.2% too short",
       [](Content& c) { c.planes[2] = withFaceNormal(c.planes[2], schema::Vec3(0.998f, 0, 0)); },
       "face plane of triangle 2 has a normal not of unit length"},
      {"node 0's child points to node 0",
       [](Content& c) {
         REQUIRE(c.root == 0);
         const schema::Node n = c.nodes[0];
         c.nodes[0] = schema::Node(n.split(), 0, n.back());
       },
       "not a tree"},
      {"a node referenced twice",
       [](Content& c) {
         for (schema::Node& n : c.nodes)
           if (n.front() > 0) {
             n = schema::Node(n.split(), n.front(), n.front());
             return;
           }
         FAIL("no node has a node child");
       },
       "a node is referenced twice"},
      {"a leaf referenced twice",
       [](Content& c) {
         for (schema::Node& n : c.nodes)
           if (n.front() < 0) {
             n = schema::Node(n.split(), n.front(), n.front());
             return;
           }
         FAIL("no node has a leaf child");
       },
       "a leaf is referenced twice"},
      {"a child reference past the nodes",
       [](Content& c) {
         const schema::Node n = c.nodes[0];
         c.nodes[0] = schema::Node(n.split(), std::int32_t(c.nodes.size()), n.back());
       },
       "out of range"},
      {"a child reference past the leaves",
       [](Content& c) {
         const schema::Node n = c.nodes[0];
         c.nodes[0] = schema::Node(n.split(), n.front(), -std::int32_t(c.leaves.size()) - 1);
       },
       "out of range"},
      {"the root past the nodes", [](Content& c) { c.root = std::int32_t(c.nodes.size()); },
       "out of range"},
      {"the most negative root",
       [](Content& c) { c.root = std::numeric_limits<std::int32_t>::min(); }, "out of range"},
      {"an unreachable leaf", [](Content& c) { c.leaves.emplace_back(0, 0); }, "not reachable"},
      {"a leaf listing triangles past the end",
       [](Content& c) { c.leaves[0] = schema::Leaf(std::uint32_t(c.leafTriangles.size()), 1); },
       "leaf 0 lists triangles past the end"},
      {"a leaf range that wraps around 32 bits",
       [](Content& c) { c.leaves[1] = schema::Leaf(1, 0xffffffffu); },
       "leaf 1 lists triangles past the end"},
      {"a NaN vertex",
       [](Content& c) {
         c.vertices[3] = schema::Vec3(0, std::numeric_limits<float>::quiet_NaN(), 0);
       },
       "vertex 3 is not finite"},
      {"an infinite vertex",
       [](Content& c) {
         c.vertices[0] = schema::Vec3(std::numeric_limits<float>::infinity(), 0, 0);
       },
       "vertex 0 is not finite"},
      {"a non-unit face normal",
       [](Content& c) { c.planes[2] = withFaceNormal(c.planes[2], schema::Vec3(0, 2, 0)); },
       "face plane of triangle 2 has a normal not of unit length"},
      {"a non-unit edge normal",
       [](Content& c) {
         const schema::TrianglePlanes& p = c.planes[4];
         schema::Plane edges[3] = {*p.edges()->Get(0), *p.edges()->Get(1), *p.edges()->Get(2)};
         edges[1] = schema::Plane(schema::Vec3(0.5f, 0, 0), edges[1].distance());
         c.planes[4] = schema::TrianglePlanes(
             p.face(), flatbuffers::span<const schema::Plane, 3>(edges),
             flatbuffers::span<const schema::Plane, 3>(p.caps()->data(), 3), p.meetable());
       },
       "edge plane of triangle 4 has a normal not of unit length"},
      {"a zero cap normal",
       [](Content& c) {
         const schema::TrianglePlanes& p = c.planes[0];
         schema::Plane caps[3] = {*p.caps()->Get(0), *p.caps()->Get(1), *p.caps()->Get(2)};
         caps[2] = schema::Plane(schema::Vec3(0, 0, 0), 0);
         c.planes[0] = schema::TrianglePlanes(
             p.face(), flatbuffers::span<const schema::Plane, 3>(p.edges()->data(), 3),
             flatbuffers::span<const schema::Plane, 3>(caps), p.meetable());
       },
       "cap plane of triangle 0 has a normal not of unit length"},
      {"a NaN plane distance",
       [](Content& c) {
         const schema::TrianglePlanes& p = c.planes[1];
         const schema::Plane face(p.face().normal(), std::numeric_limits<float>::quiet_NaN());
         c.planes[1] = schema::TrianglePlanes(
             face, flatbuffers::span<const schema::Plane, 3>(p.edges()->data(), 3),
             flatbuffers::span<const schema::Plane, 3>(p.caps()->data(), 3), p.meetable());
       },
       "face plane of triangle 1 has a non-finite value"},
      {"a non-unit split normal",
       [](Content& c) {
         const schema::Node n = c.nodes[1];
         c.nodes[1] = schema::Node(schema::Plane(schema::Vec3(1, 1, 0), n.split().distance()),
                                   n.front(), n.back());
       },
       "split plane of node 1"},
      {"triangle_planes shorter than triangles", [](Content& c) { c.planes.pop_back(); },
       "triangle_planes and triangles differ in length"},
      {"triangle_planes longer than triangles",
       [](Content& c) { c.planes.push_back(c.planes.front()); },
       "triangle_planes and triangles differ in length"},
      {"a missing surface table and triangle_surfaces", [](Content& c) { c.omitSurfaces = true; },
       "surface table or triangle_surfaces is missing"},
      {"an empty surface table",
       [](Content& c) {
         c.surfaces.clear();
         c.emptySurfaceTable = true;
       },
       "the surface table has 0 names"},
      {"triangle_surfaces shorter than triangles",
       [](Content& c) { c.triangleSurfaces.assign(c.triangles.size() - 1, 0); },
       "triangle_surfaces and triangles differ in length"},
      {"a surface id one past the table",
       [](Content& c) {
         c.surfaces = {"a", "b"};
         c.triangleSurfaces.assign(c.triangles.size(), 1);
         c.triangleSurfaces[3] = 2;
       },
       "triangle 3 has a surface id out of range"},
      {"no triangles",
       [](Content& c) {
         c.triangles.clear();
         c.planes.clear();
       },
       "no triangles"},
      {"a missing leaf_triangles vector", [](Content& c) { c.omitLeafTriangles = true; },
       "missing"},
      {"a missing leaf_triangle_bounds vector", [](Content& c) { c.omitLeafBounds = true; },
       "missing"},
      {"leaf_triangle_bounds shorter than leaf_triangles",
       [](Content& c) { c.leafBounds.pop_back(); },
       "leaf_triangle_bounds and leaf_triangles differ in length"},
      {"a leaf entry's box one ulp short of its triangle's highest x",
       [](Content& c) {
         schema::Box& box = c.leafBounds.back();
         const schema::Vec3& high = box.max();
         box = schema::Box(box.min(),
                           schema::Vec3(std::nextafter(high.x(), -1e30f), high.y(), high.z()));
       },
       "bounding box of leaf triangle entry"},
      {"a leaf entry's box one ulp above its triangle's lowest y",
       [](Content& c) {
         schema::Box& box = c.leafBounds.front();
         const schema::Vec3& low = box.min();
         box =
             schema::Box(schema::Vec3(low.x(), std::nextafter(low.y(), 1e30f), low.z()), box.max());
       },
       "bounding box of leaf triangle entry 0"},
      {"a leaf entry's box one ulp short of its triangle's highest z",
       [](Content& c) {
         schema::Box& box = c.leafBounds[c.leafBounds.size() / 2];
         const schema::Vec3& high = box.max();
         box = schema::Box(box.min(),
                           schema::Vec3(high.x(), high.y(), std::nextafter(high.z(), -1e30f)));
       },
       "bounding box of leaf triangle entry"},
      {"a leaf entry's box one ulp above its triangle's lowest z",
       [](Content& c) {
         schema::Box& box = c.leafBounds.front();
         const schema::Vec3& low = box.min();
         box =
             schema::Box(schema::Vec3(low.x(), low.y(), std::nextafter(low.z(), 1e30f)), box.max());
       },
       "bounding box of leaf triangle entry 0"},
      {"a NaN in a leaf entry's box",
       [](Content& c) {
         schema::Box& box = c.leafBounds.front();
         box = schema::Box(box.min(), schema::Vec3(std::numeric_limits<float>::quiet_NaN(),
                                                   box.max().y(), box.max().z()));
       },
       "bounding box of leaf triangle entry 0"},
      {"NaN bounds",
       [](Content& c) {
         c.boundsMax = schema::Vec3(1, std::numeric_limits<float>::quiet_NaN(), 1);
       },
       "bounds"},
      // A game querying the level's box (or placing bodies in it) would
      // break a query's precondition with it.
      {"inverted bounds", [](Content& c) { std::swap(c.boundsMin, c.boundsMax); },
       "bounds are inverted"},
      {"units other than metres", [](Content& c) { c.metresPerUnit = 0.0254f; }, "metres"},
      {"Z up", [](Content& c) { c.upAxis = schema::UpAxis::Z; }, "Y up"},
      {"tree_depth disagreeing with the tree", [](Content& c) { c.treeDepth += 1; }, "tree_depth"},
  };
  for (const Case& test : cases) {
    INFO(test.name);
    const OpenResult r = loadModified(test.change);
    INFO(r.message);
    CHECK(r.status == LoadStatus::Malformed);
    CHECK_FALSE(r);
    CHECK_THAT(r.message, Contains("<memory>"));
    CHECK_THAT(r.message, Contains(test.expected));
  }
}

TEST_CASE("A normal within the loader's tolerance (squared length 1 +- 1e-3) loads",
          "[runtime][loader]") {
  // Lengths 1 + 4e-4 and 1 - 4e-4: squared, about 1 +- 8e-4, inside the
  // tolerance; rounding in a compiler must not get a blob refused.
  // The normal keeps its direction (the corners' own), so only its length
  // is off.
  for (const float length : {1.0004f, 0.9996f}) {
    INFO("length " << length);
    const OpenResult r = loadModified([&](Content& c) {
      const schema::Vec3& n = c.planes[2].face().normal();
      c.planes[2] =
          withFaceNormal(c.planes[2], schema::Vec3(n.x() * length, n.y() * length, n.z() * length));
    });
    INFO(r.message);
    CHECK(r.status == LoadStatus::Ok);
  }
}

TEST_CASE("A tree deeper than kMaxTreeDepth is Malformed", "[runtime][loader]") {
  const OpenResult r = view(serialize(handMadeChain(kMaxTreeDepth + 1)));
  INFO(r.message);
  CHECK(r.status == LoadStatus::Malformed);
  CHECK_THAT(r.message, Contains("deeper"));
}

TEST_CASE("A semantic error in a file names the file", "[runtime][loader]") {
  Content c = contentOf(boxBlob());
  c.vertices[0] = schema::Vec3(std::numeric_limits<float>::quiet_NaN(), 0, 0);
  const fs::path dir = test::freshTempDir("loader-semantic");
  const fs::path path = dir / "nan.bspf";
  writeFile(path, serialize(c));
  const OpenResult r = openWorld(path);
  CHECK(r.status == LoadStatus::Malformed);
  CHECK_THAT(r.message, Contains(path.string()));
  CHECK_THAT(r.message, Contains("not finite"));
  fs::remove_all(dir);
}

// ---------------------------------------------------------------------------

TEST_CASE("toString gives a distinct non-empty name for every status", "[runtime][loader]") {
  std::set<std::string> names;
  for (const LoadStatus status : kAllStatuses) {
    const std::string name = toString(status);
    CHECK_FALSE(name.empty());
    CHECK(name != "unknown");
    names.insert(name);
  }
  CHECK(names.size() == std::size(kAllStatuses));
  CHECK(std::string(toString(LoadStatus::Truncated)) == "truncated");
  CHECK(std::string(toString(LoadStatus::WrongVersion)) == "wrong version");
}

}  // namespace bspf
