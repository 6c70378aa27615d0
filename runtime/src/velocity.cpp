// SPDX-License-Identifier: MIT
// The velocity model of the step: friction, input and gravity before the
// move (futureVelocity, inline in velocity.h), the contacts' response after
// it (respondToContacts).
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

}  // namespace detail

}  // namespace bspf
