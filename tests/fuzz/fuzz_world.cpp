// SPDX-License-Identifier: MIT
// libFuzzer target: the loader, then queries and steps on what it accepts.
//
// The input is a whole blob. viewWorld must refuse it with a status or
// accept it; a blob it accepts must then be safe to use: the tree
// statistics, point, box and swept-volume queries, and a few frames of
// bodies standing near its triangles, stepped alone and as a crowd, with
// both collision methods. The checks beyond the sanitizers' are the
// runtime's promises: query results name real triangles and leaves, each
// once, and from valid inputs on a verified World the step never yields a
// non-finite position or velocity (movement.h): world_checks.h.
#include <bspf/world.h>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

#include "world_checks.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Exactly `size` bytes in their own allocation (new[] aligns to 16), so
  // AddressSanitizer catches a read one byte past the blob.
  std::vector<std::byte> bytes(size);
  if (size) std::memcpy(bytes.data(), data, size);
  const bspf::OpenResult opened = bspf::viewWorld(bytes);
  if (!opened) {
    bspf::fuzz::require(opened.status != bspf::LoadStatus::Ok,
                        "a refused blob has a failure status");
    bspf::fuzz::require(!opened.message.empty(), "a refused blob has a message");
    return 0;
  }
  bspf::fuzz::checkWorld(*opened.world);
  return 0;
}
