// SPDX-License-Identifier: MIT
#include <bspc/build_tree.h>
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspc/mesh_checks.h>
#include <bspc/planes.h>
#include <bspc/write.h>

#include <chrono>
#include <optional>
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

// Fails when the blob would be larger than the limit: `bytes` is what it
// would take at least (`least`) or once written.
void checkBlobBytes(std::uint64_t bytes, bool least, const Mesh& clean,
                    const LimitSettings& limits) {
  if (bytes <= limits.maxBlobBytes) return;
  throw CompileError("too large: its blob would take " + std::string(least ? "at least " : "") +
                     std::to_string(bytes) + " bytes (" + std::to_string(clean.triangles.size()) +
                     " triangles, " + std::to_string(clean.vertices.size()) +
                     " vertices after clean), over the limit of " +
                     std::to_string(limits.maxBlobBytes) + " bytes; split the level");
}

std::vector<std::uint8_t> compileCleanStages(const Mesh& mesh, const CompileSettings& settings,
                                             const std::string& sourceName, CompileReport& report) {
  const LimitSettings& limits = settings.limits;
  const std::uint64_t peak = kPeakBytesPerTriangle * mesh.triangles.size();
  if (limits.maxMemoryBytes != 0 && peak > limits.maxMemoryBytes)
    throw CompileError("too large: its compile would take about " + std::to_string(peak >> 20) +
                       " MiB of memory (" + std::to_string(mesh.triangles.size()) +
                       " triangles), over the limit of " +
                       std::to_string(limits.maxMemoryBytes >> 20) + " MiB; split the level");
  say(settings, "clean");
  const Mesh clean =
      timed(report.seconds.clean, [&] { return cleanMesh(mesh, settings.clean, report.clean); });
  // Fail fast: the tree can only add to this.
  checkBlobBytes(minimumBlobBytes(clean.vertices.size(), clean.triangles.size()), true, clean,
                 limits);
  report.warnings = mesh.warnings;
  for (std::string& warning : meshWarnings(clean)) report.warnings.push_back(std::move(warning));
  say(settings, "build tree");
  const BspTree tree = timed(report.seconds.buildTree,
                             [&] { return buildTree(clean, settings.tree, settings.progress); });
  checkBlobBytes(estimateBlobBytes(clean.vertices.size(), clean.triangles.size(), tree.nodes.size(),
                                   tree.leaves.size(), tree.leafTriangles.size()),
                 true, clean, limits);
  say(settings, "precompute planes");
  const auto planes = timed(report.seconds.planes, [&] { return computeTrianglePlanes(clean); });
  say(settings, "serialise");
  std::vector<std::uint8_t> blob = timed(report.seconds.write, [&] {
    return serializeWorld(clean, planes, tree, {sourceName, settings, report.clean});
  });

  checkBlobBytes(blob.size(), false, clean, limits);
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

// From a file to a file: assimp's import and PendingFile's POSIX output, so
// not in a Windows build of this library (tests/windows).
#ifndef _WIN32

namespace {

// Whether two paths name the same file, or would once created.
bool sameFile(const std::filesystem::path& a, const std::filesystem::path& b) {
  std::error_code error;
  if (std::filesystem::equivalent(a, b, error)) return true;
  const auto left = std::filesystem::weakly_canonical(a, error);
  if (error) return false;
  const auto right = std::filesystem::weakly_canonical(b, error);
  return !error && left == right;
}

}  // namespace

CompileReport compileFile(const std::filesystem::path& input, const std::filesystem::path& output,
                          const CompileSettings& settings, const std::filesystem::path& statsJson) {
  validate(settings);
  if (sameFile(input, output))
    throw CompileError(output.string() + ": the output would overwrite the input");
  if (!statsJson.empty() && sameFile(statsJson, input))
    throw CompileError(statsJson.string() + ": the stats file would overwrite the input");
  if (!statsJson.empty() && sameFile(statsJson, output))
    throw CompileError(statsJson.string() + ": the stats file would overwrite the output");
  // Both temporaries first: a path that cannot be written fails before the
  // compile, and an interrupted compile leaves files the signal handler
  // (removeTemporariesOnSignal) knows of. All outputs are kept, or none.
  PendingFile blobFile(output);
  std::optional<PendingFile> statsFile;
  if (!statsJson.empty()) statsFile.emplace(statsJson);
  CompileReport report;
  try {
    say(settings, "import");
    const Mesh mesh = timed(report.seconds.import, [&] {
      return settings.import.contained ? importMeshContained(input, settings.import)
                                       : importMesh(input, settings.import);
    });
    const std::vector<std::uint8_t> blob =
        compileCleanStages(mesh, settings, input.filename().string(), report);
    timed(report.seconds.write, [&] { blobFile.write(blob); });
  } catch (const CompileError& e) {
    const std::string what = e.what();
    if (what.rfind("cannot write ", 0) == 0) throw;  // already names the output
    throw CompileError(input.string() + ": " + what);
  }
  if (statsFile) {
    const std::string json = toJson(report) + "\n";
    statsFile->write({reinterpret_cast<const std::uint8_t*>(json.data()), json.size()});
    statsFile->commit();
  }
  // The blob last: a stats file that cannot be committed leaves no blob.
  timed(report.seconds.write, [&] { blobFile.commit(); });
  return report;
}

#endif  // _WIN32

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
      << ",\"dropped_by_surface\":" << r.clean.droppedBySurface
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
