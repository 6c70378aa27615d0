// SPDX-License-Identifier: MIT
#include <bspc/mesh.h>

namespace bspc {

Mesh keepTriangles(const Mesh& mesh, const std::vector<bool>& keep) {
  Mesh out;
  std::vector<std::uint32_t> newIndex(mesh.vertices.size(), ~std::uint32_t(0));
  for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (!keep[t]) continue;
    std::array<std::uint32_t, 3> kept;
    for (int k = 0; k < 3; ++k) {
      std::uint32_t& index = newIndex[mesh.triangles[t][k]];
      if (index == ~std::uint32_t(0)) {
        index = std::uint32_t(out.vertices.size());
        out.vertices.push_back(mesh.vertices[mesh.triangles[t][k]]);
      }
      kept[k] = index;
    }
    out.triangles.push_back(kept);
  }
  carrySurfaces(mesh, keep, out);
  out.warnings = mesh.warnings;
  return out;
}

}  // namespace bspc
