// SPDX-License-Identifier: MIT
// bspc/write.h: stage 5, serialise and write the blob.
#pragma once

#include <bspc/build_tree.h>
#include <bspc/clean.h>
#include <bspc/mesh.h>
#include <bspc/settings.h>
#include <bspf/world.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <vector>

namespace bspc {

struct BlobMetadata {
  /// Recorded as given; compileFile passes the file name without its
  /// directory, so builds are reproducible wherever they run.
  std::string sourceFile;
  CompileSettings settings;
  CleanReport clean;
};

/// The complete, size-prefixed .bspf blob. Deterministic: equal inputs give
/// equal bytes.
std::vector<std::uint8_t> serializeWorld(const Mesh& mesh,
                                         const std::vector<bspf::schema::TrianglePlanes>& planes,
                                         const BspTree& tree, const BlobMetadata& metadata);

/// The bytes of the arrays of a blob of these counts (vertices, triangles,
/// tree nodes, leaves, leaf entries) as serializeWorld lays it out: the
/// blob is larger by its tables and build info (a few hundred bytes). With
/// no nodes, one leaf and one entry a triangle, it is less than any blob of
/// that mesh can be: minimumBlobBytes.
std::uint64_t estimateBlobBytes(std::uint64_t vertices, std::uint64_t triangles,
                                std::uint64_t nodes, std::uint64_t leaves, std::uint64_t entries);
inline std::uint64_t minimumBlobBytes(std::uint64_t vertices, std::uint64_t triangles) {
  return estimateBlobBytes(vertices, triangles, 0, 1, triangles);
}

/// The collision model a blob holds, as the runtime reads it (its float
/// vertices and its triangles, in their order and winding), as a Wavefront
/// OBJ: "# " and `header` on the first line, then one "v x y z" a vertex
/// (metres, Y up, each float written with the fewest digits that read back
/// as the same float) and one "f a b c" a triangle (1-based, counter-
/// clockwise seen from the side the triangle faces). Any modelling tool
/// opens it; bspc imports it again to the same triangles.
std::string toObj(const bspf::World& world, const std::string& header);

/// An output file being written: bytes go to a temporary file beside `path`
/// (".NAME.tmp-" and 12 random characters, created with O_EXCL and
/// O_NOFOLLOW, so it never opens an existing file or follows a planted
/// link), which commit() flushes to disk and renames over `path`. Until
/// then `path` is untouched; a PendingFile destroyed uncommitted removes its
/// temporary. While it exists its temporary is listed for the handler of
/// removeTemporariesOnSignal. POSIX only, like writeFileAtomically and
/// removeTemporariesOnSignal: a Windows build of the library (tests/windows)
/// declares them but does not define them.
class PendingFile {
 public:
  /// Creates the temporary. Throws CompileError naming `path` when `path`
  /// exists and is not a regular file (a device node, FIFO, socket,
  /// directory or symbolic link: bspc replaces only regular files) or the
  /// temporary cannot be made (a missing or read-only directory).
  explicit PendingFile(const std::filesystem::path& path);
  ~PendingFile();
  PendingFile(const PendingFile&) = delete;
  PendingFile& operator=(const PendingFile&) = delete;

  /// Appends `bytes`. Throws CompileError naming `path` on failure.
  void write(std::span<const std::uint8_t> bytes);
  /// Flushes the temporary to disk and renames it over `path` (checked again
  /// to be absent or a regular file). Throws CompileError naming `path` on
  /// failure, removing the temporary. Call once.
  void commit();

  const std::filesystem::path& path() const { return path_; }

 private:
  [[noreturn]] void fail(const std::string& why);
  std::filesystem::path path_;
  std::filesystem::path temporary_;
  int fd_ = -1;
  int slot_ = -1;  // in the signal handler's list
};

/// Writes `bytes` through a PendingFile: `path` is either untouched or
/// complete. Throws CompileError naming `path` on failure, leaving no
/// temporary file.
void writeFileAtomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

/// Installs handlers for SIGINT, SIGTERM and SIGHUP that remove every
/// PendingFile's temporary, then end the process by the same signal (so the
/// caller's shell sees it). For programs (bspc's main); a library caller that
/// has its own handlers leaves them be. The handler reads the one piece of
/// global state in bspc's library: a fixed table of the temporaries now on
/// disk, each entry published by an atomic flag, as a signal handler can
/// safely use nothing else.
void removeTemporariesOnSignal();

}  // namespace bspc
