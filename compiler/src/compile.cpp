// SPDX-License-Identifier: MIT
#include <bspc/build_tree.h>
#include <bspc/buried.h>
#include <bspc/compile.h>
#include <bspc/import.h>
#include <bspc/mesh_checks.h>
#include <bspc/planes.h>
#include <bspc/reach.h>
#include <bspc/write.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <functional>
#include <optional>
#include <sstream>
#include <system_error>
#include <thread>

#include "parallel.h"

namespace bspc {

namespace {

// Runs `stage`, adds its wall-clock seconds to `seconds` and the CPU seconds
// of this process's threads (std::clock) to `cpuSeconds`, returns its result.
template <typename Stage>
auto timed(double& seconds, double& cpuSeconds, Stage&& stage) {
  struct Stop {
    double &seconds, &cpuSeconds;
    std::chrono::steady_clock::time_point start = std::chrono::steady_clock::now();
    std::clock_t cpuStart = std::clock();
    ~Stop() {
      seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      cpuSeconds += double(std::clock() - cpuStart) / CLOCKS_PER_SEC;
    }
  } stop{seconds, cpuSeconds};
  return stage();
}

// The progress line: how far the whole compile is and the stage it is in,
// "47% build tree". Each stage owns a fixed span of the percentage, roughly
// its share of a compile's time; the tree build moves through its span.
void say(const CompileSettings& settings, int percent, std::string_view stage) {
  if (settings.progress) settings.progress(std::to_string(percent) + "% " + std::string(stage));
}
constexpr int kTreeFirstPercent = 20, kTreeLastPercent = 90;

// The threads of a compile: settings.threads, or every core.
int threadCount(const CompileSettings& settings) {
  if (settings.threads != 0) return static_cast<int>(settings.threads);
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
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

// The stages after import. `writeOut`, when given, writes the blob out (to
// a file committed only later) while the blob is verified: the two took
// 30 and 20 ms of oacmpctf3's compile one after the other.
std::vector<std::uint8_t> compileCleanStages(
    const Mesh& mesh, const CompileSettings& settings, const std::string& sourceName,
    CompileReport& report,
    const std::function<void(const std::vector<std::uint8_t>&)>& writeOut = {}) {
  const LimitSettings& limits = settings.limits;
  const std::uint64_t peak = kPeakBytesPerTriangle * mesh.triangles.size();
  if (limits.maxMemoryBytes != 0 && peak > limits.maxMemoryBytes)
    throw CompileError("too large: its compile would take about " + std::to_string(peak >> 20) +
                       " MiB of memory (" + std::to_string(mesh.triangles.size()) +
                       " triangles), over the limit of " +
                       std::to_string(limits.maxMemoryBytes >> 20) + " MiB; split the level");
  say(settings, 10, "clean");
  const Mesh cleaned = timed(report.seconds.clean, report.cpuSeconds.clean,
                             [&] { return cleanMesh(mesh, settings.clean, report.clean); });
  report.warnings = mesh.warnings;
  // Workers only when there is more than one thread to run on.
  std::optional<bspf::ThreadPool> pool;
  if (threadCount(settings) > 1) pool.emplace(threadCount(settings));
  bspf::ThreadPool* threads = pool ? &*pool : nullptr;
  // Both rules judge the cleaned mesh, whose solids are still closed:
  // dropping covered faces opens them.
  say(settings, kTreeFirstPercent, "drop covered and buried faces");
  std::vector<bool> keep(cleaned.triangles.size(), true);
  // Both rules and the mesh checks turn about the same edges: found once,
  // counted as edges.
  std::optional<SolidEdges> solidEdges;
  if (settings.dropCoveredFaces || settings.dropBuriedFaces)
    timed(report.seconds.edges, report.cpuSeconds.edges,
          [&] { solidEdges.emplace(cleaned, threads); });
  // The mesh checks count as cleaning; they need the closed pieces the next
  // stage opens.
  std::vector<std::string> warnings = timed(report.seconds.clean, report.cpuSeconds.clean, [&] {
    return solidEdges ? meshWarnings(*solidEdges) : meshWarnings(cleaned);
  });
  for (std::string& warning : warnings) report.warnings.push_back(std::move(warning));
  if (settings.dropCoveredFaces) {
    const std::vector<bool> covered = timed(report.seconds.edges, report.cpuSeconds.edges,
                                            [&] { return findCoveredFaces(*solidEdges, threads); });
    for (std::size_t t = 0; t < keep.size(); ++t) {
      keep[t] = !covered[t];
      report.edges.droppedCovered += covered[t];
    }
  }
  if (settings.dropBuriedFaces) {
    const std::vector<bool> buried = timed(report.seconds.buried, report.cpuSeconds.buried, [&] {
      return findBuriedFaces(*solidEdges, report.buried, threads);
    });
    for (std::size_t t = 0; t < keep.size(); ++t)
      if (buried[t] && keep[t]) {
        keep[t] = false;
        ++report.buried.dropped;
      }
  }
  // With both rules off the cleaned mesh as it is, vertex order included.
  solidEdges.reset();
  const bool dropsAny = settings.dropCoveredFaces || settings.dropBuriedFaces;
  const Mesh clean = timed(report.seconds.edges, report.cpuSeconds.edges,
                           [&] { return dropsAny ? keepTriangles(cleaned, keep) : cleaned; });
  if (clean.triangles.empty())
    throw CompileError(
        "no triangle is left: every face lies against an opposite face or inside another solid");
  // Fail fast: the tree can only add to this.
  checkBlobBytes(minimumBlobBytes(clean.vertices.size(), clean.triangles.size()), true, clean,
                 limits);
  // A copy only when the reach rule is on: the mesh can be most of the
  // compile's memory.
  Mesh dropped;
  if (!settings.reach.from.empty()) {
    say(settings, kTreeFirstPercent, "drop faces no body can reach");
    dropped = timed(report.seconds.reach, report.cpuSeconds.reach, [&] {
      return dropUnreachableFaces(clean, settings.reach, report.reach, report.warnings, threads);
    });
  }
  const Mesh& reached = settings.reach.from.empty() ? clean : dropped;
  say(settings, kTreeFirstPercent, "build tree");
  std::function<void(int)> treeProgress;
  int shown = kTreeFirstPercent;  // buildTree calls one at a time
  if (settings.progress)
    treeProgress = [&](int percent) {
      const int overall =
          kTreeFirstPercent + percent * (kTreeLastPercent - kTreeFirstPercent) / 100;
      if (overall > shown) say(settings, shown = overall, "build tree");
    };
  const BspTree tree = timed(report.seconds.buildTree, report.cpuSeconds.buildTree, [&] {
    return buildTree(reached, settings.tree, treeProgress, threads);
  });
  checkBlobBytes(
      estimateBlobBytes(reached.vertices.size(), reached.triangles.size(), tree.nodes.size(),
                        tree.leaves.size(), tree.leafTriangles.size()),
      true, reached, limits);
  say(settings, kTreeLastPercent, "precompute planes");
  const auto planes = timed(report.seconds.planes, report.cpuSeconds.planes, [&] {
    return computeTrianglePlanes(
        reached, meetablePlanes(classifyEdges(reached, threads), report.edges), threads);
  });
  say(settings, 95, "serialise");
  std::vector<std::uint8_t> blob = timed(report.seconds.write, report.cpuSeconds.write, [&] {
    return serializeWorld(reached, planes, tree, {sourceName, settings, report.clean});
  });

  checkBlobBytes(blob.size(), false, reached, limits);
  // bspc never writes a blob its own runtime would refuse (one written out
  // meanwhile is never committed).
  bspf::OpenResult opened;
  timed(report.seconds.write, report.cpuSeconds.write, [&] {
    runParallel(threads, writeOut ? 2 : 1, 1, [&](int, std::size_t first, std::size_t last) {
      for (std::size_t job = first; job < last; ++job) {
        if (job == 0)
          opened = bspf::viewWorld(std::as_bytes(std::span(blob)));
        else
          writeOut(blob);
      }
    });
  });
  if (!opened)
    throw CompileError("internal error: the compiled blob fails verification: " + opened.message);
  report.tree = bspf::computeTreeStats(*opened.world);
  report.triangles = static_cast<std::uint32_t>(reached.triangles.size());
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
                          const CompileSettings& settings, const std::filesystem::path& statsJson,
                          const std::filesystem::path& exportObj) {
  validate(settings);
  if (sameFile(input, output))
    throw CompileError(output.string() + ": the output would overwrite the input");
  if (!statsJson.empty() && sameFile(statsJson, input))
    throw CompileError(statsJson.string() + ": the stats file would overwrite the input");
  if (!statsJson.empty() && sameFile(statsJson, output))
    throw CompileError(statsJson.string() + ": the stats file would overwrite the output");
  if (!exportObj.empty()) {
    if (sameFile(exportObj, input))
      throw CompileError(exportObj.string() + ": the exported OBJ would overwrite the input");
    if (sameFile(exportObj, output))
      throw CompileError(exportObj.string() + ": the exported OBJ would overwrite the output");
    if (!statsJson.empty() && sameFile(exportObj, statsJson))
      throw CompileError(exportObj.string() + ": the exported OBJ would overwrite the stats file");
  }
  // Both temporaries first: a path that cannot be written fails before the
  // compile, and an interrupted compile leaves files the signal handler
  // (removeTemporariesOnSignal) knows of. All outputs are kept, or none.
  PendingFile blobFile(output);
  std::optional<PendingFile> statsFile, objFile;
  if (!statsJson.empty()) statsFile.emplace(statsJson);
  if (!exportObj.empty()) objFile.emplace(exportObj);
  CompileReport report;
  try {
    say(settings, 0, "import");
    const Mesh mesh = timed(report.seconds.import, report.cpuSeconds.import, [&] {
      return settings.import.contained ? importMeshContained(input, settings.import)
                                       : importMesh(input, settings.import);
    });
    const std::vector<std::uint8_t> blob =
        compileCleanStages(mesh, settings, input.filename().string(), report,
                           [&](const std::vector<std::uint8_t>& bytes) { blobFile.write(bytes); });
    timed(report.seconds.write, report.cpuSeconds.write, [&] {
      if (!objFile) return;
      // The model as the runtime reads it: from the verified blob.
      const bspf::OpenResult opened = bspf::viewWorld(std::as_bytes(std::span(blob)));
      const std::string obj =
          toObj(*opened.world,
                "bspc " BSPF_VERSION ": the collision model of " + input.filename().string());
      objFile->write({reinterpret_cast<const std::uint8_t*>(obj.data()), obj.size()});
    });
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
  if (objFile) objFile->commit();
  // The blob last: a stats file or OBJ that cannot be committed leaves no
  // blob.
  timed(report.seconds.write, report.cpuSeconds.write, [&] { blobFile.commit(); });
  return report;
}

#endif  // _WIN32

std::string toJson(const CompileReport& r) {
  std::ostringstream out;
  out.precision(6);
  out << "{\"seconds\":{\"import\":" << r.seconds.import << ",\"clean\":" << r.seconds.clean
      << ",\"edges\":" << r.seconds.edges << ",\"buried\":" << r.seconds.buried
      << ",\"build_tree\":" << r.seconds.buildTree << ",\"planes\":" << r.seconds.planes
      << ",\"reach\":" << r.seconds.reach << ",\"write\":" << r.seconds.write << "},"
      << "\"cpu_seconds\":{\"import\":" << r.cpuSeconds.import
      << ",\"clean\":" << r.cpuSeconds.clean << ",\"edges\":" << r.cpuSeconds.edges
      << ",\"buried\":" << r.cpuSeconds.buried << ",\"build_tree\":" << r.cpuSeconds.buildTree
      << ",\"planes\":" << r.cpuSeconds.planes << ",\"reach\":" << r.cpuSeconds.reach
      << ",\"write\":" << r.cpuSeconds.write << "},"
      << "\"clean\":{\"input_vertices\":" << r.clean.inputVertices
      << ",\"input_triangles\":" << r.clean.inputTriangles
      << ",\"welded_vertices\":" << r.clean.weldedVertices
      << ",\"dropped_degenerate\":" << r.clean.droppedDegenerate
      << ",\"dropped_zero_area\":" << r.clean.droppedZeroArea
      << ",\"dropped_duplicate\":" << r.clean.droppedDuplicate
      << ",\"dropped_by_surface\":" << r.clean.droppedBySurface
      << ",\"output_vertices\":" << r.clean.outputVertices
      << ",\"output_triangles\":" << r.clean.outputTriangles << "},"
      << "\"edges\":{\"dropped_covered\":" << r.edges.droppedCovered << ",\"open\":" << r.edges.open
      << ",\"convex\":" << r.edges.convex << ",\"concave\":" << r.edges.concave
      << ",\"coplanar\":" << r.edges.coplanar
      << ",\"skipped_edge_planes\":" << r.edges.skippedEdgePlanes << "},"
      << "\"buried\":{\"dropped\":" << r.buried.dropped << ",\"buried\":" << r.buried.buried
      << ",\"closed_pieces\":" << r.buried.closedPieces << ",\"containers\":" << r.buried.containers
      << "},"
      << "\"reach\":{\"applied\":" << (r.reach.applied ? "true" : "false")
      << ",\"dropped\":" << r.reach.dropped << ",\"cells\":" << r.reach.cells
      << ",\"reached_cells\":" << r.reach.reached << ",\"cell_metres\":" << r.reach.cellMetres
      << ",\"leaked\":" << (r.reach.leaked ? "true" : "false") << "},"
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
