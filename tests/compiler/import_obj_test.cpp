// SPDX-License-Identifier: MIT
// bspc's own reader of plain OBJ files (compiler/src/import_obj.cpp): the
// mesh assimp reads, bit for bit, and every other file left to assimp.
#include <bspc/import.h>

#include <catch2/catch.hpp>
#include <cstring>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace {

std::filesystem::path writeObj(const std::string& tag, const std::string& text) {
  const std::filesystem::path path = bspf::test::freshTempDir(tag) / "level.obj";
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// The import as assimp makes it: its mesh, or its error message.
struct Imported {
  std::optional<bspc::Mesh> mesh;
  std::string error;
};

Imported importWith(const std::filesystem::path& path, bspc::ImportSettings settings,
                    bool readPlainObj) {
  settings.readPlainObj = readPlainObj;
  settings.contained = false;
  Imported result;
  try {
    result.mesh = bspc::importMesh(path, settings);
  } catch (const bspc::CompileError& e) {
    result.error = e.what();
  }
  return result;
}

void requireSameMesh(const bspc::Mesh& mine, const bspc::Mesh& assimps) {
  REQUIRE(mine.vertices.size() == assimps.vertices.size());
  // Bit for bit, so -0 and +0 differ here.
  CHECK(std::memcmp(mine.vertices.data(), assimps.vertices.data(),
                    assimps.vertices.size() * sizeof(assimps.vertices[0])) == 0);
  CHECK(mine.triangles == assimps.triangles);
  CHECK(mine.surfaces == assimps.surfaces);
  CHECK(mine.triangleSurfaces == assimps.triangleSurfaces);
  CHECK(mine.warnings == assimps.warnings);
}

// A coordinate in one of the forms OBJ writers use, some rare.
// `barePoint`: also ".5", which assimp does not count as a number.
std::string randomCoordinate(std::mt19937& random, bool barePoint) {
  std::uniform_int_distribution<int> form(0, 9), digits(0, 20), sign(0, 3);
  std::string text = sign(random) == 0 ? "-" : sign(random) == 1 ? "+" : "";
  auto someDigits = [&](int count) {
    std::string d;
    for (int k = 0; k < count; ++k) d += char('0' + random() % 10);
    return d;
  };
  switch (form(random)) {
    case 0: return text + someDigits(1 + digits(random) % 6);        // an integer
    case 1: return text + someDigits(1 + digits(random) % 4) + ".";  // a trailing point
    case 2:  // up to 19 integer digits: more overflow assimp's integer, and it reads 0
      return text + someDigits(1 + digits(random) % 19) + "." + someDigits(1 + digits(random));
    case 3: return text + "0." + someDigits(1 + digits(random));
    case 4:
      return text + someDigits(2) + "." + someDigits(2) + "e" + (sign(random) ? "-" : "") +
             someDigits(1);
    case 5:
      if (barePoint) return text + "." + someDigits(3);
      [[fallthrough]];
    default: return text + someDigits(1 + digits(random) % 5) + "." + someDigits(5);
  }
}

}  // namespace

TEST_CASE("bspc's own OBJ reader gives the mesh assimp reads, bit for bit", "[compiler][import]") {
  const std::string text =
      "# a plain OBJ, as a map converter writes one\r\n"
      "v 58.12500 34.62500 0.87500\n"
      "v\t-58.1 -0.0 1e2\n"
      "\n"
      "v 0.000001 123456789.5 -7.\r\n"
      "f 1 2 3\n"
      "f -1 -3 -2   \n"
      "v 2 2 2\n"
      "f 4 1 -2\n"
      "f 1 5 2\n"  // a vertex defined after the face
      "v 1 0 0\n"
      "# the end, without a line end";
  const std::filesystem::path path = writeObj("import-obj-plain", text);
  for (const bspc::UpAxis up : {bspc::UpAxis::Y, bspc::UpAxis::Z, bspc::UpAxis::X}) {
    for (const double scale : {1.0, 0.03125, 0.0254}) {
      INFO("up " << int(up) << ", scale " << scale);
      bspc::ImportSettings settings;
      settings.up = up;
      settings.scale = scale;
      const std::optional<bspc::Mesh> mine = bspc::importPlainObj(path, settings);
      REQUIRE(mine);
      CHECK(mine->triangles.size() == 4);
      const Imported assimps = importWith(path, settings, false);
      REQUIRE(assimps.mesh);
      requireSameMesh(*mine, *assimps.mesh);
    }
  }
}

