// bspc/write.h: stage 5, serialise and write the blob.
#pragma once

#include <bspc/build_tree.h>
#include <bspc/clean.h>
#include <bspc/mesh.h>
#include <bspc/settings.h>

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

/// Writes `bytes` to a temporary file beside `path`, flushes it to disk and
/// renames it over `path`, so `path` is either untouched or complete. Throws
/// CompileError naming `path` on failure, leaving no temporary file.
void writeFileAtomically(const std::filesystem::path& path, std::span<const std::uint8_t> bytes);

}  // namespace bspc
