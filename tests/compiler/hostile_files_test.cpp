// SPDX-License-Identifier: MIT
// bspc and the loader against hostile paths: planted links at temporary
// names, outputs that are not regular files, a stats file naming the input
// or the output, FIFOs given to read, signals during a compile, and a level
// replaced under a running game. Nothing is destroyed, leaked or blocked on.
#include <bspc/compile.h>
#include <bspc/write.h>
#include <bspf/movement.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <future>
#include <iterator>
#include <string>
#include <thread>
#include <vector>

#include "support/test_support.h"

namespace {

namespace fs = std::filesystem;
using namespace std::chrono_literals;

std::string quoted(const fs::path& path) {
  std::string out = "'";
  for (const char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bspf::test::CommandResult runBspc(const std::string& arguments) {
  // `timeout`: a bspc that blocks fails the test instead of hanging it.
  return bspf::test::run("timeout 60 " + quoted(bspf::test::bspcExecutable()) + " " + arguments);
}

void writeText(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  REQUIRE(out);
}

std::string readText(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::vector<std::string> temporaryFiles(const fs::path& dir) {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator(dir))
    if (entry.path().filename().string().find(".tmp-") != std::string::npos)
      out.push_back(entry.path().filename().string());
  return out;
}

const char* kTriangleObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

// bspc started by fork and held before exec until release(), so the test
// knows its process id first (the old temporary name was built from it).
class HeldBspc {
 public:
  explicit HeldBspc(const std::vector<std::string>& arguments) {
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      ::close(fds[1]);
      char go;
      if (::read(fds[0], &go, 1) != 1) ::_exit(120);
      const int null = ::open("/dev/null", O_WRONLY);
      ::dup2(null, 1);
      ::dup2(null, 2);
      std::vector<std::string> all{bspf::test::bspcExecutable().string()};
      all.insert(all.end(), arguments.begin(), arguments.end());
      std::vector<char*> argv;
      for (std::string& a : all) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      ::_exit(121);
    }
    ::close(fds[0]);
    go_ = fds[1];
  }
  ~HeldBspc() {
    if (go_ >= 0) ::close(go_);
    if (pid_ > 0 && !waited_) {
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, nullptr, 0);
    }
  }
  pid_t pid() const { return pid_; }
  void release() {
    REQUIRE(::write(go_, "g", 1) == 1);
    ::close(go_);
    go_ = -1;
  }
  /// The raw wait status.
  int wait() {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    waited_ = true;
    return status;
  }
  bool running() {
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == 0) return true;
    waited_ = true;
    status_ = status;
    return false;
  }
  int status() const { return status_; }

 private:
  pid_t pid_ = -1;
  int go_ = -1;
  bool waited_ = false;
  int status_ = 0;
};

// A flat grid of n x n quads: big enough that compiling it takes a while.
void writeGrid(const fs::path& path, int n) {
  std::ofstream out(path);
  for (int z = 0; z <= n; ++z)
    for (int x = 0; x <= n; ++x)
      out << "v " << x * 0.5 << " " << ((x * 7 + z * 13) % 5) * 0.1 << " " << z * 0.5 << "\n";
  for (int z = 0; z < n; ++z)
    for (int x = 0; x < n; ++x) {
      const int a = z * (n + 1) + x + 1, b = a + 1, c = a + n + 1, d = c + 1;
      out << "f " << a << " " << c << " " << b << "\nf " << b << " " << c << " " << d << "\n";
    }
  REQUIRE(out);
}

}  // namespace

TEST_CASE("bspc never writes through a link planted at a guessable temporary name",
          "[compiler][bad-input][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-planted");
  writeText(dir / "tri.obj", kTriangleObj);
  writeText(dir / "victim.txt", "precious\n");
  HeldBspc bspc({(dir / "tri.obj").string(), "-o", (dir / "out.bspf").string(), "-q"});
  // The name bspc used to write through: ".out.bspf.tmp-PID".
  fs::create_symlink(dir / "victim.txt", dir / (".out.bspf.tmp-" + std::to_string(bspc.pid())));
  bspc.release();
  const int status = bspc.wait();
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(readText(dir / "victim.txt") == "precious\n");
  CHECK(fs::is_regular_file(fs::symlink_status(dir / "out.bspf")));
  CHECK(bspf::OpenResult(bspf::openWorld(dir / "out.bspf")).status == bspf::LoadStatus::Ok);
}

