// SPDX-License-Identifier: MIT
// bspc/info.h: `bspc --info`, a verified blob described for people.
#pragma once

#include <bspf/world.h>

#include <string>

namespace bspc {

/// Metadata and tree statistics, one "name  value" line each.
std::string describeWorld(const bspf::World& world, const std::string& fileName);

}  // namespace bspc
