#include <bspc/build_tree.h>
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspc/planes.h>
#include <bspc/write.h>

#include <chrono>
#include <sstream>
#include <system_error>

namespace bspc {

namespace {

// Runs `stage`, adds its wall-clock seconds to `seconds`, returns its result.
template <typename Stage>
auto timed(double& seconds, Stage&& stage) {
  const auto start = std::chrono::steady_clock::now();
  struct Stop {
    double& seconds;
    std::chrono::steady_clock::time_point start;
    ~Stop() {
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
  } stop{seconds, start};
  return stage();
}

void say(const CompileSettings& settings, std::string_view line) {
  if (settings.progress) settings.progress(line);
}

std::vector<std::uint8_t> compileCleanStages(const Mesh& mesh, const CompileSettings& settings,
                                             const std::string& sourceName,
                                             CompileReport& report) {
  say(settings, "clean");
  const Mesh clean = timed(report.seconds.clean,
                           [&] { return cleanMesh(mesh, settings.clean, report.clean); });
  say(settings, "build tree");
  const BspTree tree = timed(report.seconds.buildTree,
                             [&] { return buildTree(clean, settings.tree, settings.progress); });
  say(settings, "precompute planes");
  const auto planes = timed(report.seconds.planes, [&] { return computeTrianglePlanes(clean); });
  say(settings, "serialise");
  std::vector<std::uint8_t> blob = timed(report.seconds.write, [&] {
    return serializeWorld(clean, planes, tree, {sourceName, settings, report.clean});
  });

  // bspc never writes a blob its own runtime would refuse.
  const bspf::OpenResult opened = bspf::viewWorld(std::as_bytes(std::span(blob)));
  if (!opened)
    throw CompileError("internal error: the compiled blob fails verification: " + opened.message);
  report.tree = bspf::computeTreeStats(*opened.world);
  report.triangles = static_cast<std::uint32_t>(clean.triangles.size());
  report.outputBytes = blob.size();
  return blob;
}

}  // namespace

std::vector<std::uint8_t> compileMesh(const Mesh& mesh, const CompileSettings& settings,
                                      const std::string& sourceName, CompileReport& report) {
  validate(settings);
  report = CompileReport{};
  return compileCleanStages(mesh, settings, sourceName, report);
}

CompileReport compileFile(const std::filesystem::path& input, const std::filesystem::path& output,
                          const CompileSettings& settings) {
  validate(settings);
  std::error_code error;
  if (std::filesystem::equivalent(input, output, error))
    throw CompileError(output.string() + ": the output would overwrite the input");
  CompileReport report;
  try {
    say(settings, "import");
    const Mesh mesh =
        timed(report.seconds.import, [&] { return importMesh(input, settings.import); });
    const std::vector<std::uint8_t> blob =
        compileCleanStages(mesh, settings, input.filename().string(), report);
    timed(report.seconds.write, [&] { writeFileAtomically(output, blob); });
  } catch (const CompileError& e) {
    const std::string what = e.what();
    if (what.rfind("cannot write ", 0) == 0) throw;  // already names the output
    throw CompileError(input.string() + ": " + what);
  }
  return report;
}

std::string toJson(const CompileReport& r) {
  std::ostringstream out;
  out.precision(6);
  out << "{\"seconds\":{\"import\":" << r.seconds.import << ",\"clean\":" << r.seconds.clean
      << ",\"build_tree\":" << r.seconds.buildTree << ",\"planes\":" << r.seconds.planes
      << ",\"write\":" << r.seconds.write << "},"
      << "\"clean\":{\"input_vertices\":" << r.clean.inputVertices
      << ",\"input_triangles\":" << r.clean.inputTriangles
      << ",\"welded_vertices\":" << r.clean.weldedVertices
      << ",\"dropped_degenerate\":" << r.clean.droppedDegenerate
      << ",\"dropped_zero_area\":" << r.clean.droppedZeroArea
      << ",\"dropped_duplicate\":" << r.clean.droppedDuplicate
      << ",\"output_vertices\":" << r.clean.outputVertices
      << ",\"output_triangles\":" << r.clean.outputTriangles << "},"
      << "\"tree\":{\"nodes\":" << r.tree.nodes << ",\"leaves\":" << r.tree.leaves
      << ",\"empty_leaves\":" << r.tree.emptyLeaves << ",\"depth_max\":" << r.tree.depthMax
      << ",\"depth_mean\":" << r.tree.depthMean
      << ",\"triangles_per_leaf_max\":" << r.tree.trianglesPerLeafMax
      << ",\"triangles_per_leaf_mean\":" << r.tree.trianglesPerLeafMean
      << ",\"references_per_triangle\":" << r.tree.referencesPerTriangle
      << ",\"bytes_per_triangle\":" << r.tree.bytesPerTriangle << "},"
      << "\"triangles\":" << r.triangles << ",\"output_bytes\":" << r.outputBytes << "}";
  return out.str();
}

}  // namespace bspc
