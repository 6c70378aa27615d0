// SPDX-License-Identifier: MIT
// The import's own reader for plain OBJ files (private to the compiler).
#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <vector>

namespace bspc {

/// The positions of a plain OBJ's triangle corners in file order, three per
/// `f` line, each as assimp's OBJ importer reads it (the same float: its
/// parser's arithmetic, or the parser itself for the rarer forms). A plain OBJ holds only `v x y z`
/// lines of decimal numbers, `f a b c` lines of three vertex indices (1-based, or negative: counted
/// back from the last vertex so far), `#` comments and blank lines, such as map converters write
/// for collision meshes. Returns nothing, having changed nothing, for every other file: one that
/// cannot be opened as a regular file, holds any other statement (objects,
/// groups, materials, texture coordinates, normals, polygons, points,
/// lines, line continuations), a number or index in another form, an index
/// out of range, no face, or more than 1 GiB. Those are left to assimp, whose errors say
/// what is wrong.
std::optional<std::vector<std::array<float, 3>>> readPlainObjCorners(
    const std::filesystem::path& path);

}  // namespace bspc
