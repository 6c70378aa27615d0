// The body-against-body phase of stepBodies: a hashed grid of the bodies'
// positions after the level phase, then, for each body independently, the
// sum of the pushes from its nearest overlapping bodies, applied as one move
// against the level.
#include <bspf/movement.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numbers>

#include "slide.h"

namespace bspf {

namespace {

std::int32_t cellCoordinate(float v, float cell) {
  const float c = std::floor(v / cell);
  // Far beyond any level (or not a number): one shared cell, still correct
  // (only slower) since every pair found is tested for overlap.
  return c > -1e9f && c < 1e9f ? static_cast<std::int32_t>(c) : 0;
}

std::uint32_t bucketOf(const std::array<std::int32_t, 3>& cell, std::uint32_t mask) {
  return (std::uint32_t(cell[0]) * 73856093u ^ std::uint32_t(cell[1]) * 19349663u ^
          std::uint32_t(cell[2]) * 83492791u) &
         mask;
}

// The horizontal direction along which bodies `self` and `other` part when
// their centres give none (the same point, or one right above the other):
// fixed by the pair, opposite for the two, and spread around the circle over
// pairs so that a pile at one point spreads out in every direction.
Vec3 tieBreakDirection(std::uint32_t self, std::uint32_t other) {
  const std::uint32_t low = std::min(self, other), high = std::max(self, other);
  std::uint64_t z = (std::uint64_t(low) << 32 | high) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  const float angle = float(z >> 40) * 0x1p-24f * 2 * std::numbers::pi_v<float>;
  const float sign = self == low ? 1.0f : -1.0f;
  return sign * Vec3(std::cos(angle), 0, std::sin(angle));
}

struct Pusher {
  float distance;
  std::uint32_t body;
  Vec3 away;  ///< horizontal unit direction from the pusher to this body
  float overlap;
};

// Keeps the kMaxBodyPushes nearest pushers, nearest first (ties: lower index).
class NearestPushers {
 public:
  void offer(const Pusher& p) {
    auto before = [](const Pusher& a, const Pusher& b) {
      return a.distance != b.distance ? a.distance < b.distance : a.body < b.body;
    };
    if (count_ == kMaxBodyPushes && !before(p, pushers_[count_ - 1])) return;
    int at = count_ < kMaxBodyPushes ? count_++ : count_ - 1;
    for (; at > 0 && before(p, pushers_[at - 1]); --at) pushers_[at] = pushers_[at - 1];
    pushers_[at] = p;
  }
  std::span<const Pusher> all() const { return {pushers_.data(), std::size_t(count_)}; }

 private:
  std::array<Pusher, kMaxBodyPushes> pushers_;
  int count_ = 0;
};

}  // namespace

void BodyGrid::build(std::span<const Body> bodies) {
  const std::size_t n = bodies.size();
  // Cells as wide as the widest body and as tall as the tallest: the centres
  // of two overlapping bodies are then less than one cell apart on each axis.
  cellWidth_ = cellHeight_ = 0;
  for (const Body& b : bodies) {
    cellWidth_ = std::max(cellWidth_, 2 * b.radii.xz);
    cellHeight_ = std::max(cellHeight_, 2 * b.radii.y);
  }
  if (!(cellWidth_ > 0)) cellWidth_ = 1;
  if (!(cellHeight_ > 0)) cellHeight_ = 1;
  std::uint32_t buckets = 16;
  while (buckets < 2 * n) buckets *= 2;
  bucketMask_ = buckets - 1;

  // A counting sort by bucket (stable: body index order within a bucket).
  auto cellOf = [&](const Vec3& p) {
    return std::array<std::int32_t, 3>{cellCoordinate(p.x(), cellWidth_),
                                       cellCoordinate(p.y(), cellHeight_),
                                       cellCoordinate(p.z(), cellWidth_)};
  };
  bucketStart_.assign(buckets + 1, 0);
  bucketOf_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    bucketOf_[i] = bucketOf(cellOf(bodies[i].position), bucketMask_);
    ++bucketStart_[bucketOf_[i] + 1];
  }
  for (std::uint32_t b = 0; b < buckets; ++b) bucketStart_[b + 1] += bucketStart_[b];
  // Each body's slot is the next free one of its bucket; bucketStart_[b]
  // serves as bucket b's cursor, then is restored from its neighbour.
  entries_.resize(n);
  slotOf_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint32_t slot = bucketStart_[bucketOf_[i]]++;
    slotOf_[i] = slot;
    entries_[slot] = {bodies[i].position, bodies[i].radii, std::uint32_t(i),
                      cellOf(bodies[i].position)};
  }
  for (std::uint32_t b = buckets; b > 0; --b) bucketStart_[b] = bucketStart_[b - 1];
  bucketStart_[0] = 0;
}

