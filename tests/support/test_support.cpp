// SPDX-License-Identifier: MIT
#include "support/test_support.h"

#include <bspc/clean.h>

#ifndef _WIN32
#include <sys/wait.h>
#endif

#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <stdexcept>

namespace bspf::test {

std::filesystem::path sharedLevelsDir() {
  if (const char* fromEnvironment = std::getenv("BSPF_SHARED_LEVELS")) return fromEnvironment;
  const std::filesystem::path besideSources = BSPF_SHARED_LEVELS_DIR;
  if (std::filesystem::exists(besideSources)) return besideSources;
#ifdef _WIN32
  return besideSources;
#else
  // A project folder (sources and build/ inside) moved since the build:
  // PROJECT/build/tests/bspf_tests, levels in PROJECT/../shared/levels.
  std::error_code error;
  const std::filesystem::path executable = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return besideSources;
  return executable.parent_path() / "../../../shared/levels";
#endif
}

bspc::Mesh boxMesh(const Eigen::Vector3d& low, const Eigen::Vector3d& high) {
  bspc::Mesh m;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? high.x() : low.x(), i & 2 ? high.y() : low.y(),
                            i & 4 ? high.z() : low.z());
  // Counter-clockwise seen from outside.
  m.triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
  return m;
}

void append(bspc::Mesh& mesh, const bspc::Mesh& part) {
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), part.vertices.begin(), part.vertices.end());
  for (const auto& t : part.triangles)
    mesh.triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

bspc::Mesh cleaned(const bspc::Mesh& mesh) {
  bspc::CleanReport report;
  return bspc::cleanMesh(mesh, {}, report);
}

int differingWalkSteps(const bspf::World& a, const bspf::World& b, std::vector<bspf::Body> bodies,
                       int frames) {
  std::vector<bspf::Body> other = bodies;
  bspf::StepScratch scratch;
  int differing = 0;
  for (int frame = 0; frame < frames; ++frame) {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const float angle = 2.4f * float(i) + 0.9f * float(frame / 60);
      const bspf::Vec3 force(40 * std::cos(angle), 0, 40 * std::sin(angle));
      bspf::stepBody(a, bodies[i], force, 1 / 60.0f, scratch);
      bspf::stepBody(b, other[i], force, 1 / 60.0f, scratch);
      differing += bodies[i].position != other[i].position;
    }
  }
  return differing;
}

std::vector<std::uint8_t> compile(const bspc::Mesh& mesh, const bspc::CompileSettings& settings) {
  bspc::CompileReport report;
  return bspc::compileMesh(mesh, settings, "test-mesh", report);
}

Eigen::Vector3f pointOnTriangle(const bspf::World& world, std::uint32_t t, float u, float v) {
  if (u + v > 1) u = 1 - u, v = 1 - v;
  const auto& tri = world.triangles()[t];
  const Eigen::Vector3f a = bspf::toVec3(world.vertices()[tri.v0()]);
  const Eigen::Vector3f b = bspf::toVec3(world.vertices()[tri.v1()]);
  const Eigen::Vector3f c = bspf::toVec3(world.vertices()[tri.v2()]);
  return a + u * (b - a) + v * (c - a);
}

LevelSampler::LevelSampler(const bspf::World& world, std::uint32_t seed)
    : low(bspf::toVec3(*world.blob().bounds_min())),
      high(bspf::toVec3(*world.blob().bounds_max())),
      rng_(seed),
      pick_(0, world.triangles().size() - 1) {}

Eigen::Vector3f LevelSampler::direction() {
  return Eigen::Vector3f(gauss_(rng_), gauss_(rng_), gauss_(rng_)).normalized();
}

Eigen::Vector3f LevelSampler::inBounds() {
  return low + (high - low).cwiseProduct(Eigen::Vector3f(unit(), unit(), unit()));
}

namespace {
// samples/NAME.obj compiled with `settings` (in the Windows build, which has
// no importer, the host's bspc compiled it: scripts/cross-windows.sh, the
// blob NAME + `suffix` + .bspf).
bspf::World compiledSample(const std::string& name, const bspc::CompileSettings& settings,
                           [[maybe_unused]] const std::string& suffix) {
#ifdef BSPF_SAMPLE_BLOBS_DIR
  const std::filesystem::path blob =
      std::filesystem::path(BSPF_SAMPLE_BLOBS_DIR) / (name + suffix + ".bspf");
#else
  const std::filesystem::path blob = freshTempDir("sample") / (name + ".bspf");
  bspc::compileFile(samplesDir() / (name + ".obj"), blob, settings);
#endif
  bspf::OpenResult opened = bspf::openWorld(blob);
  if (!opened) throw std::runtime_error(opened.message);
  return *opened.world;
}
}  // namespace

bspf::World compileSample(const std::string& name) { return compiledSample(name, {}, ""); }

bspf::World compileSampleWithSplits(const std::string& name) {
  bspc::CompileSettings settings;
  settings.tree.queryReach = 1;
  return compiledSample(name, settings, ".reach1");
}

namespace {

// The directories freshTempDir made, removed when the test program exits
// (every run used to leave hundreds in /tmp), unless BSPF_KEEP_TEST_DIRS is
// set for a post-mortem.
class TempDirs {
 public:
  void add(const std::filesystem::path& dir) {
    const std::lock_guard<std::mutex> lock(mutex_);
    dirs_.push_back(dir);
  }
  ~TempDirs() {
    if (std::getenv("BSPF_KEEP_TEST_DIRS")) return;
    std::error_code ignored;  // a directory a test removed itself is fine
    for (const std::filesystem::path& dir : dirs_) std::filesystem::remove_all(dir, ignored);
  }

 private:
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};

}  // namespace

std::filesystem::path freshTempDir(const std::string& tag) {
  static TempDirs made;
  static std::mt19937_64 rng(std::random_device{}());
  static std::mutex rngMutex;
  std::uint64_t draw;
  {
    const std::lock_guard<std::mutex> lock(rngMutex);
    draw = rng();
  }
  const std::filesystem::path dir = std::filesystem::temp_directory_path() /
                                    ("bspf-test-" + tag + "-" + std::to_string(draw % 1000000000));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  made.add(dir);
  return dir;
}

CommandResult run(const std::string& command) {
  const std::filesystem::path dir = freshTempDir("run");
  const std::string full = command + " >" + (dir / "out").string() + " 2>" + (dir / "err").string();
  CommandResult r;
  const int raw = std::system(full.c_str());
#ifdef _WIN32
  r.status = raw;  // the command's exit code itself
#else
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
#endif
  auto slurp = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  };
  r.out = slurp(dir / "out");
  r.err = slurp(dir / "err");
  std::filesystem::remove_all(dir);
  return r;
}

std::string quoted(const std::filesystem::path& path) {
  std::string out = "'";
  for (const char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

CommandResult runBspc(const std::string& arguments) {
  return run(quoted(bspcExecutable()) + " " + arguments);
}

void writeText(const std::filesystem::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace bspf::test
