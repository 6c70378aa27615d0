// SPDX-License-Identifier: MIT
// bspc: compiles a mesh into a .bspf collision blob. Parses options into
// CompileSettings, runs the library, turns every failure into one line on
// stderr and a non-zero exit.
#include <bspc/compile.h>
#include <bspc/info.h>
#include <bspc/write.h>
#include <unistd.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <map>
#include <tuple>

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

// bspc::validate's message ("invalid setting: scale must be finite and > 0")
// with the option it is about and its value ("--scale '-1': must be finite
// and > 0").
std::string namingOption(const std::string& message, const bspc::CompileSettings& s) {
  const auto number = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%g", v);
    return std::string(text);
  };
  const std::tuple<const char*, const char*, double> kOptions[] = {
      {"scale", "--scale", s.import.scale},
      {"weld tolerance", "--weld", s.clean.weldTolerance},
      {"minimum triangle area", "--min-area", s.clean.minTriangleArea},
      {"max leaf triangles", "--max-leaf-triangles", s.tree.maxLeafTriangles},
      {"max depth", "--max-depth", s.tree.maxDepth},
      {"balance weight", "--balance-weight", s.tree.balanceWeight},
      {"split weight", "--split-weight", s.tree.splitWeight},
      {"query reach", "--query-reach", s.tree.queryReach},
      {"axis candidates", "--axis-candidates", s.tree.axisCandidatesPerAxis},
      {"triangle candidates", "--triangle-candidates", s.tree.triangleCandidates},
      {"body radii", "--body-radii", s.reach.radiusXZ},
      {"threads", "--threads", s.threads}};
  const std::string prefix = "invalid setting: ";
  if (message.rfind(prefix, 0) != 0) return message;
  const std::string rest = message.substr(prefix.size());
  for (const auto& [setting, option, value] : kOptions)
    if (rest.rfind(std::string(setting) + " ", 0) == 0)
      return std::string(option) + " '" + number(value) +
             "': " + rest.substr(std::string(setting).size() + 1);
  return message;
}

// CLI11's messages, said for people: "Could not convert: --scale = abc"
// becomes "--scale 'abc': not a valid number".
std::string readable(const std::string& message) {
  const std::string convert = "Could not convert: ";
  if (message.rfind(convert, 0) == 0) {
    const std::string rest = message.substr(convert.size());
    const std::size_t equals = rest.find(" = ");
    if (equals != std::string::npos)
      return rest.substr(0, equals) + " '" + rest.substr(equals + 3) + "': not a valid number";
  }
  return message;
}

// A compile allocates and frees arrays of megabytes stage after stage.
// glibc hands each such block back to the kernel when it is freed, so the
// next one is faulted in afresh, a page at a time, zeroed (oacmpctf3: 50,000
// page faults, about a sixth of the run). Kept in the heap instead, they
// are reused: a third fewer faults, tree and planes 11% faster there, for
// 15% more peak memory (kPeakBytesPerTriangle). A tool's choice, made here:
// the library leaves the process's allocator alone.
void keepFreedMemoryForReuse() {
#ifdef __GLIBC__
  constexpr int kLargest = 1 << 30;
  mallopt(M_MMAP_THRESHOLD, kLargest);
  mallopt(M_TRIM_THRESHOLD, kLargest);
#endif
}

}  // namespace

