// SPDX-License-Identifier: MIT
#include <bspf/world.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <atomic>
#include <cassert>
#include <cmath>
#include <cstring>
#include <vector>

#include "mapped_file.h"

static_assert(FLATBUFFERS_LITTLEENDIAN, "the runtime reads the blob in place: little-endian only");

namespace bspf {

const char* toString(LoadStatus status) {
  switch (status) {
    case LoadStatus::Ok: return "ok";
    case LoadStatus::CannotOpen: return "cannot open";
    case LoadStatus::Truncated: return "truncated";
    case LoadStatus::WrongIdentifier: return "wrong identifier";
    case LoadStatus::WrongVersion: return "wrong version";
    case LoadStatus::Malformed: return "malformed";
    case LoadStatus::Misaligned: return "misaligned";
  }
  return "unknown";
}

std::span<const std::uint32_t> World::leafTriangleList(std::uint32_t leafIndex) const {
  const schema::Leaf& leaf = leaves_[leafIndex];
  return leafTriangles_.subspan(leaf.first(), leaf.count());
}

std::uint32_t World::triangleSurface(std::uint32_t triangle) const {
  assert(triangle < triangleSurfaces_.size());
  return triangleSurfaces_[triangle];
}

std::string_view World::surfaceName(std::uint32_t surface) const {
  assert(surface < surfaceCount_);
  return root_table_->surfaces()->Get(surface)->string_view();
}

std::optional<std::uint32_t> World::findSurface(std::string_view name) const {
  const auto* names = root_table_->surfaces();
  for (std::uint32_t i = 0; i < surfaceCount_; ++i)
    if (names->Get(i)->string_view() == name) return i;
  return std::nullopt;
}

struct WorldAccess {
  static void set(World& w, std::shared_ptr<const void> owner, std::span<const std::byte> bytes,
                  const schema::World* table, std::uint32_t depth) {
    static std::atomic<std::uint64_t> lastId{0};
    w.id_ = ++lastId;
    w.owner_ = std::move(owner);
    w.bytes_ = bytes;
    w.root_table_ = table;
    w.treeDepth_ = depth;
    w.root_ = table->root();
    w.vertices_ = structs(table->vertices());
    w.triangles_ = structs(table->triangles());
    w.planes_ = structs(table->triangle_planes());
    w.nodes_ = structs(table->nodes());
    w.leaves_ = structs(table->leaves());
    const auto* lt = table->leaf_triangles();
    w.leafTriangles_ = {lt->data(), lt->size()};
    w.leafTriangleBounds_ = structs(table->leaf_triangle_bounds());
    const auto* surfaces = table->triangle_surfaces();
    w.triangleSurfaces_ = {surfaces->data(), surfaces->size()};
    w.surfaceCount_ = table->surfaces()->size();
  }
  template <typename T>
  static std::span<const T> structs(const flatbuffers::Vector<const T*>* v) {
    return {reinterpret_cast<const T*>(v->Data()), v->size()};
  }
};

namespace {

constexpr std::size_t kPrefixBytes = sizeof(flatbuffers::uoffset_t);
// Size prefix, root offset and file identifier.
constexpr std::size_t kHeaderBytes = kPrefixBytes + sizeof(flatbuffers::uoffset_t) + 4;

class Checker {
 public:
  explicit Checker(std::string& message) : message_(message) {}

  bool fail(std::string what) {
    message_ = std::move(what);
    return false;
  }

  static bool finite(const schema::Vec3& v) {
    return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
  }

  bool plane(const schema::Plane& p, const char* what, std::size_t index) {
    const schema::Vec3& n = p.normal();
    if (!finite(n) || !std::isfinite(p.distance()))
      return fail(std::string(what) + " " + std::to_string(index) + " has a non-finite value");
    const double len2 = double(n.x()) * n.x() + double(n.y()) * n.y() + double(n.z()) * n.z();
    if (std::abs(len2 - 1.0) > 1e-3)
      return fail(std::string(what) + " " + std::to_string(index) +
                  " has a normal not of unit length");
    return true;
  }

