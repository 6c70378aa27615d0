// SPDX-License-Identifier: MIT
// The import in a child process: assimp reads untrusted files, and some
// make it crash, loop or take all memory. The child imports with importMesh
// and streams the mesh back; this process turns every way the child can end
// into a CompileError.
#include <bspc/import.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <new>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define BSPC_SANITIZED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
#define BSPC_SANITIZED 1
#endif
#endif

namespace bspc {

namespace {

// What the child sends first: a mesh follows, or a message.
enum class Reply : std::uint8_t { Mesh = 'M', Error = 'E', OutOfMemory = 'O' };

struct MeshHeader {
  std::uint64_t vertices, triangles;
};

constexpr double kMiB = 1024.0 * 1024.0;

std::uint64_t memoryCap(const std::filesystem::path& path, const ImportSettings& settings) {
  if (settings.memoryLimitBytes != 0) return settings.memoryLimitBytes;
  struct stat info {};
  const std::uint64_t size = ::stat(path.c_str(), &info) == 0 ? std::uint64_t(info.st_size) : 0;
  return (std::uint64_t(1) << 30) + 64 * size;
}

// Writes all of `size` bytes; false when the reader is gone.
bool writeAll(int fd, const void* data, std::size_t size) {
  const auto* at = static_cast<const std::uint8_t*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, at, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    at += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

// A count, then each text as a length and its bytes.
bool sendTexts(int fd, const std::vector<std::string>& texts) {
  const auto count = static_cast<std::uint32_t>(texts.size());
  if (!writeAll(fd, &count, sizeof count)) return false;
  for (const std::string& text : texts) {
    const auto length = static_cast<std::uint32_t>(text.size());
    if (!writeAll(fd, &length, sizeof length) || !writeAll(fd, text.data(), text.size()))
      return false;
  }
  return true;
}

void sendMessage(int fd, Reply kind, const std::string& text) {
  const auto length = static_cast<std::uint32_t>(text.size());
  if (writeAll(fd, &kind, 1) && writeAll(fd, &length, sizeof length))
    writeAll(fd, text.data(), text.size());
}

// The child: limits, import, reply, exit. Never returns.
[[noreturn]] void runChild(int fd, const std::filesystem::path& path,
                           const ImportSettings& settings, std::uint64_t cap) {
  // Dies with its parent, and by the default action of every signal: a crash
  // is the parent's to report (not a handler's that the parent installed,
  // such as a test framework's), and the handler that removes the parent's
  // temporary files on SIGINT is the parent's to run.
  ::prctl(PR_SET_PDEATHSIG, SIGKILL);
  for (const int signal : {SIGINT, SIGTERM, SIGHUP, SIGSEGV, SIGBUS, SIGABRT, SIGFPE, SIGILL})
    ::signal(signal, SIG_DFL);
  // SIGXCPU at the timeout, SIGKILL a second later, should the parent's own
  // clock fail to stop it.
  const auto cpu = static_cast<rlim_t>(std::ceil(settings.timeoutSeconds)) + 1;
  const rlimit cpuLimit{cpu, cpu + 1};
  ::setrlimit(RLIMIT_CPU, &cpuLimit);
#ifndef BSPC_SANITIZED
  const rlimit memory{static_cast<rlim_t>(cap), static_cast<rlim_t>(cap)};
  ::setrlimit(RLIMIT_AS, &memory);
#else
  (void)cap;
#endif
  int status = 0;
  try {
    ImportSettings inProcess = settings;
    inProcess.contained = false;
    const Mesh mesh = importMesh(path, inProcess);
    const Reply kind = Reply::Mesh;
    const MeshHeader header{mesh.vertices.size(), mesh.triangles.size()};
    static_assert(sizeof(Eigen::Vector3d) == 3 * sizeof(double));
    static_assert(sizeof(mesh.triangles[0]) == 3 * sizeof(std::uint32_t));
    if (!writeAll(fd, &kind, 1) || !writeAll(fd, &header, sizeof header) ||
        !writeAll(fd, mesh.vertices.data(), mesh.vertices.size() * sizeof(Eigen::Vector3d)) ||
        !writeAll(fd, mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0])))
      status = 1;
    // Then each triangle's surface, the surface names and the import's
    // warnings, each list as a count, and each text as a length and bytes.
    const auto surfaceIds = static_cast<std::uint64_t>(mesh.triangleSurfaces.size());
    if (status == 0 &&
        (!writeAll(fd, &surfaceIds, sizeof surfaceIds) ||
         !writeAll(fd, mesh.triangleSurfaces.data(), surfaceIds * sizeof(std::uint32_t))))
      status = 1;
    if (status == 0 && !sendTexts(fd, mesh.surfaces)) status = 1;
    if (status == 0 && !sendTexts(fd, mesh.warnings)) status = 1;
  } catch (const CompileError& e) {
    // assimp turns an exception inside an importer into its error string.
    const bool memory = std::string_view(e.what()).find("bad_alloc") != std::string_view::npos;
    sendMessage(fd, memory ? Reply::OutOfMemory : Reply::Error, e.what());
  } catch (const std::bad_alloc&) {
    sendMessage(fd, Reply::OutOfMemory, {});
  } catch (const std::exception& e) {
    sendMessage(fd, Reply::Error, std::string("cannot import: ") + e.what());
  }
  ::_exit(status);  // no destructors, atexit handlers or stdio flushes of the parent's
}

// The parent's end: reads the child's reply against a deadline, then reaps it.
class Child {
 public:
  Child(pid_t pid, int fd, double timeoutSeconds)
      : pid_(pid),
        fd_(fd),
        timeout_(timeoutSeconds),
        deadline_(std::chrono::steady_clock::now() +
                  std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                      std::chrono::duration<double>(timeoutSeconds))) {}
  ~Child() {
    if (fd_ >= 0) ::close(fd_);
    if (pid_ > 0) {
      ::kill(pid_, SIGKILL);
      reap();
    }
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  // Fills `size` bytes, or throws why the child stopped short.
  void read(void* data, std::size_t size) {
    auto* at = static_cast<std::uint8_t*>(data);
    while (size > 0) {
      const auto left = deadline_ - std::chrono::steady_clock::now();
      const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(left).count();
      if (ms <= 0) timedOut();
      pollfd ready{fd_, POLLIN, 0};
      const int polled = ::poll(&ready, 1, static_cast<int>(std::min<long long>(ms, 1 << 30)));
      if (polled < 0 && errno == EINTR) continue;
      if (polled < 0)
        throw CompileError(std::string("cannot wait for the importer: ") + std::strerror(errno));
      if (polled == 0) continue;  // the deadline is checked above
      const ssize_t n = ::read(fd_, at, size);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) stoppedShort();
      at += n;
      size -= static_cast<std::size_t>(n);
    }
  }

