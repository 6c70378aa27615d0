// SPDX-License-Identifier: MIT
// The velocity model of the step: friction, input and gravity before the
// move (futureVelocity), the contacts' response after it (respondToContacts).
#include "velocity.h"

#include <algorithm>

namespace bspf {

namespace detail {

// Removes (slide) or reflects (bounce) the velocity's component into each
// contact; a walkable contact stops the fall.
void respondToContacts(Body& body, const SlideResult& slide, float dt) {
  const float e = body.settings.restitution;
  // Below this normal speed a bounce is a resting contact, not a rebound:
  // one frame of gravity, so a resting body does not jitter.
  const float restingSpeed = 2.0f * body.settings.gravity * dt;
  for (int i = 0; i < slide.contactCount; ++i) {
    const Contact& c = slide.contacts[i];
    // A steep surface facing up (a rounded edge met low on the body, a
    // slope too steep to walk) stops a sliding body like a wall: removing
    // the velocity along its true normal would turn a fast run into a leap
    // over the obstacle. Bouncing bodies keep the true normal.
    Vec3 normal = c.normal;
    if (!c.walkable && e == 0 && normal.y() > 0) {
      const Vec3 level(normal.x(), 0, normal.z());
      if (level.squaredNorm() > 1e-6f) normal = level.normalized();
    }
    const float into = body.velocity.dot(normal);
    if (into >= 0) continue;
    const bool bounce = e > 0 && -into > restingSpeed;
    if (c.walkable && !bounce) {
      body.velocity.y() = std::max(body.velocity.y(), 0.0f);
    } else {
      body.velocity -= (1.0f + (bounce ? e : 0.0f)) * into * normal;
    }
  }
}

void futureVelocity(Body& body, const Vec3& force, float dt) {
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

}  // namespace detail

}  // namespace bspf
