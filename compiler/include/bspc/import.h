// SPDX-License-Identifier: MIT
// bspc/import.h: stage 1, read any mesh format assimp knows.
#pragma once

#include <bspc/mesh.h>
#include <bspc/settings.h>

#include <filesystem>

namespace bspc {

/// Reads every mesh of the scene at `path`, applies each node's transform (a
/// mesh used by two nodes appears twice), triangulates polygons, drops points
/// and lines, rotates `settings.up` to Y and scales to metres. Does not weld
/// or drop anything else. Throws CompileError when the file cannot be read or
/// parsed, or holds no triangles.
/// A Collada file that declares its up axis X_UP or Z_UP (<up_axis> in its
/// <asset>) is turned to Y up by assimp itself; for such a file
/// `settings.up` other than Y is not applied (it would turn the level over
/// again), and the mesh's warnings say so.
Mesh importMesh(const std::filesystem::path& path, const ImportSettings& settings);

/// importMesh in a child process, so that no file can crash, hang or exhaust
/// this one: the child (made by fork) imports and sends the mesh back over a
/// pipe, bit for bit (the same mesh as importMesh). It runs with an address
/// space cap (settings.memoryLimitBytes) and a CPU time limit, and is killed
/// when it runs longer than settings.timeoutSeconds or this process dies.
/// Throws CompileError as importMesh does, and also: "importer crashed
/// (signal N)" when the importer dies by a signal (a crash, an abort),
/// "import took longer than N s", "the importer ran out of memory (cap N
/// MiB)". Safe to call from a program with other threads, as long as none
/// holds a lock that the import needs (assimp's allocations go through
/// malloc, which fork makes safe).
Mesh importMeshContained(const std::filesystem::path& path, const ImportSettings& settings);

}  // namespace bspc