 private:
  std::string& message_;
};

bool checkGeometry(const schema::World& w, Checker& check) {
  const auto* vertices = w.vertices();
  const auto* triangles = w.triangles();
  const auto* planes = w.triangle_planes();
  if (!vertices || !triangles || !planes || !w.nodes() || !w.leaves() || !w.leaf_triangles() ||
      !w.leaf_triangle_bounds())
    return check.fail("a required vector is missing");
  if (!w.bounds_min() || !w.bounds_max() || !Checker::finite(*w.bounds_min()) ||
      !Checker::finite(*w.bounds_max()))
    return check.fail("bounds are missing or not finite");
  const schema::Vec3 &low = *w.bounds_min(), &high = *w.bounds_max();
  if (!(low.x() <= high.x() && low.y() <= high.y() && low.z() <= high.z()))
    return check.fail("bounds are inverted (bounds_min above bounds_max on an axis)");
  if (w.metres_per_unit() != 1.0f || w.up_axis() != schema::UpAxis::Y)
    return check.fail("units are not metres with Y up");
  if (triangles->size() == 0) return check.fail("no triangles");
  for (flatbuffers::uoffset_t i = 0; i < vertices->size(); ++i)
    if (!Checker::finite(*vertices->Get(i)))
      return check.fail("vertex " + std::to_string(i) + " is not finite");
  const auto vertexCount = vertices->size();
  for (flatbuffers::uoffset_t i = 0; i < triangles->size(); ++i) {
    const schema::Triangle& t = *triangles->Get(i);
    if (t.v0() >= vertexCount || t.v1() >= vertexCount || t.v2() >= vertexCount)
      return check.fail("triangle " + std::to_string(i) + " has a vertex index out of range");
  }
  if (planes->size() != triangles->size())
    return check.fail("triangle_planes and triangles differ in length");
  for (flatbuffers::uoffset_t i = 0; i < planes->size(); ++i) {
    const schema::TrianglePlanes& p = *planes->Get(i);
    if (!check.plane(p.face(), "face plane of triangle", i)) return false;
    if (p.meetable() >= 64)
      return check.fail("meetable planes of triangle " + std::to_string(i) +
                        " set a bit beyond the six planes");
    for (int k = 0; k < 3; ++k)
      if (!check.plane(*p.edges()->Get(k), "edge plane of triangle", i) ||
          !check.plane(*p.caps()->Get(k), "cap plane of triangle", i))
        return false;
  }
  return true;
}

// The surface table and each triangle's id into it (docs/format.md,
// "Surfaces"). Ids are 16-bit: a table of more than 65536 names could never
// be used in full.
bool checkSurfaces(const schema::World& w, Checker& check) {
  const auto* names = w.surfaces();
  const auto* ids = w.triangle_surfaces();
  if (!names || !ids) return check.fail("the surface table or triangle_surfaces is missing");
  if (names->size() == 0 || names->size() > 65536)
    return check.fail("the surface table has " + std::to_string(names->size()) +
                      " names (1 to 65536 allowed)");
  if (ids->size() != w.triangles()->size())
    return check.fail("triangle_surfaces and triangles differ in length");
  for (flatbuffers::uoffset_t i = 0; i < names->size(); ++i)
    if (!names->Get(i)) return check.fail("surface name " + std::to_string(i) + " is missing");
  for (flatbuffers::uoffset_t i = 0; i < ids->size(); ++i)
    if (ids->Get(i) >= names->size())
      return check.fail("triangle " + std::to_string(i) + " has a surface id out of range");
  return true;
}

// The node graph must be a tree rooted at `root` that reaches every node and
// every leaf exactly once, no deeper than kMaxTreeDepth.
bool checkTree(const schema::World& w, Checker& check, std::uint32_t& depthOut) {
  const auto* nodes = w.nodes();
  const auto* leaves = w.leaves();
  const auto* leafTriangles = w.leaf_triangles();
  const auto triangleCount = w.triangles()->size();
  const std::int64_t nodeCount = nodes->size();
  const std::int64_t leafCount = leaves->size();

  for (flatbuffers::uoffset_t i = 0; i < leaves->size(); ++i) {
    const schema::Leaf& leaf = *leaves->Get(i);
    if (std::uint64_t(leaf.first()) + leaf.count() > leafTriangles->size())
      return check.fail("leaf " + std::to_string(i) + " lists triangles past the end");
  }
  for (flatbuffers::uoffset_t i = 0; i < leafTriangles->size(); ++i)
    if (leafTriangles->Get(i) >= triangleCount)
      return check.fail("leaf triangle entry " + std::to_string(i) + " is out of range");
  // Queries reject a triangle by its entry's box alone: a box that does not
  // hold the triangle would hide it from every query.
  const auto* bounds = w.leaf_triangle_bounds();
  if (bounds->size() != leafTriangles->size())
    return check.fail("leaf_triangle_bounds and leaf_triangles differ in length");
  for (flatbuffers::uoffset_t i = 0; i < bounds->size(); ++i) {
    const schema::Box& box = *bounds->Get(i);
    const schema::Triangle& t = *w.triangles()->Get(leafTriangles->Get(i));
    bool holds = Checker::finite(box.min()) && Checker::finite(box.max());
    for (const std::uint32_t v : {t.v0(), t.v1(), t.v2()}) {
      const schema::Vec3& p = *w.vertices()->Get(v);
      holds = holds && box.min().x() <= p.x() && p.x() <= box.max().x() && box.min().y() <= p.y() &&
              p.y() <= box.max().y() && box.min().z() <= p.z() && p.z() <= box.max().z();
    }
    if (!holds)
      return check.fail("the bounding box of leaf triangle entry " + std::to_string(i) +
                        " does not hold its triangle");
  }
  for (flatbuffers::uoffset_t i = 0; i < nodes->size(); ++i)
    if (!check.plane(nodes->Get(i)->split(), "split plane of node", i)) return false;

  auto validRef = [&](std::int32_t ref) {
    return ref >= 0 ? ref < nodeCount : -(std::int64_t(ref) + 1) < leafCount;
  };
  std::vector<bool> nodeSeen(nodeCount), leafSeen(leafCount);
  struct Pending {
    std::int32_t ref;
    std::uint32_t depth;
  };
  std::vector<Pending> stack{{w.root(), 0}};
  std::int64_t nodesSeen = 0, leavesSeen = 0;
  std::uint32_t depthMax = 0;
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    if (!validRef(p.ref)) return check.fail("a child reference is out of range");
    if (p.depth > kMaxTreeDepth) return check.fail("the tree is deeper than the runtime allows");
    depthMax = std::max(depthMax, p.depth);
    if (p.ref < 0) {
      const auto leaf = static_cast<std::size_t>(-(std::int64_t(p.ref) + 1));
      if (leafSeen[leaf]) return check.fail("a leaf is referenced twice: not a tree");
      leafSeen[leaf] = true;
      ++leavesSeen;
      continue;
    }
    if (nodeSeen[p.ref]) return check.fail("a node is referenced twice: not a tree");
    nodeSeen[p.ref] = true;
    ++nodesSeen;
    const schema::Node& node = *nodes->Get(p.ref);
    stack.push_back({node.front(), p.depth + 1});
    stack.push_back({node.back(), p.depth + 1});
  }
  if (nodesSeen != nodeCount || leavesSeen != leafCount)
    return check.fail("some nodes or leaves are not reachable from the root");
  if (depthMax != w.tree_depth()) return check.fail("tree_depth disagrees with the tree");
  depthOut = depthMax;
  return true;
}

Eigen::Vector3d toDouble(const schema::Vec3& v) { return {v.x(), v.y(), v.z()}; }

bool withinBound(const schema::Vec3& v) {
  return std::abs(v.x()) <= kMaxCoordinate && std::abs(v.y()) <= kMaxCoordinate &&
         std::abs(v.z()) <= kMaxCoordinate;
}

// The largest corner coordinate magnitude, metres, at least 1: the scale of
// the triangle's float rounding.
double roundingScale(const Eigen::Vector3d (&p)[3]) {
  double scale = 1;
  for (const Eigen::Vector3d& v : p) scale = std::max(scale, v.cwiseAbs().maxCoeff());
  return scale;
}

// The seven stored planes against the ones the corners give (the
// construction of docs/format.md, section 3.3): each normal within 1e-3 of
// the corners' (the loader's tolerance for unit length), and each corner the
// plane passes through within 1 mm plus 1e-6 of the rounding scale (bspc's
// float rounding is under a tenth of that at any size up to kMaxCoordinate).
// The planes method slides along these planes: planes of another triangle
// would let bodies through this one or stop them in the open.
const char* disagreeingPlane(const schema::TrianglePlanes& stored, const Eigen::Vector3d (&p)[3]) {
  using V = Eigen::Vector3d;
  const double tolerance = 1e-3 + 1e-6 * roundingScale(p);
  auto agrees = [&](const schema::Plane& plane, const V& normal, const V* on0, const V* on1,
                    const V* on2) {
    const V n = toDouble(plane.normal());
    if ((n - normal).norm() > 1e-3) return false;
    for (const V* q : {on0, on1, on2})
      if (q && std::abs(n.dot(*q) - plane.distance()) > tolerance) return false;
    return true;
  };
  const V face = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
  if (!agrees(stored.face(), face, &p[0], &p[1], &p[2])) return "face";
  V edge[3];
  for (int k = 0; k < 3; ++k) edge[k] = face.cross(p[(k + 1) % 3] - p[k]).normalized();
  for (int k = 0; k < 3; ++k) {
    if (!agrees(*stored.edges()->Get(k), edge[k], &p[k], &p[(k + 1) % 3], nullptr)) return "edge";
    if (!agrees(*stored.caps()->Get(k), -edge[(k + 1) % 3], &p[k], nullptr, nullptr)) return "cap";
  }
  return nullptr;
}

// What the step needs beyond a blob that is safe to read: coordinates within
// kMaxCoordinate, usable triangles, and planes that match them.
bool checkStepSafety(const schema::World& w, Checker& check) {
  const auto* vertices = w.vertices();
  for (flatbuffers::uoffset_t i = 0; i < vertices->size(); ++i)
    if (!withinBound(*vertices->Get(i)))
      return check.fail("vertex " + std::to_string(i) + " is beyond the coordinate bound (" +
                        "1e5 m)");
  if (!withinBound(*w.bounds_min()) || !withinBound(*w.bounds_max()))
    return check.fail("bounds are beyond the coordinate bound (1e5 m)");
  const auto* boxes = w.leaf_triangle_bounds();
  for (flatbuffers::uoffset_t i = 0; i < boxes->size(); ++i)
    if (!withinBound(boxes->Get(i)->min()) || !withinBound(boxes->Get(i)->max()))
      return check.fail("the bounding box of leaf triangle entry " + std::to_string(i) +
                        " is beyond the coordinate bound (1e5 m)");
  const auto* nodes = w.nodes();
  for (flatbuffers::uoffset_t i = 0; i < nodes->size(); ++i)
    if (!(std::abs(nodes->Get(i)->split().distance()) <= 2 * kMaxCoordinate))
      return check.fail("split plane of node " + std::to_string(i) +
                        " is beyond the coordinate bound (1e5 m)");
  const auto* triangles = w.triangles();
  for (flatbuffers::uoffset_t i = 0; i < triangles->size(); ++i) {
    const schema::Triangle& t = *triangles->Get(i);
    const schema::Vec3 &a = *vertices->Get(t.v0()), &b = *vertices->Get(t.v1()),
                       &c = *vertices->Get(t.v2());
    if (!isUsableTriangle(a, b, c))
      return check.fail("triangle " + std::to_string(i) +
                        " is degenerate (its corners are on one line, to float precision)");
    const Eigen::Vector3d p[3] = {toDouble(a), toDouble(b), toDouble(c)};
    if (const char* which = disagreeingPlane(*w.triangle_planes()->Get(i), p))
      return check.fail(std::string(which) + " plane of triangle " + std::to_string(i) +
                        " disagrees with its vertices");
  }
  return true;
}

OpenResult refuse(LoadStatus status, const std::string& name, const std::string& why) {
  OpenResult r;
  r.status = status;
  r.message = name + ": " + why;
  return r;
}

OpenResult verifyAndView(std::span<const std::byte> bytes, std::shared_ptr<const void> owner,
                         const std::string& name) {
  const auto* data = reinterpret_cast<const std::uint8_t*>(bytes.data());
  if (reinterpret_cast<std::uintptr_t>(data) % 8 != 0)
    return refuse(LoadStatus::Misaligned, name, "blob bytes are not 8-byte aligned");
  if (bytes.size() < kHeaderBytes)
    return refuse(LoadStatus::Truncated, name,
                  "truncated: " + std::to_string(bytes.size()) + " bytes is too short for a blob");
  if (!flatbuffers::BufferHasIdentifier(data, kFileIdentifier, /*size_prefixed=*/true))
    return refuse(LoadStatus::WrongIdentifier, name, "not a .bspf blob (wrong file identifier)");
  const std::size_t announced = flatbuffers::GetPrefixedSize(data);
  const std::size_t present = bytes.size() - kPrefixBytes;
  if (present < announced)
    return refuse(LoadStatus::Truncated, name,
                  "truncated: " + std::to_string(present) + " of " + std::to_string(announced) +
                      " blob bytes present");
  if (present > announced)
    return refuse(
        LoadStatus::Malformed, name,
        "malformed: " + std::to_string(present - announced) + " stray bytes after the blob");
  if (announced >= FLATBUFFERS_MAX_BUFFER_SIZE)
    return refuse(LoadStatus::Malformed, name, "malformed: larger than a blob can be (2 GiB)");

  const std::uint8_t* body = data + kPrefixBytes;
  // Read the version through a verifier that covers only the root table and
  // that field, so a blob of another layout still gets WrongVersion.
  {
    flatbuffers::Verifier header(body, announced);
    if (!header.VerifyOffset(0))
      return refuse(LoadStatus::Malformed, name, "malformed: bad root offset");
    const auto* table = flatbuffers::GetRoot<flatbuffers::Table>(body);
    if (!table->VerifyTableStart(header) ||
        !table->VerifyField<std::uint32_t>(header, schema::World::VT_FORMAT_VERSION, 4))
      return refuse(LoadStatus::Malformed, name, "malformed: bad root table");
    const auto version = table->GetField<std::uint32_t>(schema::World::VT_FORMAT_VERSION, 0);
    if (version != kFormatVersion)
      return refuse(LoadStatus::WrongVersion, name,
                    "format version " + std::to_string(version) + ", this runtime reads version " +
                        std::to_string(kFormatVersion) +
                        " (recompile the level with a matching bspc)");
  }
  flatbuffers::Verifier verifier(data, bytes.size());
  if (!schema::VerifySizePrefixedWorldBuffer(verifier))
    return refuse(LoadStatus::Malformed, name, "malformed: FlatBuffers verification failed");

  const schema::World* table = schema::GetSizePrefixedWorld(data);
  std::string why;
  Checker check(why);
  std::uint32_t depth = 0;
  if (!checkGeometry(*table, check) || !checkSurfaces(*table, check) ||
      !checkTree(*table, check, depth) || !checkStepSafety(*table, check))
    return refuse(LoadStatus::Malformed, name, "malformed: " + why);

  OpenResult r;
  r.world.emplace();
  WorldAccess::set(*r.world, std::move(owner), bytes, table, depth);
  return r;
}

}  // namespace

