// The body-against-body phase of stepBodies: overlapping bodies are pushed
// apart, each push a move against the level.
#include "body_phase.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <tuple>

#include "slide.h"

namespace bspf::detail {

void pushBodiesApart(const World& world, std::span<Body> bodies, StepScratch& scratch,
                     std::span<StepReport> reports) {
  auto reportOf = [&](std::size_t i) { return reports.empty() ? nullptr : &reports[i]; };
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
                recordSlide(r, push, false);
                ++r->bodyContacts;
              }
            }
          }
        }
  }
}

}  // namespace bspf::detail
