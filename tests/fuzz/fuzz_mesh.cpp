// SPDX-License-Identifier: MIT
// libFuzzer target: a mesh straight into bspc's stages, then the runtime.
//
// fuzz_obj reaches the stages through assimp, whose OBJ reader fills a
// 16 MB buffer for every file, which dominates its time. This target
// decodes the bytes into a mesh itself, over ten times as many inputs a
// second (docs/fuzzing.md), so the clean and tree stages see more shapes: compileMesh (clean, tree,
// planes, serialise, verification) must throw CompileError or return a blob
// the runtime accepts, and on that blob queries and steps with both methods
// must keep their promises (world_checks.h).
//
// The input: byte 0, the settings (bits 0-2: the leaf size - 1; bit 3:
// query reach 0; bits 4-5: the weld tolerance, 1e-4, 0, 0.05 or 0.5 m;
// bit 6: the split candidates, both or axis only; bit 7: raw floats, else
// coordinates are 16-bit integers in steps of 1/64 m (so points coincide,
// lie in planes and weld, as in real levels); byte 1: the vertex count;
// then the vertices (x, y, z), then triangles of three 16-bit indices, each
// taken modulo (vertex count + 1), so one index value is out of range.
#include <bspc/compile.h>
#include <bspf/world.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <span>
#include <string>
#include <vector>

#include "world_checks.h"

namespace {

class Reader {
 public:
  Reader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool has(std::size_t bytes) const { return size_ - at_ >= bytes; }
  template <typename T>
  T take() {
    T value{};
    if (has(sizeof(T))) {
      std::memcpy(&value, data_ + at_, sizeof(T));
      at_ += sizeof(T);
    } else {
      at_ = size_;
    }
    return value;
  }

 private:
  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in(data, size);
  const auto flags = in.take<std::uint8_t>();
  const auto vertexCount = in.take<std::uint8_t>();
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = 1u + (flags & 7u);
  settings.tree.queryReach = flags & 8u ? 0.0 : 1.0;
  constexpr double kWelds[] = {1e-4, 0.0, 0.05, 0.5};
  settings.clean.weldTolerance = kWelds[(flags >> 4) & 3u];
  if (flags & 64u) settings.tree.candidates = bspc::SplitCandidates::Axis;
  const bool rawFloats = flags & 128u;

  bspc::Mesh mesh;
  for (unsigned v = 0; v < vertexCount && in.has(1); ++v) {
    Eigen::Vector3d p;
    for (int axis = 0; axis < 3; ++axis)
      p[axis] = rawFloats ? static_cast<double>(in.take<float>())
                          : static_cast<double>(in.take<std::int16_t>()) / 64.0;
    mesh.vertices.push_back(p);
  }
  const std::uint32_t indexRange = static_cast<std::uint32_t>(mesh.vertices.size()) + 1;
  while (in.has(6)) {
    std::array<std::uint32_t, 3> t{};
    for (auto& index : t) index = in.take<std::uint16_t>() % indexRange;
    mesh.triangles.push_back(t);
  }

  std::vector<std::uint8_t> blob;
  try {
    bspc::CompileReport report;
    blob = bspc::compileMesh(mesh, settings, "fuzz-mesh", report);
  } catch (const bspc::CompileError& error) {
    const std::string message = error.what();
    bspf::fuzz::require(!message.empty() && message.find('\n') == std::string::npos,
                        "a CompileError is one line");
    return 0;
  }
  // compileMesh verified it; the checks use it as a game would.
  const bspf::OpenResult opened = bspf::viewWorld(std::as_bytes(std::span(blob)));
  bspf::fuzz::require(opened.world.has_value(), "bspc's blob opens");
  bspf::fuzz::checkWorld(*opened.world);
  return 0;
}
