// SPDX-License-Identifier: MIT
// bspc/mesh.h: the triangle mesh passed between compiler stages.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

namespace bspc {

/// An indexed triangle mesh in metres, Y up. Triangles are counter-clockwise
/// seen from the side their face normal points to.
struct Mesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  /// Surface names: the source's materials, each once, in the order the
  /// triangles first use them (the import merges materials of one name).
  /// Empty means one surface, kDefaultSurface.
  std::vector<std::string> surfaces;
  /// Parallel to triangles: each triangle's index into `surfaces`. Empty
  /// means every triangle has surface 0.
  std::vector<std::uint32_t> triangleSurfaces;
  /// What the import noticed and worked around, one line each, without the
  /// file's name (an --up the importer's own axis conversion made moot).
  std::vector<std::string> warnings;
};

/// The name of the one surface of a mesh without materials, and of
/// triangles whose source material has no name: the import gives it to a
/// material named "" or assimp's "DefaultMaterial" (the name assimp gives the
/// material it makes for meshes that have none, such as an OBJ's triangles
/// before any usemtl).
inline constexpr const char* kDefaultSurface = "default";

/// A compile failure caused by the input or the settings. The message is one
/// line; the driver prefixes the file it concerns.
class CompileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace bspc
