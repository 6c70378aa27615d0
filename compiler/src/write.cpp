#include <bspc/write.h>
#include <bspf/world.h>
#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <limits>

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
  flatbuffers::FlatBufferBuilder fbb(1024 + mesh.triangles.size() * 160);
  fbb.ForceDefaults(true);
  const CleanReport& clean = metadata.clean;
  const auto build = fb::CreateBuildInfo(
      fbb, fbb.CreateString("bspc " BSPF_VERSION),
      fbb.CreateString(describeOptions(metadata.settings)), fbb.CreateString(metadata.sourceFile),
      toSchema(metadata.settings.import.up), static_cast<float>(metadata.settings.import.scale),
      clean.inputTriangles, clean.inputVertices, clean.weldedVertices, clean.droppedDegenerate,
      clean.droppedZeroArea, clean.droppedDuplicate, metadata.settings.tree.maxLeafTriangles,
      metadata.settings.tree.maxDepth);
  const fb::Vec3 boundsMin(low.x(), low.y(), low.z());
  const fb::Vec3 boundsMax(high.x(), high.y(), high.z());
  const auto world =
      fb::CreateWorld(fbb, bspf::kFormatVersion, 1.0f, fb::UpAxis::Y, &boundsMin, &boundsMax, build,
                      fbb.CreateVectorOfStructs(vertices), fbb.CreateVectorOfStructs(triangles),
                      fbb.CreateVectorOfStructs(planes), fbb.CreateVectorOfStructs(tree.nodes),
                      fbb.CreateVectorOfStructs(tree.leaves), fbb.CreateVector(tree.leafTriangles),
                      tree.root, tree.depth, fbb.CreateVectorOfStructs(leafBounds));
  fbb.FinishSizePrefixed(world, bspf::kFileIdentifier);
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

void writeFileAtomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  const std::filesystem::path temporary =
      path.parent_path() / ("." + path.filename().string() + ".tmp-" + std::to_string(::getpid()));
  auto fail = [&](const std::string& why) {
    ::unlink(temporary.c_str());
    throw CompileError("cannot write " + path.string() + ": " + why);
  };
  const int fd = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw CompileError("cannot write " + path.string() + ": " + std::strerror(errno));
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t n = ::write(fd, bytes.data() + done, bytes.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(fd);
      fail(n < 0 ? std::strerror(error) : "short write");
    }
    done += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const int error = errno;
    ::close(fd);
    fail(std::strerror(error));
  }
  if (::close(fd) != 0) fail(std::strerror(errno));
  if (::rename(temporary.c_str(), path.c_str()) != 0) fail(std::strerror(errno));
}

}  // namespace bspc