  // A count (at most `most`), then each text as a length and its bytes.
  std::vector<std::string> readTexts(std::uint64_t most) {
    std::uint32_t count = 0;
    read(&count, sizeof count);
    if (count > most) throw CompileError("the importer sent a malformed reply");
    std::vector<std::string> texts;
    for (std::uint32_t k = 0; k < count; ++k) {
      std::uint32_t length = 0;
      read(&length, sizeof length);
      if (length > (1u << 20)) throw CompileError("the importer sent a malformed reply");
      read(texts.emplace_back(length, '\0').data(), length);
    }
    return texts;
  }

  // Reaps a child that has sent its whole reply; throws when it then failed.
  void finish() {
    ::close(fd_);
    fd_ = -1;
    const int status = reap();
    if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0)) describe(status);
  }

 private:
  int reap() {
    int status = 0;
    while (::waitpid(pid_, &status, 0) < 0 && errno == EINTR) {
    }
    pid_ = -1;
    return status;
  }

  [[noreturn]] void timedOut() {
    ::kill(pid_, SIGKILL);
    reap();
    throwTimeout();
  }

  [[noreturn]] void throwTimeout() const {
    std::string seconds = std::to_string(timeout_);
    seconds.erase(seconds.find_last_not_of('0') + 1);
    if (seconds.back() == '.') seconds.pop_back();
    throw CompileError("the import took longer than " + seconds +
                       " s (the importer was stopped; see the import timeout)");
  }

  // The pipe closed early: the child died. Say how.
  [[noreturn]] void stoppedShort() {
    ::close(fd_);
    fd_ = -1;
    describe(reap());
    throw CompileError("the importer stopped without a reply");
  }

  void describe(int status) const {
    if (WIFSIGNALED(status)) {
      const int signal = WTERMSIG(status);
      if (signal == SIGXCPU) throwTimeout();
      if (signal == SIGKILL)
        throw CompileError("the importer was killed (signal 9: out of CPU time, or of memory)");
      const char* name = ::strsignal(signal);
      throw CompileError("the importer crashed reading the file (signal " + std::to_string(signal) +
                         ": " + (name ? name : "unknown") + ")");
    }
    if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
      throw CompileError("the importer failed (exit status " + std::to_string(WEXITSTATUS(status)) +
                         ")");
  }

  pid_t pid_;
  int fd_;
  double timeout_;
  std::chrono::steady_clock::time_point deadline_;
};

}  // namespace