bool isUsableTriangle(const schema::Vec3& a, const schema::Vec3& b, const schema::Vec3& c) {
  const Eigen::Vector3d p[3] = {toDouble(a), toDouble(b), toDouble(c)};
  const double longest2 = std::max(
      {(p[1] - p[0]).squaredNorm(), (p[2] - p[1]).squaredNorm(), (p[0] - p[2]).squaredNorm()});
  if (!(longest2 > 0)) return false;
  // Float corners differ by exact doubles, whose cross product is exact
  // enough: the height is the triangle's own, not rounding's.
  const double height = (p[1] - p[0]).cross(p[2] - p[0]).norm() / std::sqrt(longest2);
  constexpr double kFloatStep = 1.0 / (1 << 23);
  return height >= 8 * kFloatStep * roundingScale(p);
}

OpenResult openWorld(const std::filesystem::path& path) {
  // The name in UTF-8 on every system: path::string() would convert a
  // Windows path to the active code page, and throw for a character it lacks.
  const std::u8string utf8 = path.u8string();
  const std::string name(utf8.begin(), utf8.end());
  std::string error;
  std::shared_ptr<detail::MappedFile> file = detail::MappedFile::open(path, error);
  if (!file) return refuse(LoadStatus::CannotOpen, name, "cannot open: " + error);
  const std::span<const std::byte> bytes = file->bytes();
  return verifyAndView(bytes, std::move(file), name);
}