int main(int argc, char** argv) {
  keepFreedMemoryForReuse();
  CLI::App app{"bspc: compile a level mesh (any format assimp reads) into a .bspf collision blob",
               "bspc"};
  bspc::CompileSettings settings;
  std::string input, output, infoPath, statsJson, exportObj;
  bool quiet = false;

  app.set_version_flag("--version", "bspc " BSPF_VERSION " (format version " +
                                        std::to_string(bspf::kFormatVersion) + ")");
  app.add_option("input", input, "Source mesh: OBJ, glTF, FBX, PLY, ... (anything assimp reads)")
      ->type_name("FILE");
  app.add_option("-o,--output", output, "The .bspf file to write (replaced atomically)")
      ->type_name("FILE");
  app.add_option("--info", infoPath, "Verify a .bspf file and print its metadata and tree figures")
      ->type_name("FILE");
  std::string up = "y", candidates = "both";
  app.add_option("--up", up,
                 "Up axis of the source: x, y or z (the blob is always Y up). Not applied to a "
                 "Collada file that declares its own up axis: the importer turns it Y up")
      ->type_name("AXIS")
      ->capture_default_str();
  app.add_option("--scale", settings.import.scale, "Metres per source unit")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--weld", settings.clean.weldTolerance, "Weld tolerance, metres")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--min-area", settings.clean.minTriangleArea,
                 "Drop triangles below this area, square metres")
      ->type_name("M2")
      ->capture_default_str();
  app.add_option("--max-leaf-triangles", settings.tree.maxLeafTriangles,
                 "A node this small becomes a leaf")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--max-depth", settings.tree.maxDepth, "Deepest leaf (1 to 64)")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--balance-weight", settings.tree.balanceWeight,
                 "Split score weight of front/back imbalance")
      ->type_name("W")
      ->capture_default_str();
  app.add_option("--split-weight", settings.tree.splitWeight,
                 "Split score weight of triangles straddling the plane")
      ->type_name("W")
      ->capture_default_str();
  app.add_option("--query-reach", settings.tree.queryReach,
                 "Typical query size, metres: a split must pay for itself at this size")
      ->type_name("M")
      ->capture_default_str();
  app.add_option("--candidates", candidates, "Split planes tried: axis, triangle or both")
      ->type_name("WHERE")
      ->capture_default_str();
  app.add_option("--axis-candidates", settings.tree.axisCandidatesPerAxis,
                 "Axis-aligned candidates per axis")
      ->type_name("N")
      ->capture_default_str();
  app.add_option("--triangle-candidates", settings.tree.triangleCandidates,
                 "Triangle-plane candidates per node")
      ->type_name("N")
      ->capture_default_str();
  app.add_flag("--exhaustive-split-search", settings.tree.exhaustiveSplitSearch,
               "Count every split candidate on every triangle of a node (about a fifth more "
               "tree build time; by default a node of more than 128 triangles picks its 4 best "
               "candidates on a sample of 64)");
  app.add_option("--import-timeout", settings.import.timeoutSeconds,
                 "Seconds the importer may take before it is stopped")
      ->type_name("S")
      ->capture_default_str();
  std::uint64_t importMemoryMiB = 0;
  app.add_option("--import-memory", importMemoryMiB,
                 "MiB of address space the importer may use (0: 1 GiB + 64 x the file size)")
      ->type_name("MIB")
      ->check(CLI::Range(std::uint64_t{0}, std::uint64_t{1} << 40))
      ->capture_default_str();
  std::string reachFrom;
  std::vector<double> bodyRadii;
  app.add_option("--reach-from", reachFrom,
                 "Drop every face no body can touch from these points (body centres, metres, "
                 "one \"x y z\" a line): see README, \"Faces no body can touch\"")
      ->type_name("FILE");
  app.add_option("--body-radii", bodyRadii,
                 "The body --reach-from keeps faces for: horizontal and vertical radius, metres")
      ->expected(2)
      ->type_name("XZ Y")
      ->default_str("0.45 0.85");
  app.add_option("--threads", settings.threads,
                 "Threads for the stages after clean: face rules, reach, tree, planes (0: every "
                 "core); the blob is the same for any count")
      ->type_name("N")
      ->capture_default_str();
  bool keepCovered = false;
  app.add_flag("--keep-covered-faces", keepCovered,
               "Keep the faces lying against an opposite face of another solid (no body can "
               "touch them; dropped by default)");
  bool keepBuried = false;
  app.add_flag("--keep-buried-faces", keepBuried,
               "Keep the faces lying inside another closed solid (no body outside the solids "
               "can touch them; dropped by default)");
  app.add_option("--drop-surface", settings.clean.dropSurfaces,
                 "Leave out the triangles of this surface (material name; repeatable)")
      ->type_name("NAME")
      ->expected(1)
      ->allow_extra_args(false)
      ->take_all();
  app.add_option("--only-surface", settings.clean.onlySurfaces,
                 "Keep only the triangles of this surface (material name; repeatable)")
      ->type_name("NAME")
      ->expected(1)
      ->allow_extra_args(false)
      ->take_all();
  app.add_option("--stats-json", statsJson, "Also write the compile report as JSON to this file")
      ->type_name("FILE");
  app.add_option("--export-obj", exportObj,
                 "Also write the compiled collision model (what the runtime sees) as a Wavefront "
                 "OBJ to this file")
      ->type_name("FILE");
  app.add_flag("-q,--quiet", quiet, "Print nothing but errors and warnings");
  app.footer(R"(Examples:
  bspc level.obj -o level.bspf                   an OBJ in metres, Y up
  bspc q3dm1.obj -o q3dm1.bspf --up z --scale 0.03125
                                                 Quake units (1/32 m), Z up
  bspc scene.gltf -o scene.bspf --stats-json scene.json
                                                 also the compile report as JSON
  bspc level.obj -o level.bspf --drop-surface trigger --drop-surface water
                                                 leave two materials out
  bspc --info level.bspf                         verify a blob, print its figures

Exit status: 0 written; 1 the input could not be compiled or a file could
not be written (the error names the file, and no output is left); 2 a bad
command line (the error names the option).)");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    std::cerr << "bspc: error: " << readable(e.what()) << " (see bspc --help)\n";
    return 2;
  }
  // The option named, its value quoted, what it takes.
  const auto badValue = [](const std::string& option, const std::string& value,
                           const std::string& takes) {
    std::cerr << "bspc: error: " << option << " '" << value << "': " << takes
              << " (see bspc --help)\n";
    return 2;
  };
  const std::map<std::string, bspc::UpAxis> axes{
      {"x", bspc::UpAxis::X}, {"y", bspc::UpAxis::Y}, {"z", bspc::UpAxis::Z}};
  const std::map<std::string, bspc::SplitCandidates> candidateKinds{
      {"axis", bspc::SplitCandidates::Axis},
      {"triangle", bspc::SplitCandidates::Triangle},
      {"both", bspc::SplitCandidates::Both}};
  const std::string upLower = CLI::detail::to_lower(up),
                    candidatesLower = CLI::detail::to_lower(candidates);
  if (!axes.count(upLower)) return badValue("--up", up, "the up axis is x, y or z");
  if (!candidateKinds.count(candidatesLower))
    return badValue("--candidates", candidates, "takes axis, triangle or both");
  settings.import.up = axes.at(upLower);
  settings.tree.candidates = candidateKinds.at(candidatesLower);
  settings.import.memoryLimitBytes = importMemoryMiB << 20;
  if (!bodyRadii.empty()) {
    if (reachFrom.empty()) {
      std::cerr << "bspc: error: --body-radii needs --reach-from (see bspc --help)\n";
      return 2;
    }
    settings.reach.radiusXZ = bodyRadii[0];
    settings.reach.radiusY = bodyRadii[1];
  }
  if (!infoPath.empty()) return runInfo(infoPath);
  if (!settings.clean.dropSurfaces.empty() && !settings.clean.onlySurfaces.empty()) {
    std::cerr << "bspc: error: --drop-surface and --only-surface cannot be used together (see "
                 "bspc --help)\n";
    return 2;
  }
  settings.dropCoveredFaces = !keepCovered;
  settings.dropBuriedFaces = !keepBuried;
  if (input.empty() || output.empty()) {
    std::cerr << "bspc: error: need an input mesh and -o OUTPUT.bspf (see bspc --help)\n";
    return 2;
  }
  // An option out of range is a usage error (exit status 2), like one CLI11
  // refuses; compileFile checks the settings again, for library callers.
  try {
    bspc::validate(settings);
  } catch (const bspc::CompileError& e) {
    std::cerr << "bspc: error: " << namingOption(e.what(), settings) << " (see bspc --help)\n";
    return 2;
  }
  if (!quiet && ::isatty(STDERR_FILENO))
    settings.progress = [](std::string_view line) {
      std::cerr << "\r\033[Kbspc: " << line << std::flush;
    };

  if (!reachFrom.empty()) {
    try {
      settings.reach.from = bspc::readReachPoints(reachFrom);
    } catch (const bspc::CompileError& e) {
      std::cerr << "bspc: error: " << e.what() << "\n";
      return 1;
    }
  }

  // Ctrl-C or a kill during the compile removes the temporary files.
  bspc::removeTemporariesOnSignal();
  try {
    const bspc::CompileReport report =
        bspc::compileFile(input, output, settings, statsJson, exportObj);
    if (settings.progress) std::cerr << "\r\033[K";
    for (const std::string& warning : report.warnings)
      std::cerr << "bspc: warning: " << input << ": " << warning << "\n";
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
