// SPDX-License-Identifier: MIT
// bspc/compile.h: the whole compile, stage by stage.
#pragma once

#include <bspc/clean.h>
#include <bspc/edges.h>
#include <bspc/mesh.h>
#include <bspc/settings.h>
#include <bspf/world.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace bspc {

/// Wall-clock seconds per stage.
struct StageTimes {
  double import = 0, clean = 0, edges = 0, buildTree = 0, planes = 0, write = 0;
};

struct CompileReport {
  CleanReport clean;
  /// Covered faces dropped, edges by kind, edge planes skipped.
  EdgeReport edges;
  StageTimes seconds;
  std::uint64_t outputBytes = 0;
  /// Figures of the tree as the runtime sees it (the blob is verified).
  bspf::TreeStats tree;
  std::uint32_t triangles = 0;
  /// The import's warnings (Mesh::warnings), then the cleaned mesh's
  /// (meshWarnings: inside-out pieces, a size that suggests the wrong unit),
  /// one line each, without the file's name.
  std::vector<std::string> warnings;
};

/// import, clean, drop covered faces, build tree, classify edges and
/// precompute planes, write: `input` (any format
/// assimp reads, a regular file) to the blob at `output`, and, when
/// `statsJson` is not empty, the report as JSON (toJson) to that file. Both
/// outputs are written through PendingFile (write.h): their temporaries are
/// made before the import, and both are kept or neither (the stats file is
/// renamed into place first, the blob last). Throws CompileError with a
/// one-line message naming the file at fault (an output that is not a
/// regular file, a stats path naming the input or the output, ...); the
/// outputs are then left as they were. POSIX only: not in a Windows build of
/// the library (tests/windows), which has compileMesh.
CompileReport compileFile(const std::filesystem::path& input, const std::filesystem::path& output,
                          const CompileSettings& settings,
                          const std::filesystem::path& statsJson = {});

/// The same stages on a mesh in memory (metres, Y up), returning the blob.
/// `sourceName` is recorded as the source file name.
std::vector<std::uint8_t> compileMesh(const Mesh& mesh, const CompileSettings& settings,
                                      const std::string& sourceName, CompileReport& report);

/// The report as one JSON object (stage times, clean counts, tree figures,
/// output size).
std::string toJson(const CompileReport& report);

}  // namespace bspc
