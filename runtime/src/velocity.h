// SPDX-License-Identifier: MIT
// The velocity model of the movement step (stepBody's steps 1 and 3), exposed
// so the Bullet peer of the benchmarks (bench/bullet_peer.cpp) moves bodies
// by the very same rules. Private to the runtime: not part of the API.
#pragma once

#include <bspf/movement.h>

#include <Eigen/Core>
#include <algorithm>

#include "slide.h"

namespace bspf::detail {

/// Step 1: friction (grounded or air) slows the horizontal velocity without
/// reversing it, the input force (xz only) accelerates it, the horizontal
/// speed is capped, and gravity pulls along -Y. Units: m/s, m/s^2, s.
/// Inline: the step reads the velocity right after, and a call wrote it a
/// float at a time, which the step's wider load of it then waited for (a
/// failed store forward: 15% of stepOne's own samples, perf on walkers).
inline void futureVelocity(Body& body, const Vec3& force, float dt) {
  const MovementSettings& s = body.settings;
  Eigen::Vector2f horizontal(body.velocity.x(), body.velocity.z());
  const float speed = horizontal.norm();
  const float friction = body.grounded ? s.groundFriction : s.airFriction;
  if (speed > 0) horizontal *= std::max(0.0f, speed - friction * dt) / speed;
  horizontal += Eigen::Vector2f(force.x(), force.z()) * dt;
  const float limited = horizontal.norm();
  if (limited > s.maxHorizontalSpeed) horizontal *= s.maxHorizontalSpeed / limited;
  body.velocity.x() = horizontal.x();
  body.velocity.z() = horizontal.y();
  body.velocity.y() -= s.gravity * dt;
}

/// Step 3: removes (slide) or reflects (bounce, restitution > 0) the
/// velocity's component into each of `slide`'s contacts; a walkable contact
/// only stops the fall.
void respondToContacts(Body& body, const SlideResult& slide, float dt);

}  // namespace bspf::detail
