// SPDX-License-Identifier: MIT
// libFuzzer target: an OBJ file through bspc's stages.
//
// The input is the text of an OBJ file. It goes through the compiler
// library's stages as bspc runs them: importMesh (bspc's own reader or
// assimp reads it from a file, as bspc does; the two must agree), then compileMesh: clean, tree,
// planes, serialise, and the runtime's verification of the blob. Each stage must either throw
// CompileError (bad input: a one-line message) or succeed; anything else
// (a crash, a sanitizer report, another exception, a blob its own runtime
// refuses) is a finding. The tree settings vary with the input's size, so
// deep trees with one triangle a leaf are tried too.
#include <bspc/compile.h>
#include <bspc/import.h>
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <optional>
#include <string>

namespace {

// One file per process, rewritten for every input: importMesh reads paths.
const std::filesystem::path& inputPath() {
  static const std::filesystem::path path = [] {
    std::filesystem::path p = std::filesystem::temp_directory_path() /
                              ("bspf-fuzz-obj-" + std::to_string(::getpid()) + ".obj");
    std::atexit([] { std::remove(inputPath().c_str()); });
    return p;
  }();
  return path;
}

void writeInput(const std::uint8_t* data, std::size_t size) {
  std::FILE* file = std::fopen(inputPath().c_str(), "wb");
  if (!file || (size && std::fwrite(data, 1, size, file) != size) || std::fclose(file) != 0) {
    std::perror("fuzz_obj: cannot write the input file");
    std::abort();
  }
}

// bspc's own reader of plain OBJ files must read what assimp reads, bit
// for bit, or leave the file to assimp: a file it takes that assimp reads
// otherwise, or refuses, is a finding.
void checkPlainObjReader(const bspc::ImportSettings& settings) {
  const std::optional<bspc::Mesh> plain = bspc::importPlainObj(inputPath(), settings);
  if (!plain) return;
  bspc::ImportSettings assimpOnly = settings;
  assimpOnly.readPlainObj = false;
  bspc::Mesh assimps;
  try {
    assimps = bspc::importMesh(inputPath(), assimpOnly);
  } catch (const bspc::CompileError& error) {
    std::fprintf(stderr, "fuzz_obj: bspc's OBJ reader read a file assimp refuses: %s\n",
                 error.what());
    std::abort();
  }
  if (plain->vertices.size() != assimps.vertices.size() ||
      std::memcmp(plain->vertices.data(), assimps.vertices.data(),
                  assimps.vertices.size() * sizeof(assimps.vertices[0])) != 0 ||
      plain->triangles != assimps.triangles || plain->surfaces != assimps.surfaces ||
      plain->triangleSurfaces != assimps.triangleSurfaces) {
    std::fprintf(stderr, "fuzz_obj: bspc's OBJ reader and assimp read different meshes\n");
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  writeInput(data, size);
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = 1 + static_cast<std::uint32_t>(size % 8);
  settings.tree.queryReach = size % 2 ? 0.0 : 1.0;
  checkPlainObjReader(settings.import);
  try {
    const bspc::Mesh mesh = bspc::importMesh(inputPath(), settings.import);
    bspc::CompileReport report;
    bspc::compileMesh(mesh, settings, "fuzz.obj", report);
  } catch (const bspc::CompileError& error) {
    // Refused with a message: the defined outcome for bad input.
    const std::string message = error.what();
    if (message.empty() || message.find('\n') != std::string::npos) {
      std::fprintf(stderr, "fuzz_obj: not a one-line message: \"%s\"\n", message.c_str());
      std::abort();
    }
  }
  return 0;
}
