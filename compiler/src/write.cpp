// SPDX-License-Identifier: MIT
#include <bspc/write.h>
#include <bspf/world.h>

#include <charconv>
#include <limits>

// The output files (PendingFile) are POSIX: a Windows build of this library
// (tests/windows) has serializeWorld only.
#ifndef _WIN32
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <climits>
#include <csignal>
#include <cstring>
#include <random>
#endif

#ifndef BSPF_VERSION
#define BSPF_VERSION "unknown"
#endif

namespace bspc {

namespace {

bspf::schema::UpAxis toSchema(UpAxis axis) {
  switch (axis) {
    case UpAxis::X: return bspf::schema::UpAxis::X;
    case UpAxis::Y: return bspf::schema::UpAxis::Y;
    case UpAxis::Z: return bspf::schema::UpAxis::Z;
  }
  return bspf::schema::UpAxis::Y;
}

}  // namespace

std::vector<std::uint8_t> serializeWorld(const Mesh& mesh,
                                         const std::vector<bspf::schema::TrianglePlanes>& planes,
                                         const BspTree& tree, const BlobMetadata& metadata) {
  namespace fb = bspf::schema;
  std::vector<fb::Vec3> vertices;
  vertices.reserve(mesh.vertices.size());
  Eigen::Vector3f low = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
  Eigen::Vector3f high = -low;
  for (const Eigen::Vector3d& v : mesh.vertices) {
    const Eigen::Vector3f f = v.cast<float>();
    vertices.emplace_back(f.x(), f.y(), f.z());
    low = low.cwiseMin(f);
    high = high.cwiseMax(f);
  }
  std::vector<fb::Triangle> triangles;
  triangles.reserve(mesh.triangles.size());
  for (const auto& t : mesh.triangles) triangles.emplace_back(t[0], t[1], t[2]);

  std::vector<fb::Box> leafBounds;
  leafBounds.reserve(tree.leafTriangles.size());
  for (const std::uint32_t t : tree.leafTriangles) {
    // From the float vertices the runtime reads, so the box holds them exactly.
    Eigen::Vector3f boxLow = Eigen::Vector3f::Constant(std::numeric_limits<float>::max());
    Eigen::Vector3f boxHigh = -boxLow;
    for (const std::uint32_t v : mesh.triangles[t]) {
      const Eigen::Vector3f f = mesh.vertices[v].cast<float>();
      boxLow = boxLow.cwiseMin(f);
      boxHigh = boxHigh.cwiseMax(f);
    }
    leafBounds.emplace_back(fb::Vec3(boxLow.x(), boxLow.y(), boxLow.z()),
                            fb::Vec3(boxHigh.x(), boxHigh.y(), boxHigh.z()));
  }
  // The surfaces as cleanMesh left them (a mesh without any: one, the default).
  std::vector<std::uint16_t> triangleSurfaces(mesh.triangles.size(), 0);
  for (std::size_t t = 0; t < mesh.triangleSurfaces.size() && t < triangleSurfaces.size(); ++t)
    triangleSurfaces[t] = static_cast<std::uint16_t>(mesh.triangleSurfaces[t]);
  const std::vector<std::string> surfaceNames =
      mesh.surfaces.empty() ? std::vector<std::string>{kDefaultSurface} : mesh.surfaces;
  flatbuffers::FlatBufferBuilder fbb(1024 + mesh.triangles.size() * 160);
  fbb.ForceDefaults(true);
  const CleanReport& clean = metadata.clean;
  // Every part serialised in its own statement, in one fixed order: as
  // arguments of one call they were serialised in the order the compiler
  // chose (GCC's right to left, clang's left to right), and so were the
  // blob's bytes. The order is GCC's, which wrote every blob before.
  const auto sourceFile = fbb.CreateString(metadata.sourceFile);
  const auto options = fbb.CreateString(describeOptions(metadata.settings));
  const auto version = fbb.CreateString("bspc " BSPF_VERSION);
  const auto build = fb::CreateBuildInfo(
      fbb, version, options, sourceFile, toSchema(metadata.settings.import.up),
      static_cast<float>(metadata.settings.import.scale), clean.inputTriangles, clean.inputVertices,
      clean.weldedVertices, clean.droppedDegenerate, clean.droppedZeroArea, clean.droppedDuplicate,
      metadata.settings.tree.maxLeafTriangles, metadata.settings.tree.maxDepth,
      clean.droppedBySurface);
  const fb::Vec3 boundsMin(low.x(), low.y(), low.z());
  const fb::Vec3 boundsMax(high.x(), high.y(), high.z());
  const auto surfaceIds = fbb.CreateVector(triangleSurfaces);
  const auto surfaceTable = fbb.CreateVectorOfStrings(surfaceNames);
  const auto leafBoxes = fbb.CreateVectorOfStructs(leafBounds);
  const auto leafEntries = fbb.CreateVector(tree.leafTriangles);
  const auto leaves = fbb.CreateVectorOfStructs(tree.leaves);
  const auto nodes = fbb.CreateVectorOfStructs(tree.nodes);
  const auto planeTable = fbb.CreateVectorOfStructs(planes);
  const auto triangleTable = fbb.CreateVectorOfStructs(triangles);
  const auto vertexTable = fbb.CreateVectorOfStructs(vertices);
  const auto world =
      fb::CreateWorld(fbb, bspf::kFormatVersion, 1.0f, fb::UpAxis::Y, &boundsMin, &boundsMax, build,
                      vertexTable, triangleTable, planeTable, nodes, leaves, leafEntries, tree.root,
                      tree.depth, leafBoxes, surfaceTable, surfaceIds);
  fbb.FinishSizePrefixed(world, bspf::kFileIdentifier);
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

std::string toObj(const bspf::World& world, const std::string& header) {
  std::string out = "# " + header + "\n";
  out.reserve(out.size() + world.vertices().size() * 40 + world.triangles().size() * 30);
  char text[64];
  const auto number = [&](float value) {
    // Shortest round trip: the float read back is this float.
    const auto end = std::to_chars(text, text + sizeof text, value).ptr;
    out.append(text, end);
  };
  for (const bspf::schema::Vec3& v : world.vertices()) {
    out += "v ";
    number(v.x());
    out += ' ';
    number(v.y());
    out += ' ';
    number(v.z());
    out += '\n';
  }
  for (const bspf::schema::Triangle& t : world.triangles()) {
    out += 'f';
    for (const std::uint32_t v : {t.v0(), t.v1(), t.v2()}) {
      out += ' ';
      out.append(text, std::to_chars(text, text + sizeof text, std::uint64_t(v) + 1).ptr);
    }
    out += '\n';
  }
  return out;
}

std::uint64_t estimateBlobBytes(std::uint64_t vertices, std::uint64_t triangles,
                                std::uint64_t nodes, std::uint64_t leaves, std::uint64_t entries) {
  namespace fb = bspf::schema;
  // The arrays and their 4-byte lengths; the tables, the size prefix and the
  // build info's strings come on top.
  return 9 * 4 + vertices * sizeof(fb::Vec3) +
         triangles * (sizeof(fb::Triangle) + sizeof(fb::TrianglePlanes) + sizeof(std::uint16_t)) +
         nodes * sizeof(fb::Node) + leaves * sizeof(fb::Leaf) +
         entries * (sizeof(std::uint32_t) + sizeof(fb::Box));
}

#ifndef _WIN32

namespace {

// The temporaries now on disk, for the signal handler: the only global state
// here, fixed-size and lock-free, because a handler may run between any two
// instructions and can use nothing that allocates or locks. A slot is
// claimed (`claimed`), filled, then published (`ready`); the handler reads
// only published slots.
struct TemporarySlot {
  std::atomic<bool> claimed{false};
  std::atomic<bool> ready{false};
  char path[PATH_MAX] = {};
};
constexpr int kTemporarySlots = 8;
TemporarySlot temporarySlots[kTemporarySlots];
static_assert(std::atomic<bool>::is_always_lock_free);

int listTemporary(const std::string& path) {
  if (path.size() >= PATH_MAX) return -1;
  for (int i = 0; i < kTemporarySlots; ++i) {
    bool expected = false;
    if (!temporarySlots[i].claimed.compare_exchange_strong(expected, true)) continue;
    std::memcpy(temporarySlots[i].path, path.c_str(), path.size() + 1);
    temporarySlots[i].ready.store(true);
    return i;
  }
  return -1;  // more files at once than slots: only signal cleanup is lost
}

void unlistTemporary(int slot) {
  if (slot < 0) return;
  temporarySlots[slot].ready.store(false);
  temporarySlots[slot].claimed.store(false);
}

extern "C" void removeTemporariesAndDie(int signal) {
  for (TemporarySlot& slot : temporarySlots)
    if (slot.ready.load()) ::unlink(slot.path);
  ::signal(signal, SIG_DFL);
  ::raise(signal);
}

// 12 characters of 32 possible each from the system's random source: 60 bits
// no other process can guess ahead of time.
std::string randomSuffix() {
  static constexpr char kAlphabet[] = "abcdefghijklmnopqrstuvwxyz234567";
  std::random_device source;
  std::string out;
  for (int i = 0; i < 12; ++i) out += kAlphabet[source() % 32];
  return out;
}

// Empty when `path` is absent or a regular file, else why bspc will not
// replace it.
std::string notReplaceable(const std::filesystem::path& path) {
  struct stat info {};
  if (::lstat(path.c_str(), &info) != 0) return errno == ENOENT ? "" : std::strerror(errno);
  if (S_ISREG(info.st_mode)) return "";
  if (S_ISDIR(info.st_mode)) return "is a directory";
  if (S_ISLNK(info.st_mode))
    return "is a symbolic link (bspc replaces only regular files: name its target)";
  return "is not a regular file (a device, FIFO or socket): bspc replaces only regular files";
}

}  // namespace

PendingFile::PendingFile(const std::filesystem::path& path) : path_(path) {
  if (const std::string why = notReplaceable(path_); !why.empty())
    throw CompileError("cannot write " + path_.string() + ": " + why);
  for (int attempt = 0; attempt < 16; ++attempt) {
    // Appended piece by piece: GCC 12 warns (-Wrestrict, a false positive,
    // its bug 105329) on "." + std::string&& here.
    std::string name = ".";
    name += path_.filename().string();
    name += ".tmp-";
    name += randomSuffix();
    temporary_ = path_.parent_path() / name;
    // Listed before it exists, so a signal never leaves it unlisted.
    slot_ = listTemporary(temporary_.string());
    fd_ = ::open(temporary_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
    if (fd_ >= 0) return;
    const int error = errno;
    unlistTemporary(slot_);
    slot_ = -1;
    if (error != EEXIST)
      throw CompileError("cannot write " + path_.string() + ": " + std::strerror(error));
  }
  throw CompileError("cannot write " + path_.string() + ": no unused temporary file name");
}

PendingFile::~PendingFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temporary_.empty()) ::unlink(temporary_.c_str());
  unlistTemporary(slot_);
}

void PendingFile::fail(const std::string& why) {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  ::unlink(temporary_.c_str());
  temporary_.clear();
  unlistTemporary(slot_);
  slot_ = -1;
  throw CompileError("cannot write " + path_.string() + ": " + why);
}

void PendingFile::write(std::span<const std::uint8_t> bytes) {
  if (fd_ < 0) fail("already closed");
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) fail(n < 0 ? std::strerror(errno) : "short write");
    done += static_cast<std::size_t>(n);
  }
}

void PendingFile::commit() {
  if (fd_ < 0) fail("already closed");
  if (::fsync(fd_) != 0) fail(std::strerror(errno));
  const int fd = fd_;
  fd_ = -1;
  if (::close(fd) != 0) fail(std::strerror(errno));
  // Again: something may have been put there during the compile.
  if (const std::string why = notReplaceable(path_); !why.empty()) fail(why);
  if (::rename(temporary_.c_str(), path_.c_str()) != 0) fail(std::strerror(errno));
  temporary_.clear();
  unlistTemporary(slot_);
  slot_ = -1;
}

void writeFileAtomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  PendingFile file(path);
  file.write(bytes);
  file.commit();
}

void removeTemporariesOnSignal() {
  for (const int signal : {SIGINT, SIGTERM, SIGHUP}) {
    struct sigaction action {};
    action.sa_handler = removeTemporariesAndDie;
    sigemptyset(&action.sa_mask);
    ::sigaction(signal, &action, nullptr);
  }
}

#endif  // _WIN32

}  // namespace bspc
