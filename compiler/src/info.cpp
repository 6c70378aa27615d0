// SPDX-License-Identifier: MIT
#include <bspc/info.h>

#include <iomanip>
#include <sstream>
#include <vector>

namespace bspc {

namespace {
std::string str(const flatbuffers::String* s) { return s ? s->str() : std::string("-"); }

std::string point(const bspf::schema::Vec3* v) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(3) << "(" << v->x() << ", " << v->y() << ", " << v->z()
      << ")";
  return out.str();
}
}  // namespace

std::string describeWorld(const bspf::World& world, const std::string& fileName) {
  const bspf::schema::World& blob = world.blob();
  const bspf::schema::BuildInfo* build = blob.build();
  const bspf::TreeStats tree = bspf::computeTreeStats(world);
  std::ostringstream out;
  out << std::fixed << std::setprecision(2);
  auto line = [&](const char* name) -> std::ostream& {
    return out << std::left << std::setw(24) << name;
  };
  line("file") << fileName << "\n";
  line("format version") << blob.format_version() << " (identifier " << bspf::kFileIdentifier
                         << ")\n";
  line("units") << "metres, Y up\n";
  line("bounds min") << point(blob.bounds_min()) << " m\n";
  line("bounds max") << point(blob.bounds_max()) << " m\n";
  if (build) {
    line("compiler") << str(build->compiler_version()) << "\n";
    line("source") << str(build->source_file()) << "\n";
    line("options") << str(build->options()) << "\n";
    line("input") << build->input_triangles() << " triangles, " << build->input_vertices()
                  << " vertices\n";
    line("cleaning") << build->welded_vertices() << " vertices welded, "
                     << build->dropped_degenerate() << " degenerate, " << build->dropped_zero_area()
                     << " zero-area, " << build->dropped_duplicate()
                     << " duplicate triangles dropped\n";
    if (build->dropped_by_surface() > 0)
      line("surface selection") << build->dropped_by_surface() << " triangles left out\n";
  }
  line("triangles") << world.triangles().size() << "\n";
  line("vertices") << world.vertices().size() << "\n";
  line("nodes") << tree.nodes << "\n";
  line("leaves") << tree.leaves << " (" << tree.emptyLeaves << " empty)\n";
  line("depth") << "max " << tree.depthMax << ", mean " << tree.depthMean << "\n";
  line("triangles per leaf") << "max " << tree.trianglesPerLeafMax << ", mean "
                             << tree.trianglesPerLeafMean << "\n";
  line("references per tri") << tree.referencesPerTriangle << "\n";
  // The surface table: id, triangles, name (quoted: a name may hold spaces).
  std::vector<std::uint32_t> counts(world.surfaceCount(), 0);
  for (const std::uint16_t surface : world.triangleSurfaces()) ++counts[surface];
  line("surfaces") << world.surfaceCount() << " (id, triangles, name)\n";
  for (std::uint32_t id = 0; id < world.surfaceCount(); ++id)
    out << "  " << std::right << std::setw(5) << id << std::setw(10) << counts[id] << "  \""
        << world.surfaceName(id) << "\"\n"
        << std::left;
  line("size") << world.bytes().size() << " bytes, " << tree.bytesPerTriangle << " per triangle\n";
  return out.str();
}

}  // namespace bspc
