// SPDX-License-Identifier: MIT
// Helpers shared by the tests: paths, small meshes, compiled blobs.
#pragma once

#include <bspc/compile.h>
#include <bspc/mesh.h>
#include <bspf/geometry.h>
#include <bspf/movement.h>
#include <bspf/world.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <random>
#include <span>
#include <string>
#include <vector>

namespace bspf::test {

inline std::filesystem::path samplesDir() { return BSPF_SAMPLES_DIR; }
/// The real levels: $BSPF_SHARED_LEVELS when set (even to a missing folder,
/// which hides them), else ../shared/levels beside the source tree, else
/// beside the build tree holding this executable. May be absent on a user's
/// clone.
std::filesystem::path sharedLevelsDir();
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

/// `mesh` through bspc's clean stage with default settings.
bspc::Mesh cleaned(const bspc::Mesh& mesh);

/// Compiles a mesh in memory with default settings (or `settings`).
std::vector<std::uint8_t> compile(const bspc::Mesh& mesh,
                                  const bspc::CompileSettings& settings = {});

/// A mesh compiled in memory, kept alive with its World.
struct CompiledMesh {
  AlignedBytes bytes;
  bspf::World world;
  explicit CompiledMesh(const bspc::Mesh& mesh, const bspc::CompileSettings& settings = {})
      : bytes(compile(mesh, settings)), world(*bspf::viewWorld(bytes.span()).world) {}
};

/// Steps `bodies` in `a` and a copy of them in `b` for `frames` frames of
/// 1/60 s, body by body, each walking a direction of its own that turns
/// every second (into walls, over edges, down ramps); returns how many
/// body-steps ended at a different position in the two worlds.
int differingWalkSteps(const bspf::World& a, const bspf::World& b, std::vector<bspf::Body> bodies,
                       int frames);

/// The point of triangle `t` of `world` with weights u and v on its second
/// and third corners, folded back into the triangle when u + v > 1 (so u, v
/// uniform in [0, 1) give a point uniform over its area). Metres.
Eigen::Vector3f pointOnTriangle(const bspf::World& world, std::uint32_t t, float u, float v);

/// Seeded random numbers over a level, for the query tests: the same
/// sequence on every run and platform's build of the same compiler.
class LevelSampler {
 public:
  LevelSampler(const bspf::World& world, std::uint32_t seed);
  /// Uniform in [0, 1).
  float unit() { return unit_(rng_); }
  /// A uniform random unit vector.
  Eigen::Vector3f direction();
  /// A uniform random triangle index.
  std::uint32_t triangle() { return std::uint32_t(pick_(rng_)); }
  /// A uniform random point in the level's bounds.
  Eigen::Vector3f inBounds();
  /// The level's bounds, metres.
  Eigen::Vector3f low, high;

 private:
  std::mt19937 rng_;
  std::uniform_real_distribution<float> unit_{0.f, 1.f};
  std::normal_distribution<float> gauss_;
  std::uniform_int_distribution<std::size_t> pick_;
};

/// Compiles samples/NAME.obj with default settings into a temp directory
/// and opens it (the World keeps its mapping alive). In the Windows build
/// (tests/windows), opens the host bspc's blob from BSPF_SAMPLE_BLOBS_DIR.
bspf::World compileSample(const std::string& name);

/// compileSample at a 1 m query reach (bspc's default until the walkers
/// chose 6 m): a tree with splits even for the small samples, whose faces
/// then lie in split planes (box_room at 6 m is a single leaf). In the
/// Windows build, the host bspc's NAME.reach1.bspf.
bspf::World compileSampleWithSplits(const std::string& name);

/// A fresh empty directory under the system temp dir, removed with
/// everything in it when the test program exits (kept when the environment
/// variable BSPF_KEEP_TEST_DIRS is set, for post-mortems).
std::filesystem::path freshTempDir(const std::string& tag);

/// Runs a shell command; returns its exit status and stderr.
struct CommandResult {
  int status = -1;
  std::string out, err;
};
CommandResult run(const std::string& command);

/// `path` in single quotes, for a POSIX shell command.
std::string quoted(const std::filesystem::path& path);

/// Runs the bspc built with the tests with `arguments` (quoted already).
CommandResult runBspc(const std::string& arguments);

/// Writes `text` to `path`. Throws std::runtime_error when it cannot.
void writeText(const std::filesystem::path& path, const std::string& text);

}  // namespace bspf::test

/// What a skipped test prints (ctest's SKIP_REGULAR_EXPRESSION for the tests,
/// set in tests/CMakeLists.txt, matches it and reports the test as skipped).
#define BSPF_SKIPPED_MARKER "BSPF_TEST_SKIPPED"

/// In a Catch2 test: returns from the test, with a warning (printed even when
/// the test passes) that ctest reads as a skip, when the shared levels are
/// absent (a user's clone has none).
#define BSPF_SKIP_WITHOUT_SHARED_LEVELS()                                           \
  do {                                                                              \
    if (!std::filesystem::exists(bspf::test::sharedLevelsDir())) {                  \
      WARN(BSPF_SKIPPED_MARKER ": " << bspf::test::sharedLevelsDir()                \
                                    << " is absent (set BSPF_SHARED_LEVELS to the " \
                                       "folder of the real levels)");               \
      return;                                                                       \
    }                                                                               \
  } while (false)
