// bspc: compiles a mesh into a .bspf collision blob. Parses options into
// CompileSettings, runs the library, turns every failure into one line on
// stderr and a non-zero exit.
#include <bspc/compile.h>
#include <bspc/info.h>
#include <bspc/write.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <iostream>
#include <map>

namespace {

int runInfo(const std::string& path) {
  const bspf::OpenResult opened = bspf::openWorld(path);
  if (!opened) {
    std::cerr << "bspc: error: " << opened.message << "\n";
    return 1;
  }
  std::cout << bspc::describeWorld(*opened.world, path);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bspc: compile a level mesh (any format assimp reads) into a .bspf collision blob",
               "bspc"};
  bspc::CompileSettings settings;
  std::string input, output, infoPath, statsJson;
  bool quiet = false;

  app.set_version_flag("--version", "bspc " BSPF_VERSION " (format version " +
                                        std::to_string(bspf::kFormatVersion) + ")");
  app.add_option("input", input, "Source mesh: OBJ, glTF, FBX, PLY, ... (anything assimp reads)");
  app.add_option("-o,--output", output, "The .bspf file to write (replaced atomically)");
  app.add_option("--info", infoPath, "Verify a .bspf file and print its metadata and tree figures");
  app.add_option("--up", settings.import.up, "Up axis of the source: x, y or z")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, bspc::UpAxis>{
              {"x", bspc::UpAxis::X}, {"y", bspc::UpAxis::Y}, {"z", bspc::UpAxis::Z}},
          CLI::ignore_case))
      ->capture_default_str();
  app.add_option("--scale", settings.import.scale, "Metres per source unit")->capture_default_str();
  app.add_option("--weld", settings.clean.weldTolerance, "Weld tolerance, metres")
      ->capture_default_str();
  app.add_option("--min-area", settings.clean.minTriangleArea,
                 "Drop triangles below this area, square metres")
      ->capture_default_str();
  app.add_option("--max-leaf-triangles", settings.tree.maxLeafTriangles,
                 "A node this small becomes a leaf")
      ->capture_default_str();
  app.add_option("--max-depth", settings.tree.maxDepth, "Deepest leaf (1 to 64)")
      ->capture_default_str();
  app.add_option("--balance-weight", settings.tree.balanceWeight,
                 "Split score weight of front/back imbalance")
      ->capture_default_str();
  app.add_option("--split-weight", settings.tree.splitWeight,
                 "Split score weight of triangles straddling the plane")
      ->capture_default_str();
  app.add_option("--query-reach", settings.tree.queryReach,
                 "Typical query size, metres: a split must pay for itself at this size")
      ->capture_default_str();
  app.add_option("--candidates", settings.tree.candidates,
                 "Split planes tried: axis, triangle, both")
      ->transform(CLI::CheckedTransformer(
          std::map<std::string, bspc::SplitCandidates>{
              {"axis", bspc::SplitCandidates::Axis},
              {"triangle", bspc::SplitCandidates::Triangle},
              {"both", bspc::SplitCandidates::Both}},
          CLI::ignore_case))
      ->capture_default_str();
  app.add_option("--axis-candidates", settings.tree.axisCandidatesPerAxis,
                 "Axis-aligned candidates per axis")
      ->capture_default_str();
  app.add_option("--triangle-candidates", settings.tree.triangleCandidates,
                 "Triangle-plane candidates per node")
      ->capture_default_str();
  bool keepCovered = false;
  app.add_flag("--keep-covered-faces", keepCovered,
               "Keep the faces lying against an opposite face of another solid (no body can "
               "touch them; dropped by default)");
  app.add_option("--stats-json", statsJson, "Also write the compile report as JSON to this file");
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "bspc: error: " << e.what() << " (see bspc --help)\n";
    return 2;
  }
  if (!infoPath.empty()) return runInfo(infoPath);
  settings.dropCoveredFaces = !keepCovered;
  if (input.empty() || output.empty()) {
    std::cerr << "bspc: error: need an input mesh and -o OUTPUT.bspf (see bspc --help)\n";
    return 2;
  }
  // An option out of range is a usage error (exit status 2), like one CLI11
  // refuses; compileFile checks the settings again, for library callers.
  try {
    bspc::validate(settings);
  } catch (const bspc::CompileError& e) {
    std::cerr << "bspc: error: " << e.what() << " (see bspc --help)\n";
    return 2;
  }
  if (!quiet && ::isatty(STDERR_FILENO))
    settings.progress = [](std::string_view line) {
      std::cerr << "\r\033[K" << line << std::flush;
    };

  // Ctrl-C or a kill during the compile removes the temporary files.
  bspc::removeTemporariesOnSignal();
  try {
    const bspc::CompileReport report = bspc::compileFile(input, output, settings, statsJson);
    if (settings.progress) std::cerr << "\r\033[K";
    if (!quiet)
      std::cout << "bspc: wrote " << output << ": " << report.triangles << " triangles, "
                << report.outputBytes << " bytes, " << report.tree.leaves << " leaves, depth "
                << report.tree.depthMax << "\n";
    return 0;
  } catch (const bspc::CompileError& e) {
    if (settings.progress) std::cerr << "\r\033[K";
    std::cerr << "bspc: error: " << e.what() << "\n";
    return 1;
  } catch (const std::exception& e) {
    std::cerr << "bspc: error: " << input << ": " << e.what() << "\n";
    return 1;
  }
}
