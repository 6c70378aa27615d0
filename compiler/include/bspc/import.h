// SPDX-License-Identifier: MIT
// bspc/import.h: stage 1, read any mesh format assimp knows.
#pragma once

#include <bspc/mesh.h>
#include <bspc/settings.h>

#include <filesystem>
#include <optional>

namespace bspc {

/// Reads every mesh of the scene at `path`, applies each node's transform (a
/// mesh used by two nodes appears twice), triangulates polygons, drops points
/// and lines, rotates `settings.up` to Y and scales to metres. Does not weld
/// or drop anything else. A plain OBJ is read by importPlainObj (unless
/// settings.readPlainObj is false), every other file by assimp. Throws
/// CompileError when the file cannot be read or parsed, or holds no
/// triangles.
/// A Collada file that declares its up axis X_UP or Z_UP (<up_axis> in its
/// <asset>) is turned to Y up by assimp itself; for such a file
/// `settings.up` other than Y is not applied (it would turn the level over
/// again), and the mesh's warnings say so.
Mesh importMesh(const std::filesystem::path& path, const ImportSettings& settings);

/// importMesh's mesh of a plain OBJ, read by bspc's own reader in this
/// process (ImportSettings::readPlainObj, which importMesh and
/// importMeshContained try first): a file of only `v x y z` lines (decimal
/// numbers), triangle `f a b c` lines (vertex indices, 1-based or negative:
/// counted back from the last vertex so far), `#` comments and blank lines.
/// The mesh is the one assimp reads, bit for bit: a vertex per triangle
/// corner, in file order, the coordinates parsed as assimp parses them, one
/// surface (kDefaultSurface), `settings.up` and `settings.scale` applied.
/// Returns nothing, and reads nothing further, for every other file: one
/// that is not a regular file, holds any other statement (objects, groups,
/// materials, texture coordinates or normals, polygons, points, lines, line
/// continuations, a byte order mark), a number or index in another form,
/// an index out of range, no face, or more than 1 GiB (left to assimp's
/// contained import, whose memory is capped). Throws only std::bad_alloc.
std::optional<Mesh> importPlainObj(const std::filesystem::path& path,
                                   const ImportSettings& settings);

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
