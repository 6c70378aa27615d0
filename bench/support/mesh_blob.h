// SPDX-License-Identifier: MIT
// Levels compiled in memory for the benchmarks and the stability scenes.
#pragma once

#include <bspc/compile.h>
#include <bspf/world.h>

#include <cstdint>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace bspf::bench {

/// A level compiled in memory: the blob in 8-byte aligned storage (as
/// viewWorld requires) and the World viewing it. Movable (the storage moves
/// with its buffer), not copyable. Throws bspc::CompileError for a mesh the
/// compiler rejects and std::runtime_error if the blob does not verify.
class CompiledLevel {
 public:
  CompiledLevel(const bspc::Mesh& mesh, const bspc::CompileSettings& settings,
                const std::string& name) {
    bspc::CompileReport report;
    const std::vector<std::uint8_t> bytes = bspc::compileMesh(mesh, settings, name, report);
    storage_.resize(bytes.size() / 8 + 1);
    std::memcpy(storage_.data(), bytes.data(), bytes.size());
    OpenResult opened =
        viewWorld({reinterpret_cast<const std::byte*>(storage_.data()), bytes.size()});
    if (!opened) throw std::runtime_error(name + ": " + opened.message);
    world_ = std::move(opened.world);
  }
  CompiledLevel(CompiledLevel&&) = default;
  CompiledLevel& operator=(CompiledLevel&&) = default;
  CompiledLevel(const CompiledLevel&) = delete;
  CompiledLevel& operator=(const CompiledLevel&) = delete;

  const World& world() const { return *world_; }

 private:
  std::vector<std::uint64_t> storage_;
  std::optional<World> world_;
};

/// A 1 m thick floor slab with its top at y = 0, spanning +-halfSize metres in
/// x and z, offset so (0, 0) to (2 halfSize, 2 halfSize) is inside.
inline bspc::Mesh floorMesh(double halfSize) {
  bspc::Mesh m;
  const double lo = -10, hi = 2 * halfSize - 10;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi : lo, i & 2 ? 0.0 : -1.0, i & 4 ? hi : lo);
  m.triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
  return m;
}

}  // namespace bspf::bench
