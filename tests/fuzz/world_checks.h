// SPDX-License-Identifier: MIT
// The checks the fuzz targets run on a World the loader accepted: the
// runtime's promises beyond memory safety, which the sanitizers check.
#pragma once

#include <bspf/world.h>

namespace bspf::fuzz {

/// Prints "fuzz: broken promise: WHAT" and aborts (libFuzzer then saves the
/// input as a crash) unless `holds`.
void require(bool holds, const char* what);

/// On a verified World: the tree statistics; point, box and swept-volume
/// queries over the blob's bounds return leaves and triangles in range, each
/// triangle once; bodies placed just off up to 6 triangles spread over the
/// level, moving along them, stepped 4 frames alone (stepBody) and 4 as an
/// overlapping crowd (stepBodies: the body phase too), with each collision
/// method, keep finite positions and velocities (movement.h: from valid
/// inputs on a verified World the position and velocity stay finite).
void checkWorld(const World& world);

}  // namespace bspf::fuzz
