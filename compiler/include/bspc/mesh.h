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

/// Gives `kept`, made of the triangles of `mesh` for which keep[t] holds (in
/// their order), those triangles' surfaces: the names they use, renumbered
/// in the order the kept triangles first use them, as cleanMesh leaves a
/// mesh. For the stages that drop triangles after clean.
inline void carrySurfaces(const Mesh& mesh, const std::vector<bool>& keep, Mesh& kept) {
  kept.surfaces.clear();
  kept.triangleSurfaces.clear();
  if (mesh.triangleSurfaces.empty()) {
    kept.surfaces = mesh.surfaces;
    return;
  }
  std::vector<std::uint32_t> renumbered(mesh.surfaces.size(), ~std::uint32_t(0));
  for (std::size_t t = 0; t < keep.size(); ++t) {
    if (!keep[t]) continue;
    std::uint32_t& id = renumbered[mesh.triangleSurfaces[t]];
    if (id == ~std::uint32_t(0)) {
      id = std::uint32_t(kept.surfaces.size());
      kept.surfaces.push_back(mesh.surfaces[mesh.triangleSurfaces[t]]);
    }
    kept.triangleSurfaces.push_back(id);
  }
}

/// The triangles of `mesh` for which keep[t] holds, in their order, with
/// the vertices they use in order of first use, their surfaces
/// (carrySurfaces) and `mesh`'s warnings. For the stages that drop triangles
/// after clean.
Mesh keepTriangles(const Mesh& mesh, const std::vector<bool>& keep);

/// A compile failure caused by the input or the settings. The message is one
/// line; the driver prefixes the file it concerns.
class CompileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace bspc
