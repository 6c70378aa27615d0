// SPDX-License-Identifier: MIT
// bspc/compile.h: the whole compile, stage by stage.
#pragma once

#include <bspc/buried.h>
#include <bspc/clean.h>
#include <bspc/edges.h>
#include <bspc/mesh.h>
#include <bspc/reach.h>
#include <bspc/settings.h>
#include <bspf/world.h>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace bspc {

/// Wall-clock seconds per stage. `edges` counts the covered-face rule and
/// the edge classes both rules share; `write` serialising, verifying the
/// blob as the runtime loads it (while compileFile writes it out), and
/// writing, syncing and renaming the files. Together they are nearly the
/// whole compile (not the checks of the settings and paths, nor the tree
/// figures taken from the verified blob).
struct StageTimes {
  double import = 0, clean = 0, edges = 0, buried = 0, reach = 0, buildTree = 0, planes = 0,
         write = 0;
};

struct CompileReport {
  CleanReport clean;
  ReachReport reach;
  /// Covered faces dropped, edges by kind, edge planes skipped.
  EdgeReport edges;
  /// Faces lying inside another closed solid (settings.dropBuriedFaces).
  BuriedReport buried;
  StageTimes seconds;
  /// CPU seconds per stage, all of this process's threads together (the
  /// contained import's child is not counted: its time is the wait).
  StageTimes cpuSeconds;
  std::uint64_t outputBytes = 0;
  /// Figures of the tree as the runtime sees it (the blob is verified).
  bspf::TreeStats tree;
  std::uint32_t triangles = 0;
  /// The import's warnings (Mesh::warnings), then the cleaned mesh's
  /// (meshWarnings: inside-out pieces, a size that suggests the wrong unit),
  /// one line each, without the file's name.
  std::vector<std::string> warnings;
};

/// import, clean, drop covered faces and faces buried in other solids, drop faces no body can reach
/// (settings.reach, when it names points), build tree, classify edges and
/// precompute planes, write: `input` (any format
/// assimp reads, a regular file) to the blob at `output`, and, when
/// `statsJson` is not empty, the report as JSON (toJson) to that file, and,
/// when `exportObj` is not empty, the compiled model as an OBJ (toObj) to
/// that one. All outputs are written through PendingFile (write.h): their
/// temporaries are made before the import, and all are kept or none (the
/// stats file and the OBJ are renamed into place first, the blob last). No
/// two of the paths may name the same file. Throws CompileError with a
/// one-line message naming the file at fault (an output that is not a
/// regular file, a stats path naming the input or the output, ...); the
/// outputs are then left as they were. POSIX only: not in a Windows build of
/// the library (tests/windows), which has compileMesh.
CompileReport compileFile(const std::filesystem::path& input, const std::filesystem::path& output,
                          const CompileSettings& settings,
                          const std::filesystem::path& statsJson = {},
                          const std::filesystem::path& exportObj = {});

/// The same stages on a mesh in memory (metres, Y up), returning the blob.
/// `sourceName` is recorded as the source file name.
std::vector<std::uint8_t> compileMesh(const Mesh& mesh, const CompileSettings& settings,
                                      const std::string& sourceName, CompileReport& report);

/// The report as one JSON object (stage wall and CPU times, clean counts, tree figures,
/// output size).
std::string toJson(const CompileReport& report);

}  // namespace bspc