TEST_CASE("bspc's own OBJ reader parses every coordinate form as assimp does",
          "[compiler][import]") {
  std::mt19937 random(12);
  int plainFiles = 0;
  for (int file = 0; file < 40; ++file) {
    std::ostringstream text;
    const int vertices = 300;
    const bool barePoints = file % 4 == 0;
    for (int v = 0; v < vertices; ++v)
      text << "v " << randomCoordinate(random, barePoints) << ' '
           << randomCoordinate(random, barePoints) << ' ' << randomCoordinate(random, barePoints)
           << '\n';
    for (int f = 0; f + 2 < vertices; f += 3) text << "f " << f + 1 << ' ' << f + 2 << " -1\n";
    const std::filesystem::path path = writeObj("import-obj-numbers", text.str());
    INFO("file " << file << ":\n" << text.str());
    const Imported assimps = importWith(path, {}, false);
    const std::optional<bspc::Mesh> mine = bspc::importPlainObj(path, {});
    // A word assimp does not count as a number (".5") changes what it
    // reads: such a file must be left to it.
    if (barePoints) {
      CHECK_FALSE(mine);
      continue;
    }
    REQUIRE(mine);
    ++plainFiles;
    REQUIRE(assimps.mesh);
    requireSameMesh(*mine, *assimps.mesh);
  }
  CHECK(plainFiles == 30);
}

TEST_CASE("bspc's own OBJ reader leaves every other file to assimp, which reads it as before",
          "[compiler][import]") {
  const std::string triangle = "v 0 0 0\nv 1 0 0\nv 0 0 1\n";
  const std::vector<std::string> others = {
      "o box\n" + triangle + "f 1 2 3\n",                 // objects
      triangle + "usemtl stone\nf 1 2 3\n",               // materials
      triangle + "g wall\nf 1 2 3\n",                     // groups
      triangle + "vt 0 0\nf 1/1 2/1 3/1\n",               // texture coordinates
      triangle + "vn 0 1 0\nf 1//1 2//1 3//1\n",          // normals
      triangle + "v 1 0 1\nf 1 2 4 3\n",                  // a quad
      triangle + "f 1 2\n",                               // a line
      triangle + "f 1 2 \\\n3\n",                         // a line continuation
      triangle + "f 1 2 3\rf 3 2 1\n",                    // a lone carriage return
      triangle + "f 1 2 3\n# a \\\nf 3 2 1\n",            // a comment continued
      " " + triangle + "f 1 2 3\n",                       // a statement after a blank
      "\xEF\xBB\xBF" + triangle + "f 1 2 3\n",            // a byte order mark
      triangle + "f 1 2 3 # a comment\n",                 // a comment after a face
      triangle + "f 01 2 3\n",                            // a leading zero
      "v 0 0\nv 1 0 0\nv 0 0 1\nv 1 1 1\nf 1 2 3\n",      // a vertex of two numbers
      "v 0 0 0 1\nv 1 0 0 1\nv 0 0 1 1\nf 1 2 3\n",       // homogeneous vertices
      "v 0 0 0\nv 1 0 .5\nv 0 0 1\nf 1 2 3\n",            // a word assimp does not count
      triangle + "f 1 2 4\n",                             // an index out of range
      triangle + "f 0 1 2\n",                             // index 0
      triangle + "f 1 2 " + std::string(80, '8') + "\n",  // an index of 80 digits
      triangle + "f -4 -1 -2\n",                          // before the first vertex
      triangle,                                           // no face
      triangle + std::string("f 1 2 3\n\0", 9),           // a NUL byte
  };
  for (std::size_t k = 0; k < others.size(); ++k) {
    INFO("file " << k << ": " << others[k]);
    const std::filesystem::path path = writeObj("import-obj-other", others[k]);
    CHECK_FALSE(bspc::importPlainObj(path, {}));
    // importMesh then reads it with assimp: the same mesh or the same error.
    const Imported viaReader = importWith(path, {}, true);
    const Imported assimps = importWith(path, {}, false);
    CHECK(viaReader.error == assimps.error);
    REQUIRE(viaReader.mesh.has_value() == assimps.mesh.has_value());
    if (assimps.mesh) requireSameMesh(*viaReader.mesh, *assimps.mesh);
  }
  // Not a regular file, or none at all.
  CHECK_FALSE(bspc::importPlainObj(bspf::test::freshTempDir("import-obj-dir"), {}));
  CHECK_FALSE(bspc::importPlainObj(bspf::test::freshTempDir("import-obj-none") / "no.obj", {}));
}

TEST_CASE("the shared levels import by bspc's own OBJ reader as assimp reads them",
          "[compiler][import]") {
  BSPF_SKIP_WITHOUT_SHARED_LEVELS();
  const std::filesystem::path levels = bspf::test::sharedLevelsDir();
  for (const char* name : {"fan", "oa_dm4"}) {
    INFO(name);
    const std::filesystem::path path = levels / (std::string(name) + ".obj");
    const std::optional<bspc::Mesh> mine = bspc::importPlainObj(path, {});
    REQUIRE(mine);
    const Imported assimps = importWith(path, {}, false);
    REQUIRE(assimps.mesh);
    requireSameMesh(*mine, *assimps.mesh);
  }
}
