// SPDX-License-Identifier: MIT
// The velocity model of the movement step (stepBody's steps 1 and 3), exposed
// so the Bullet peer of the benchmarks (bench/bullet_peer.cpp) moves bodies
// by the very same rules. Private to the runtime: not part of the API.
#pragma once

#include <bspf/movement.h>

#include "slide.h"

namespace bspf::detail {

/// Step 1: friction (grounded or air) slows the horizontal velocity without
/// reversing it, the input force (xz only) accelerates it, the horizontal
/// speed is capped, and gravity pulls along -Y. Units: m/s, m/s^2, s.
void futureVelocity(Body& body, const Vec3& force, float dt);

/// Step 3: removes (slide) or reflects (bounce, restitution > 0) the
/// velocity's component into each of `slide`'s contacts; a walkable contact
/// only stops the fall.
void respondToContacts(Body& body, const SlideResult& slide, float dt);

}  // namespace bspf::detail
