// Blobs for benchmarks, compiled in memory.
#pragma once

#include <bspc/compile.h>

#include <cstdint>
#include <vector>

namespace bspf::bench {

/// A 1 m thick floor slab with its top at y = 0, spanning +-halfSize metres in
/// x and z, offset so (0, 0) to (2 halfSize, 2 halfSize) is inside.
inline std::vector<std::uint8_t> floorBlob(double halfSize) {
  bspc::Mesh m;
  const double lo = -10, hi = 2 * halfSize - 10;
  for (int i = 0; i < 8; ++i)
    m.vertices.emplace_back(i & 1 ? hi : lo, i & 2 ? 0.0 : -1.0, i & 4 ? hi : lo);
  m.triangles = {{0, 4, 6}, {0, 6, 2}, {1, 3, 7}, {1, 7, 5}, {0, 1, 5}, {0, 5, 4},
                 {2, 6, 7}, {2, 7, 3}, {0, 2, 3}, {0, 3, 1}, {4, 5, 7}, {4, 7, 6}};
  bspc::CompileReport report;
  return bspc::compileMesh(m, {}, "floor", report);
}

}  // namespace bspf::bench