Mesh importMeshContained(const std::filesystem::path& path, const ImportSettings& settings) {
  // bspc's own reader needs no containing: it reads nothing but numbers
  // into arrays the file's size bounds.
  if (settings.readPlainObj)
    if (std::optional<Mesh> mesh = importPlainObj(path, settings)) return std::move(*mesh);
  const std::uint64_t cap = memoryCap(path, settings);
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0)
    throw CompileError(std::string("cannot start the importer: ") + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int error = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    throw CompileError(std::string("cannot start the importer: ") + std::strerror(error));
  }
  if (pid == 0) {
    ::close(fds[0]);
    runChild(fds[1], path, settings, cap);
  }
  ::close(fds[1]);
  Child child(pid, fds[0], settings.timeoutSeconds);

  Reply kind{};
  child.read(&kind, 1);
  if (kind == Reply::Error || kind == Reply::OutOfMemory) {
    std::uint32_t length = 0;
    child.read(&length, sizeof length);
    if (length > (1u << 20)) throw CompileError("the importer sent a malformed reply");
    std::string text(length, '\0');
    child.read(text.data(), text.size());
    child.finish();
    if (kind == Reply::OutOfMemory)
      throw CompileError("the importer ran out of memory (cap " +
                         std::to_string(static_cast<std::uint64_t>(std::ceil(cap / kMiB))) +
                         " MiB; see the import memory limit)");
    throw CompileError(text);
  }
  if (kind != Reply::Mesh) throw CompileError("the importer sent a malformed reply");
  MeshHeader header{};
  child.read(&header, sizeof header);
  // Indices are 32-bit: no mesh of ours has more vertices than that.
  if (header.vertices > 0xFFFFFFFFu || header.triangles > 0xFFFFFFFFu)
    throw CompileError("the importer sent a malformed reply");
  Mesh mesh;
  mesh.vertices.resize(header.vertices);
  mesh.triangles.resize(header.triangles);
  child.read(mesh.vertices.data(), mesh.vertices.size() * sizeof(Eigen::Vector3d));
  child.read(mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
  std::uint64_t surfaceIds = 0;
  child.read(&surfaceIds, sizeof surfaceIds);
  if (surfaceIds != 0 && surfaceIds != header.triangles)
    throw CompileError("the importer sent a malformed reply");
  mesh.triangleSurfaces.resize(surfaceIds);
  child.read(mesh.triangleSurfaces.data(), surfaceIds * sizeof(std::uint32_t));
  // A surface per mesh of the scene at most: no more than its triangles.
  mesh.surfaces = child.readTexts(header.triangles + 1);
  mesh.warnings = child.readTexts(1024);
  child.finish();
  return mesh;
}

}  // namespace bspc