void pushBodiesApart(const World& world, const BodyGrid& grid, std::span<Body> bodies,
                     std::size_t first, std::size_t last, StepScratch& scratch,
                     std::span<StepReport> reports) {
  if (grid.entries_.size() < 2) return;
  for (std::size_t i = first; i < last; ++i) {
    Body& body = bodies[i];
    const BodyGrid::Entry& self = grid.entries_[grid.slotOf_[i]];
    NearestPushers nearest;
    int examined = 0;
    auto examine = [&](const BodyGrid::Entry& other) {
      ++examined;
      Vec3 apart = self.position - other.position;  // from the other towards this body
      float distance = apart.norm();
      Vec3 away(apart.x(), 0, apart.z());
      if (distance <= 1e-6f) {
        distance = 0;
        apart = away = tieBreakDirection(self.body, other.body);
      } else {
        apart /= distance;
        away = away.squaredNorm() > 1e-12f ? Vec3(away.normalized())
                                           : tieBreakDirection(self.body, other.body);
      }
      const float overlap =
          effectiveRadius(apart, self.radii) + effectiveRadius(apart, other.radii) - distance;
      if (overlap > 0) nearest.offer({distance, other.body, away, overlap});
    };

    // Its own cell first, outwards from its own slot (bodies of the same
    // bucket sit in index order): in a pile larger than the candidate cap,
    // each body meets the bodies nearest it in index order, not all the same
    // few.
    const std::uint32_t bucket = bucketOf(self.cell, grid.bucketMask_);
    const std::uint32_t begin = grid.bucketStart_[bucket], end = grid.bucketStart_[bucket + 1];
    const std::uint32_t slot = grid.slotOf_[i];
    for (std::uint32_t step = 1; examined < kMaxBodyCandidates; ++step) {
      const bool below = slot >= begin + step, above = slot + step < end;
      if (!below && !above) break;
      if (below && examined < kMaxBodyCandidates) {
        const BodyGrid::Entry& other = grid.entries_[slot - step];
        if (other.cell == self.cell) examine(other);
      }
      if (above && examined < kMaxBodyCandidates) {
        const BodyGrid::Entry& other = grid.entries_[slot + step];
        if (other.cell == self.cell) examine(other);
      }
    }
    // Then the 26 neighbouring cells.
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          if ((dx == 0 && dy == 0 && dz == 0) || examined >= kMaxBodyCandidates) continue;
          const std::array<std::int32_t, 3> cell{self.cell[0] + dx, self.cell[1] + dy,
                                                 self.cell[2] + dz};
          const std::uint32_t b = bucketOf(cell, grid.bucketMask_);
          for (std::uint32_t e = grid.bucketStart_[b];
               e < grid.bucketStart_[b + 1] && examined < kMaxBodyCandidates; ++e)
            if (grid.entries_[e].cell == cell) examine(grid.entries_[e]);
        }

    const std::span<const Pusher> pushers = nearest.all();
    if (pushers.empty()) continue;
    // Half of each overlap, plus half the skin so that the pair ends just
    // apart; the velocity loses only its horizontal closing speed: removing
    // it along a tilted line between centres would turn a fast body's run
    // into a jump over the other's shoulder.
    Vec3 push = Vec3::Zero();
    for (const Pusher& p : pushers) {
      push += (0.5f * p.overlap + 0.5f * body.settings.skin) * p.away;
      const float closing = body.velocity.dot(p.away);
      if (closing < 0) body.velocity -= closing * p.away;
    }
    const SlideResult slide =
        slideAgainstLevel(world, body.position, body.position + push, body.radii, body.settings,
                          walkableNormalY(body.settings), scratch);
    body.position = slide.end;
    if (!reports.empty()) {
      recordSlide(&reports[i], slide, false);
      reports[i].bodyContacts += int(pushers.size());
    }
  }
}

}  // namespace bspf
