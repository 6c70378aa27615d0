#include <bspf/movement.h>

#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>
#include <numbers>
#include <optional>
#include <tuple>

#include "narrow_phase.h"
#include "slide.h"
#include "velocity.h"

namespace bspf {

namespace {

struct Hit {
  std::uint32_t triangle;
  float facing;
};

// The triangle in the way of the move start -> end with the lowest facing
// value, if any.
std::optional<Hit> findBlockingTriangle(const World& world, const Vec3& start, const Vec3& end,
                                        EllipsoidRadii radii,
                                        std::span<const std::uint32_t> candidates) {
  const Vec3 move = end - start;
  const float moveLength = move.norm();
  const Vec3 direction = moveLength > 0 ? Vec3(move / moveLength) : Vec3::Zero();
  std::optional<Hit> best;
  for (const std::uint32_t t : candidates) {
    const schema::TrianglePlanes& planes = world.trianglePlanes()[t];
    const schema::Plane& face = planes.face();
    const detail::SideValues sides = detail::sideValues(face, start, end, radii);
    if (!detail::passesPreCheck(sides)) continue;
    const auto [reach, startSide, endSide] = sides;
    // Test the six planes where the centre crosses the offset plane (the
    // article leaves this position unspecified: testing the end lets fast
    // bodies skip small triangles). A body already within it is tested at
    // its start and at its end.
    bool inside;
    if (startSide >= reach) {
      const float t = (startSide - reach) / (startSide - endSide);
      inside = detail::insideGrownTriangle(planes, start + t * move, radii);
    } else {
      inside = detail::insideGrownTriangle(planes, start, radii) ||
               detail::insideGrownTriangle(planes, end, radii);
    }
    if (!inside) continue;
    const float facing = toVec3(face.normal()).dot(direction);
    if (!best || facing < best->facing || (facing == best->facing && t < best->triangle))
      best = Hit{t, facing};
  }
  return best;
}

// A surface the end was moved out of this step: the end must keep
// dot(normal, end) >= target, and is moved along `push` to get there.
struct Constraint {
  Vec3 normal;
  float target;
  Vec3 push;
};

float violation(const Constraint& c, const Vec3& end) { return c.target - c.normal.dot(end); }

// Moves `end` along the push directions of `set` (2 or 3 constraints) so it
// lies on all of them at once: the crease or corner they form. Returns false
// (and leaves `end`) when they are too close to parallel to meet, or when
// meeting them would pull the end into any of them.
template <int N>
bool meetConstraints(const std::array<const Constraint*, N>& set, float maxShift, Vec3& end) {
  Eigen::Matrix<float, N, N> m;
  Eigen::Matrix<float, N, 1> need;
  for (int r = 0; r < N; ++r) {
    for (int c = 0; c < N; ++c) m(r, c) = set[r]->normal.dot(set[c]->push);
    need(r) = violation(*set[r], end);
  }
  const Eigen::FullPivLU<Eigen::Matrix<float, N, N>> lu(m);
  if (!lu.isInvertible() || std::abs(lu.determinant()) < 1e-3f) return false;
  const Eigen::Matrix<float, N, 1> amount = lu.solve(need);
  if ((amount.array() < -1e-4f).any()) return false;
  Vec3 shift = Vec3::Zero();
  for (int c = 0; c < N; ++c) shift += amount(c) * set[c]->push;
  // Nearly parallel surfaces meet far away: going there would teleport the
  // body. Such a crease is left to the ordinary slides.
  if (!(shift.norm() <= maxShift)) return false;
  end += shift;
  return true;
}

// Moves the end out of blocking triangles until none blocks, or refuses the
// move after maxIterations slides. Walkable contacts push the end straight
// up rather than along the normal, so a body standing on a slope does not
// creep down it. When moving out of one surface puts the end back into a
// surface of an earlier slide (a crease, or a corner of three), the end goes
// to where they meet at once instead of bouncing between them, which would
// use up the iterations and refuse the move.
}  // namespace

SlideResult slideWithPlanes(const World& world, const Vec3& start, const Vec3& desiredEnd,
                            EllipsoidRadii radii, const MovementSettings& settings,
                            float walkableNormalY, StepScratch& scratch) {
  SlideResult result;
  result.end = desiredEnd;
  std::array<Constraint, kMaxReportedContacts> constraints;
  int constraintCount = 0;
  // A crease solution may move the end at most this far: a frame's travel
  // plus the body's size.
  const float maxShift = (desiredEnd - start).norm() + std::max(radii.xz, radii.y);
  for (int iteration = 0;; ++iteration) {
    collectCandidateTriangles(world, start, result.end, radii, scratch.sweep, scratch.candidates);
    const std::optional<Hit> hit =
        findBlockingTriangle(world, start, result.end, radii, scratch.candidates);
    if (!hit) return result;
    if (iteration == settings.maxIterations) {
      result.refused = true;
      result.end = start;
      return result;
    }
    const schema::Plane& face = world.trianglePlanes()[hit->triangle].face();
    const Vec3 normal = toVec3(face.normal());
    const bool walkable = normal.y() >= walkableNormalY;
    const Constraint added{normal, face.distance() + effectiveRadius(normal, radii) + settings.skin,
                           walkable ? Vec3::UnitY() : normal};
    result.end += added.push * (violation(added, result.end) / normal.dot(added.push));

    // The most recent earlier surfaces the end is back inside, if any.
    const Constraint* back[2] = {nullptr, nullptr};
    for (int i = constraintCount - 1; i >= 0 && !back[1]; --i) {
      if (violation(constraints[i], result.end) <= 1e-5f) continue;
      if (constraints[i].normal.dot(normal) > 0.9999f) continue;  // the same surface
      (back[0] ? back[1] : back[0]) = &constraints[i];
    }
    if (back[0]) {
      Vec3 meet = result.end;
      if (meetConstraints<2>({&added, back[0]}, maxShift, meet)) {
        result.end = meet;
        if (back[1] && violation(*back[1], meet) > 1e-5f &&
            meetConstraints<3>({&added, back[0], back[1]}, maxShift, meet))
          result.end = meet;
      }
    }
    if (constraintCount < kMaxReportedContacts) constraints[constraintCount++] = added;
    ++result.iterations;
    if (result.contactCount < kMaxReportedContacts)
      result.contacts[result.contactCount++] = {normal, walkable};
  }
}

namespace {

SlideResult slideAgainstLevel(const World& world, const Vec3& start, const Vec3& desiredEnd,
                              EllipsoidRadii radii, const MovementSettings& settings,
                              float walkableNormalY, StepScratch& scratch) {
  return settings.method == CollisionMethod::ExactSweep
             ? slideExact(world, start, desiredEnd, radii, settings, walkableNormalY, scratch)
             : slideWithPlanes(world, start, desiredEnd, radii, settings, walkableNormalY, scratch);
}

}  // namespace

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

namespace {

float walkableNormalY(const MovementSettings& s) {
  return std::cos(s.walkableSlopeDegrees * std::numbers::pi_v<float> / 180.0f);
}

// Adds a slide's figures to the report. Pushes between bodies add their
// contacts but not their iterations or refusals: those describe the body's
// own move.
void record(StepReport* report, const SlideResult& slide, bool ownMove) {
  if (!report) return;
  if (ownMove) {
    report->iterations += slide.iterations;
    report->refused = report->refused || slide.refused;
  }
  for (int i = 0; i < slide.contactCount && report->contactCount < kMaxReportedContacts; ++i)
    report->contactNormals[report->contactCount++] = slide.contacts[i].normal;
}

// How far a slide got along the horizontal direction of `move`, metres.
float horizontalProgress(const Vec3& start, const Vec3& end, const Vec3& move) {
  const Vec3 along(move.x(), 0, move.z());
  const float length = along.norm();
  return length > 0 ? (end - start).dot(along) / length : 0;
}

// Stairs: a grounded body whose horizontal move was blocked retries it lifted
// by maxStepHeight (up, across, then down onto the step), and keeps the retry
// when it lands on walkable ground further along than the plain slide. The
// slides are the narrow phase's own, so a step-up never enters a wall; a
// ceiling lower than the lift just lifts less.
void tryStepUp(const World& world, const Body& body, const Vec3& start, const Vec3& desiredEnd,
               float walkableY, StepScratch& scratch, SlideResult& slide) {
  const Vec3 move = desiredEnd - start;
  const Vec3 across(move.x(), 0, move.z());
  const float plainProgress = horizontalProgress(start, slide.end, move);
  // Only a move stopped short by something steep is retried.
  bool blocked = false;
  for (int i = 0; i < slide.contactCount; ++i) blocked = blocked || !slide.contacts[i].walkable;
  if (!blocked || across.norm() - plainProgress < 1e-4f) return;

  const MovementSettings& s = body.settings;
  const SlideResult up = slideAgainstLevel(world, start, start + Vec3(0, s.maxStepHeight, 0),
                                           body.radii, s, walkableY, scratch);
  const SlideResult over =
      slideAgainstLevel(world, up.end, up.end + across, body.radii, s, walkableY, scratch);
  // Down by the lift and by the move's own fall.
  const float drop = (up.end.y() - start.y()) + std::max(0.0f, -move.y());
  const SlideResult down = slideAgainstLevel(world, over.end, over.end - Vec3(0, drop, 0),
                                             body.radii, s, walkableY, scratch);
  auto walkable = [](const SlideResult& r) {
    return std::any_of(r.contacts.begin(), r.contacts.begin() + r.contactCount,
                       [](const Contact& c) { return c.walkable; });
  };
  // A rounded body (the exact sweep) comes down on the step's edge before
  // its centre is over the step: an edge contact facing up, higher than the
  // start, is standing on a step. (A steep slope's face still refuses.)
  const bool onStepEdge =
      !walkable(down) && down.end.y() > start.y() + 1e-3f &&
      std::any_of(down.contacts.begin(), down.contacts.begin() + down.contactCount,
                  [](const Contact& c) { return c.edge && c.normal.y() > 0; });
  if (!walkable(down) && !onStepEdge) return;
  // Never higher than the step height: a walkable response on the way down
  // (the planes method lifts a body onto a surface it reaches) could
  // otherwise carry it onto a ledge above the lift.
  if (up.refused || over.refused || down.refused ||
      down.end.y() > start.y() + s.maxStepHeight + s.skin ||
      horizontalProgress(start, down.end, move) <= plainProgress + 1e-4f)
    return;
  SlideResult stepped = down;
  stepped.iterations = up.iterations + over.iterations + down.iterations;
  stepped.contactCount = 0;
  for (const SlideResult* part : {&over, &down})
    for (int i = 0; i < part->contactCount && stepped.contactCount < kMaxReportedContacts; ++i)
      if (part != &down || !onStepEdge)
        stepped.contacts[stepped.contactCount++] = part->contacts[i];
  // Standing on the step's edge counts as standing on the step.
  if (onStepEdge && stepped.contactCount < kMaxReportedContacts)
    stepped.contacts[stepped.contactCount++] = {Vec3::UnitY(), true};
  slide = stepped;
}

[[maybe_unused]] bool settingsInRange(const Body& body) {
  const MovementSettings& s = body.settings;
  return body.radii.xz > 0 && body.radii.y > 0 && s.gravity >= 0 && s.groundFriction >= 0 &&
         s.airFriction >= 0 && s.maxHorizontalSpeed > 0 && s.walkableSlopeDegrees >= 0 &&
         s.walkableSlopeDegrees <= 89 && s.maxIterations >= 1 && s.maxIterations <= 32 &&
         s.restitution >= 0 && s.restitution <= 1 && s.skin > 0 && s.maxStepHeight >= 0 &&
         s.maxStepHeight <= 2 * body.radii.y;
}

}  // namespace

void stepBody(const World& world, Body& body, const Vec3& force, float dt, StepScratch& scratch,
              StepReport* report) {
  assert(dt > 0 && std::isfinite(dt));
  assert(settingsInRange(body));
  if (report) *report = StepReport{};

  detail::futureVelocity(body, force, dt);
  const Vec3 start = body.position;
  const float walkableY = walkableNormalY(body.settings);
  SlideResult slide = slideAgainstLevel(world, start, start + body.velocity * dt, body.radii,
                                        body.settings, walkableY, scratch);
  // A rounded body resting on a step's edge (not walkable ground, but
  // support) may step on as well.
  auto onEdge = [&slide] {
    return std::any_of(slide.contacts.begin(), slide.contacts.begin() + slide.contactCount,
                       [](const Contact& c) { return c.edge && c.normal.y() > 0; });
  };
  if (body.settings.maxStepHeight > 0 && (body.grounded || onEdge()))
    tryStepUp(world, body, start, start + body.velocity * dt, walkableY, scratch, slide);
  body.position = slide.end;
  detail::respondToContacts(body, slide, dt);
  body.grounded = std::any_of(slide.contacts.begin(), slide.contacts.begin() + slide.contactCount,
                              [](const Contact& c) { return c.walkable; });
  if (report) {
    record(report, slide, true);
    report->grounded = body.grounded;
  }
}

void stepBodies(const World& world, std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                StepScratch& scratch, std::span<StepReport> reports) {
  assert(forces.size() == bodies.size());
  assert(reports.empty() || reports.size() == bodies.size());
  auto reportOf = [&](std::size_t i) { return reports.empty() ? nullptr : &reports[i]; };
  for (std::size_t i = 0; i < bodies.size(); ++i)
    stepBody(world, bodies[i], forces[i], dt, scratch, reportOf(i));

  // Broad phase: a uniform grid with cells as wide as the widest body, so an
  // overlapping pair always sits in the same or neighbouring cells. Bodies
  // are sorted by cell key; each looks up the 27 cells around it.
  float cell = 0;
  for (const Body& b : bodies) cell = std::max({cell, 2 * b.radii.xz, 2 * b.radii.y});
  if (bodies.size() < 2 || cell <= 0) return;
  auto cellCoordinate = [&](float v) {
    return static_cast<std::int64_t>(std::floor(v / cell)) & 0x1fffff;  // 21 bits each
  };
  auto keyOf = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (std::uint64_t(x & 0x1fffff) << 42) | (std::uint64_t(y & 0x1fffff) << 21) |
           std::uint64_t(z & 0x1fffff);
  };
  const std::size_t n = bodies.size();
  scratch.cellKeys_.resize(n);
  scratch.order_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3& p = bodies[i].position;
    scratch.cellKeys_[i] =
        keyOf(cellCoordinate(p.x()), cellCoordinate(p.y()), cellCoordinate(p.z()));
    scratch.order_[i] = static_cast<std::uint32_t>(i);
  }
  std::sort(scratch.order_.begin(), scratch.order_.end(), [&](std::uint32_t a, std::uint32_t b) {
    return scratch.cellKeys_[a] != scratch.cellKeys_[b]
               ? scratch.cellKeys_[a] < scratch.cellKeys_[b]
               : a < b;
  });
  auto firstInCell = [&](std::uint64_t key) {
    return std::lower_bound(
        scratch.order_.begin(), scratch.order_.end(), key,
        [&](std::uint32_t body, std::uint64_t k) { return scratch.cellKeys_[body] < k; });
  };

  for (std::size_t i = 0; i < n; ++i) {
    Body& a = bodies[i];
    const std::int64_t cx = cellCoordinate(a.position.x()), cy = cellCoordinate(a.position.y()),
                       cz = cellCoordinate(a.position.z());
    for (std::int64_t dx = -1; dx <= 1; ++dx)
      for (std::int64_t dy = -1; dy <= 1; ++dy)
        for (std::int64_t dz = -1; dz <= 1; ++dz) {
          const std::uint64_t key = keyOf(cx + dx, cy + dy, cz + dz);
          for (auto it = firstInCell(key);
               it != scratch.order_.end() && scratch.cellKeys_[*it] == key; ++it) {
            const std::size_t j = *it;
            if (j <= i) continue;  // each pair once, lower index first
            Body& b = bodies[j];
            Vec3 apart = a.position - b.position;  // from b towards a
            float distance = apart.norm();
            if (distance <= 1e-6f) {
              apart = Vec3::UnitX();  // coincident: any fixed direction
              distance = 0;
            } else {
              apart /= distance;
            }
            const float overlap =
                effectiveRadius(apart, a.radii) + effectiveRadius(apart, b.radii) - distance;
            if (overlap <= 0) continue;
            // Each moves half the overlap away from the other, as a move
            // against the level (no gravity): a push never enters a wall.
            // Pushes are horizontal. Along the line between centres, a body
            // squeezed against a wall by a crowd was ratcheted upwards a
            // little every frame, until it stood on the wall's top and
            // walked out of the level; a body dropped onto another slides
            // off it instead of standing on its head.
            Vec3 level(apart.x(), 0, apart.z());
            level = level.squaredNorm() > 1e-12f ? Vec3(level.normalized()) : Vec3::UnitX();
            const float half = 0.5f * overlap + 0.5f * a.settings.skin;
            for (auto [body, sign, index] : {std::tuple{&a, 1.0f, i}, std::tuple{&b, -1.0f, j}}) {
              const SlideResult push = slideAgainstLevel(
                  world, body->position, body->position + sign * half * level, body->radii,
                  body->settings, walkableNormalY(body->settings), scratch);
              body->position = push.end;
              // Only the horizontal closing speed is removed: removing it
              // along a tilted line between centres would turn a fast
              // body's run into a jump over the other's shoulder.
              const Vec3 away = sign * level;
              const float closing = body->velocity.dot(away);
              if (closing < 0) body->velocity -= closing * away;
              if (StepReport* r = reportOf(index)) {
                record(r, push, false);
                ++r->bodyContacts;
              }
            }
          }
        }
  }
}

}  // namespace bspf