TEST_CASE("a PendingFile's temporary has an unpredictable name and is removed unless committed",
          "[compiler][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-pending");
  {
    bspc::PendingFile a(dir / "out.bspf");
    bspc::PendingFile b(dir / "out.bspf");
    const std::vector<std::string> names = temporaryFiles(dir);
    REQUIRE(names.size() == 2);
    CHECK(names[0] != names[1]);
    for (const std::string& name : names) {
      CHECK(name.rfind(".out.bspf.tmp-", 0) == 0);
      CHECK(name.size() == std::string(".out.bspf.tmp-").size() + 12);
    }
  }
  CHECK(temporaryFiles(dir).empty());
  CHECK_FALSE(fs::exists(dir / "out.bspf"));
}

TEST_CASE("bspc refuses an output that is not a regular file and leaves it as it was",
          "[compiler][bad-input][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-output");
  writeText(dir / "tri.obj", kTriangleObj);
  SECTION("a FIFO") {
    REQUIRE(::mkfifo((dir / "out.bspf").c_str(), 0644) == 0);
    const auto r = runBspc(quoted(dir / "tri.obj") + " -o " + quoted(dir / "out.bspf"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("out.bspf") && Catch::Contains("not a regular file"));
    CHECK(fs::is_fifo(dir / "out.bspf"));
  }
  SECTION("a symbolic link") {
    writeText(dir / "target.bspf", "old\n");
    fs::create_symlink(dir / "target.bspf", dir / "out.bspf");
    const auto r = runBspc(quoted(dir / "tri.obj") + " -o " + quoted(dir / "out.bspf"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("out.bspf") && Catch::Contains("symbolic link"));
    CHECK(fs::is_symlink(dir / "out.bspf"));
    CHECK(readText(dir / "target.bspf") == "old\n");
  }
  CHECK(temporaryFiles(dir).empty());
}

TEST_CASE(
    "bspc refuses a stats file naming the input or the output, and writes all outputs or "
    "none",
    "[compiler][bad-input][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-stats");
  writeText(dir / "tri.obj", kTriangleObj);
  const std::string files = quoted(dir / "tri.obj") + " -o " + quoted(dir / "out.bspf");
  SECTION("the input") {
    const auto r = runBspc(files + " --stats-json " + quoted(dir / "tri.obj"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("tri.obj") && Catch::Contains("overwrite the input"));
    CHECK(readText(dir / "tri.obj") == kTriangleObj);
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("the output, spelt another way") {
    const auto r = runBspc(files + " --stats-json " + quoted(dir / "." / "out.bspf"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK_THAT(r.err, Catch::Contains("overwrite the output"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("a stats file that cannot be written") {
    const auto r = runBspc(files + " --stats-json " + quoted(dir / "missing" / "stats.json"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("stats.json"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("both written") {
    const auto r = runBspc(files + " -q --stats-json " + quoted(dir / "stats.json"));
    INFO(r.err);
    CHECK(r.status == 0);
    CHECK(fs::exists(dir / "out.bspf"));
    CHECK_THAT(readText(dir / "stats.json"), Catch::StartsWith("{\"seconds\""));
  }
  CHECK(temporaryFiles(dir).empty());
}

TEST_CASE("a FIFO given to read is refused at once, never waited on",
          "[compiler][runtime][bad-input][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-fifo");
  REQUIRE(::mkfifo((dir / "level.obj").c_str(), 0644) == 0);
  REQUIRE(::mkfifo((dir / "level.bspf").c_str(), 0644) == 0);
  SECTION("bspc's input") {
    const auto r = runBspc(quoted(dir / "level.obj") + " -o " + quoted(dir / "out.bspf"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("level.obj") && Catch::Contains("not a regular file"));
    CHECK_FALSE(fs::exists(dir / "out.bspf"));
  }
  SECTION("an OBJ's material library") {
    writeText(dir / "tri.obj", std::string("mtllib level.obj\n") + kTriangleObj);
    const auto r = runBspc(quoted(dir / "tri.obj") + " -q -o " + quoted(dir / "out.bspf"));
    INFO(r.err);
    CHECK(r.status == 0);
  }
  SECTION("bspc --info") {
    const auto r = runBspc("--info " + quoted(dir / "level.bspf"));
    INFO(r.err);
    CHECK(r.status == 1);
    CHECK(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    CHECK_THAT(r.err, Catch::Contains("level.bspf") && Catch::Contains("not a regular file"));
  }
  SECTION("openWorld") {
    auto opening =
        std::async(std::launch::async, [&] { return bspf::openWorld(dir / "level.bspf"); });
    if (opening.wait_for(20s) != std::future_status::ready) {
      // Open the other end, so the blocked open returns and the test ends.
      const int writer = ::open((dir / "level.bspf").c_str(), O_WRONLY);
      opening.wait();
      ::close(writer);
      FAIL("openWorld blocked on a FIFO");
    }
    const bspf::OpenResult r = opening.get();
    CHECK(r.status == bspf::LoadStatus::CannotOpen);
    CHECK_THAT(r.message, Catch::Contains("level.bspf") && Catch::Contains("not a regular file"));
  }
}

TEST_CASE("SIGINT or SIGTERM during a compile removes bspc's temporary files",
          "[compiler][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-signal");
  writeGrid(dir / "grid.obj", 300);
  const int signal = GENERATE(SIGINT, SIGTERM);
  INFO("signal " << signal);
  HeldBspc bspc({(dir / "grid.obj").string(), "-o", (dir / "out.bspf").string(), "-q",
                 "--stats-json", (dir / "stats.json").string()});
  bspc.release();
  // Wait for the temporaries (made before the import), then interrupt.
  bool seen = false;
  for (int i = 0; i < 2000 && bspc.running() && !seen; ++i) {
    seen = temporaryFiles(dir).size() == 2;
    if (!seen) std::this_thread::sleep_for(5ms);
  }
  REQUIRE(seen);
  ::kill(bspc.pid(), signal);
  const int status = bspc.wait();
  CHECK(WIFSIGNALED(status));
  if (WIFSIGNALED(status)) CHECK(WTERMSIG(status) == signal);
  CHECK(temporaryFiles(dir).empty());
  CHECK_FALSE(fs::exists(dir / "out.bspf"));
  CHECK_FALSE(fs::exists(dir / "stats.json"));
}

TEST_CASE(
    "a level replaced by bspc while a game has it open: the old World keeps working, a new "
    "open sees the new level",
    "[compiler][runtime][hostile]") {
  const fs::path dir = bspf::test::freshTempDir("hostile-replace");
  const fs::path level = dir / "level.bspf";
  writeText(dir / "small.obj", kTriangleObj);
  bspc::compileFile(bspf::test::samplesDir() / "box_room.obj", level, {});
  const bspf::OpenResult before = bspf::openWorld(level);
  REQUIRE(before);
  const bspf::World& old = *before.world;
  const std::vector<bspf::schema::Vec3> oldVertices(old.vertices().begin(), old.vertices().end());

  // The game's reload pattern: bspc (or a copy and a rename) replaces the
  // file; the open World keeps the old file's pages.
  bspc::compileFile(dir / "small.obj", level, {});
  CHECK(old.vertices().size() == oldVertices.size());
  CHECK(std::equal(oldVertices.begin(), oldVertices.end(), old.vertices().begin(),
                   [](const auto& a, const auto& b) {
                     return a.x() == b.x() && a.y() == b.y() && a.z() == b.z();
                   }));
  bspf::Body body;
  body.position = bspf::Vec3(0, 1.0f, 0);
  bspf::StepScratch scratch;
  for (int frame = 0; frame < 60; ++frame)
    bspf::stepBody(old, body, bspf::Vec3(3, 0, 0), 1.0f / 60, scratch);
  CHECK(body.position.allFinite());
  CHECK(body.grounded);  // still standing on the old level's floor

  const bspf::OpenResult after = bspf::openWorld(level);
  REQUIRE(after);
  CHECK(after.world->triangles().size() == 1);
  CHECK(old.triangles().size() > 1);
}
