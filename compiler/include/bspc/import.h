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
Mesh importMesh(const std::filesystem::path& path, const ImportSettings& settings);

}  // namespace bspc
