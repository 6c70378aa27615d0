// Helpers shared by the tests: paths, small meshes, compiled blobs.
#pragma once

#include <bspc/compile.h>
#include <bspc/mesh.h>
#include <bspf/world.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace bspf::test {

inline std::filesystem::path samplesDir() { return BSPF_SAMPLES_DIR; }
/// ../shared/levels beside the project; may be absent on a user's clone.
inline std::filesystem::path sharedLevelsDir() { return BSPF_SHARED_LEVELS_DIR; }
inline std::filesystem::path bspcExecutable() { return BSPC_EXECUTABLE; }

/// The six shared levels, smallest first.
inline const std::vector<std::string>& sharedLevelNames() {
  static const std::vector<std::string> names{"fan",    "oa_dm1", "oacmpdm5",
                                              "oa_dm4", "oa_dm5", "oacmpctf3"};
  return names;
}

/// Bytes with 8-byte alignment, as viewWorld requires.
class AlignedBytes {
 public:
  explicit AlignedBytes(std::span<const std::uint8_t> bytes)
      : storage_((bytes.size() + 7) / 8 + 1), size_(bytes.size()) {
    std::memcpy(storage_.data(), bytes.data(), bytes.size());
  }
  std::span<const std::byte> span() const {
    return {reinterpret_cast<const std::byte*>(storage_.data()), size_};
  }
  std::uint8_t* data() { return reinterpret_cast<std::uint8_t*>(storage_.data()); }
  std::size_t size() const { return size_; }

 private:
  std::vector<std::uint64_t> storage_;
  std::size_t size_;
};

/// An axis-aligned box as a closed mesh, 12 triangles facing out.
bspc::Mesh boxMesh(const Eigen::Vector3d& low, const Eigen::Vector3d& high);

/// Appends `part` to `mesh` (vertices not shared).
void append(bspc::Mesh& mesh, const bspc::Mesh& part);

/// Compiles a mesh in memory with default settings (or `settings`).
std::vector<std::uint8_t> compile(const bspc::Mesh& mesh,
                                  const bspc::CompileSettings& settings = {});

/// A mesh compiled in memory, kept alive with its World.
struct CompiledMesh {
  AlignedBytes bytes;
  bspf::World world;
  explicit CompiledMesh(const bspc::Mesh& mesh)
      : bytes(compile(mesh)), world(*bspf::viewWorld(bytes.span()).world) {}
};

/// Compiles samples/NAME.obj with default settings into a temp directory
/// and opens it (the World keeps its mapping alive).
bspf::World compileSample(const std::string& name);

/// A fresh empty directory under the system temp dir, removed by the caller
/// when it likes (tests leave it for post-mortems).
std::filesystem::path freshTempDir(const std::string& tag);

/// Runs a shell command; returns its exit status and stderr.
struct CommandResult {
  int status = -1;
  std::string out, err;
};
CommandResult run(const std::string& command);

}  // namespace bspf::test

/// In a Catch2 test: returns from the test, with a warning, when
/// ../shared/levels is absent (a user's clone has none).
#define BSPF_SKIP_WITHOUT_SHARED_LEVELS()                                  \
  do {                                                                     \
    if (!std::filesystem::exists(bspf::test::sharedLevelsDir())) {         \
      WARN("skipped: " << bspf::test::sharedLevelsDir()                    \
                       << " is absent (a user's clone has no ../shared)"); \
      return;                                                              \
    }                                                                      \
  } while (false)
