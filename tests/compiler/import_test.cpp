// SPDX-License-Identifier: MIT
// bspc's import stage (compiler/src/import.cpp): node transforms.
#include <bspc/import.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace {

// A glTF 2.0 scene of one triangle facing +Y, (0,0,0) (0,0,1) (1,0,0),
// placed by two nodes: as it is, and with `secondNode` (a JSON node's
// transform properties).
std::filesystem::path writeTwoNodeGltf(const std::string& tag, const std::string& secondNode) {
  const std::filesystem::path dir = bspf::test::freshTempDir(tag);
  const float positions[9] = {0, 0, 0, 0, 0, 1, 1, 0, 0};
  const std::uint16_t indices[4] = {0, 1, 2, 0};  // the last pads to 4 bytes
  std::vector<char> bytes(sizeof positions + sizeof indices);
  std::memcpy(bytes.data(), positions, sizeof positions);
  std::memcpy(bytes.data() + sizeof positions, indices, sizeof indices);
  std::ofstream(dir / "triangle.bin", std::ios::binary).write(bytes.data(), bytes.size());
  std::ofstream(dir / "scene.gltf") << R"({
  "asset": {"version": "2.0"},
  "scene": 0,
  "scenes": [{"nodes": [0, 1]}],
  "nodes": [{"mesh": 0}, {"mesh": 0, )"
                                    << secondNode << R"(}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
  "buffers": [{"uri": "triangle.bin", "byteLength": 44}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                  {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
  "accessors": [
    {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
     "min": [0, 0, 0], "max": [1, 0, 1]},
    {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]
})";
  return dir / "scene.gltf";
}

Eigen::Vector3d faceNormal(const bspc::Mesh& mesh, std::size_t t) {
  const auto& tri = mesh.triangles[t];
  const Eigen::Vector3d a = mesh.vertices[tri[0]], b = mesh.vertices[tri[1]],
                        c = mesh.vertices[tri[2]];
  return (b - a).cross(c - a).normalized();
}

}  // namespace

TEST_CASE("a mirroring node transform keeps its triangles facing the way their surface does",
          "[compiler][import]") {
  for (const std::string mirror :
       {R"("scale": [-1, 1, 1], "translation": [5, 0, 0])", R"("scale": [1, 1, -1])",
        R"("matrix": [1,0,0,0, 0,1,0,0, 0,0,-2,0, 3,0,0,1])"}) {
    INFO(mirror);
    const bspc::Mesh mesh = bspc::importMesh(writeTwoNodeGltf("import-mirror", mirror), {});
    REQUIRE(mesh.triangles.size() == 2);
    // Mirrored in x or z, a floor triangle is still a floor facing up.
    CHECK(faceNormal(mesh, 0).isApprox(Eigen::Vector3d::UnitY()));
    CHECK(faceNormal(mesh, 1).isApprox(Eigen::Vector3d::UnitY()));
  }
}

TEST_CASE("a node transform that does not mirror keeps the file's winding", "[compiler][import]") {
  // Turned upside down by a rotation of 180 degrees about x (not a mirror):
  // the triangle then faces down, as the file says.
  const bspc::Mesh mesh = bspc::importMesh(
      writeTwoNodeGltf("import-rotate", R"("rotation": [1, 0, 0, 0], "translation": [0, 2, 0])"),
      {});
  REQUIRE(mesh.triangles.size() == 2);
  CHECK(faceNormal(mesh, 0).isApprox(Eigen::Vector3d::UnitY()));
  CHECK(faceNormal(mesh, 1).isApprox(-Eigen::Vector3d::UnitY()));
}

namespace {

// A Collada 1.4 file of one triangle, (0,0,0) (1,0,0) (0,1,0): counter-
// clockwise seen from +Z, so it faces +Z in the file's coordinates;
// `upAxis` is the <up_axis> element's text, or "" for none (Y_UP by the
// Collada specification).
std::filesystem::path writeCollada(const std::string& tag, const std::string& upAxis) {
  const std::filesystem::path path = bspf::test::freshTempDir(tag) / "triangle.dae";
  std::ofstream(path) << R"(<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
  <asset><unit name="meter" meter="1"/>)"
                      << (upAxis.empty() ? "" : "<up_axis>" + upAxis + "</up_axis>") << R"(</asset>
  <library_geometries><geometry id="g"><mesh>
    <source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array>
      <technique_common><accessor source="#pa" count="3" stride="3">
        <param name="X" type="float"/><param name="Y" type="float"/><param name="Z" type="float"/>
      </accessor></technique_common></source>
    <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>
    <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>
  </mesh></geometry></library_geometries>
  <library_visual_scenes><visual_scene id="s"><node id="n"><instance_geometry url="#g"/></node>
  </visual_scene></library_visual_scenes>
  <scene><instance_visual_scene url="#s"/></scene>
</COLLADA>
)";
  return path;
}

}  // namespace