OpenResult viewWorld(std::span<const std::byte> bytes) {
  return verifyAndView(bytes, nullptr, "<memory>");
}

TreeStats computeTreeStats(const World& world) {
  TreeStats s;
  s.nodes = static_cast<std::uint32_t>(world.nodes().size());
  s.leaves = static_cast<std::uint32_t>(world.leaves().size());
  for (const schema::Leaf& leaf : world.leaves()) {
    s.trianglesPerLeafMax = std::max(s.trianglesPerLeafMax, leaf.count());
    s.emptyLeaves += leaf.count() == 0;
  }
  s.trianglesPerLeafMean = double(world.leafTriangles().size()) / s.leaves;
  s.referencesPerTriangle = double(world.leafTriangles().size()) / world.triangles().size();
  s.bytesPerTriangle = double(world.bytes().size()) / world.triangles().size();

  struct Pending {
    std::int32_t ref;
    std::uint32_t depth;
  };
  std::vector<Pending> stack{{world.root(), 0}};
  double depthSum = 0;
  while (!stack.empty()) {
    const Pending p = stack.back();
    stack.pop_back();
    if (p.ref < 0) {
      depthSum += p.depth;
      s.depthMax = std::max(s.depthMax, p.depth);
      continue;
    }
    const schema::Node& node = world.nodes()[p.ref];
    stack.push_back({node.front(), p.depth + 1});
    stack.push_back({node.back(), p.depth + 1});
  }
  s.depthMean = depthSum / s.leaves;
  return s;
}

}  // namespace bspf
