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

}  // namespace bspc