TEST_CASE("a Collada file marked Z_UP is turned Y up once: --up z is not applied again, and said",
          "[compiler][import]") {
  const std::filesystem::path zUp = writeCollada("import-collada-z", "Z_UP");
  bspc::ImportSettings settings;
  SECTION("the default --up y: the importer's conversion alone, no warning") {
    const bspc::Mesh mesh = bspc::importMesh(zUp, settings);
    REQUIRE(mesh.triangles.size() == 1);
    REQUIRE(faceNormal(mesh, 0).isApprox(Eigen::Vector3d::UnitY(), 1e-9));
    REQUIRE(mesh.warnings.empty());
  }
  SECTION("--up z: not applied (it would turn the level upside down), with a warning") {
    settings.up = bspc::UpAxis::Z;
    const bspc::Mesh mesh = bspc::importMesh(zUp, settings);
    REQUIRE(faceNormal(mesh, 0).isApprox(Eigen::Vector3d::UnitY(), 1e-9));
    REQUIRE(mesh.warnings.size() == 1);
    REQUIRE_THAT(mesh.warnings[0], Catch::Contains("Collada") && Catch::Contains("--up z"));
  }
  SECTION("bspc prints the warning naming the file, and compiles") {
    const std::filesystem::path out = zUp.parent_path() / "out.bspf";
    const auto r = bspf::test::run("'" + bspf::test::bspcExecutable().string() + "' '" +
                                   zUp.string() + "' -o '" + out.string() + "' --up z -q");
    INFO(r.err);
    REQUIRE(r.status == 0);
    REQUIRE_THAT(r.err, Catch::StartsWith("bspc: warning: " + zUp.string() + ": the Collada") &&
                            Catch::EndsWith("not applied\n"));
    REQUIRE(std::filesystem::exists(out));
  }
}

TEST_CASE(
    "bspc's --up applies to a Collada file that declares no up axis (the importer left it as is)",
    "[compiler][import]") {
  bspc::ImportSettings settings;
  settings.up = bspc::UpAxis::Z;
  for (const std::string declared : {"", "Y_UP"}) {
    INFO("up_axis '" << declared << "'");
    const bspc::Mesh mesh = bspc::importMesh(writeCollada("import-collada-y", declared), settings);
    // +Z in the file is up: after --up z it faces +Y.
    REQUIRE(faceNormal(mesh, 0).isApprox(Eigen::Vector3d::UnitY(), 1e-9));
    REQUIRE(mesh.warnings.empty());
  }
}

TEST_CASE("the contained import gives the in-process import's mesh bit for bit",
          "[compiler][import]") {
  bspc::ImportSettings settings;
  settings.up = bspc::UpAxis::Z;
  settings.scale = 0.03125;
  for (const std::filesystem::path& path :
       {bspf::test::samplesDir() / "arena.obj",
        writeTwoNodeGltf("import-contained", R"("scale": [-1, 1, 1])")}) {
    INFO(path);
    const bspc::Mesh direct = bspc::importMesh(path, settings);
    const bspc::Mesh contained = bspc::importMeshContained(path, settings);
    REQUIRE(contained.vertices.size() == direct.vertices.size());
    REQUIRE(contained.triangles == direct.triangles);
    CHECK(std::memcmp(contained.vertices.data(), direct.vertices.data(),
                      direct.vertices.size() * sizeof(direct.vertices[0])) == 0);
  }
}

TEST_CASE("the contained import carries the import's warnings back", "[compiler][import]") {
  bspc::ImportSettings settings;
  settings.up = bspc::UpAxis::Z;
  const std::filesystem::path zUp = writeCollada("import-contained-warning", "Z_UP");
  const bspc::Mesh direct = bspc::importMesh(zUp, settings);
  const bspc::Mesh contained = bspc::importMeshContained(zUp, settings);
  REQUIRE(direct.warnings.size() == 1);
  CHECK(contained.warnings == direct.warnings);
}

TEST_CASE("the contained import reports the importer's own errors as importMesh does",
          "[compiler][import]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("import-contained-error");
  std::ofstream(dir / "points.obj") << "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  std::string direct, contained;
  try {
    bspc::importMesh(dir / "points.obj", {});
  } catch (const bspc::CompileError& e) {
    direct = e.what();
  }
  try {
    bspc::importMeshContained(dir / "points.obj", {});
  } catch (const bspc::CompileError& e) {
    contained = e.what();
  }
  CHECK_FALSE(direct.empty());
  CHECK(contained == direct);
}
