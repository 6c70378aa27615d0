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

// The horizontal direction along which bodies `self` and `other` part when
// their centres give none (the same point, or one right above the other):
// fixed by the pair, opposite for the two, and spread around the circle over
// pairs so that a pile at one point spreads out in every direction. One of
// 256 directions, from a table: a pile's first frame needs millions.
Vec3 tieBreakDirection(std::uint32_t self, std::uint32_t other) {
  static const std::array<Vec3, 256> directions = [] {
    std::array<Vec3, 256> table;
    for (int k = 0; k < 256; ++k) {
      const float angle = float(k) * 2 * std::numbers::pi_v<float> / 256;
      table[k] = Vec3(std::cos(angle), 0, std::sin(angle));
    }
    return table;
  }();
  const std::uint32_t low = std::min(self, other), high = std::max(self, other);
  std::uint64_t z = (std::uint64_t(low) << 32 | high) + 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return (self == low ? 1.0f : -1.0f) * directions[(z ^ (z >> 31)) >> 56];
}

struct Pusher {
  float distance;
  std::uint32_t body;
  Vec3 apart;  ///< from the pusher's centre to this body's
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

std::array<std::int64_t, 3> BodyGrid::cellOf(const Vec3& p, std::array<int, 3>* nearerSide) const {
  const Vec3 scaled(p.x() / cellWidth_, p.y() / cellHeight_, p.z() / cellWidth_);
  std::array<std::int64_t, 3> cell;
  for (int axis = 0; axis < 3; ++axis) {
    const float c = std::floor(scaled[axis]);
    // Far beyond any level (or not a number), bodies share the edge cells of
    // keyOf: still correct, as every pair found is tested for overlap.
    cell[axis] = c > -1e9f && c < 1e9f ? std::int64_t(c) : 0;
    if (nearerSide) (*nearerSide)[axis] = scaled[axis] - c < 0.5f ? -1 : 1;
  }
  return cell;
}

std::uint64_t BodyGrid::keyOf(const std::array<std::int64_t, 3>& cell) {
  // 21 bits a coordinate: 2 million cells along each axis, about 1,900 km of
  // 0.9 m cells.
  constexpr std::int64_t kHalfRange = 1 << 20;
  auto bits = [](std::int64_t c) {
    return std::uint64_t(std::clamp(c, -kHalfRange, kHalfRange - 1) + kHalfRange);
  };
  return bits(cell[0]) << 42 | bits(cell[1]) << 21 | bits(cell[2]);
}

std::uint32_t BodyGrid::find(std::uint64_t key) const {
  const std::uint32_t mask = std::uint32_t(cells_.size() - 1);
  // splitmix64's finaliser: neighbouring cells differ in a few low bits of
  // each coordinate, which a plain multiplication spreads poorly.
  std::uint64_t h = (key ^ (key >> 30)) * 0xbf58476d1ce4e5b9ull;
  h = (h ^ (h >> 27)) * 0x94d049bb133111ebull;
  std::uint32_t slot = std::uint32_t(h ^ (h >> 31)) & mask;
  while (cells_[slot].key != key && cells_[slot].key != kFree) slot = (slot + 1) & mask;
  return slot;
}

void BodyGrid::build(std::span<const Body> bodies) {
  const std::size_t n = bodies.size();
  // Cells twice as wide as the widest body and twice as tall as the tallest:
  // the centres of two overlapping bodies are then less than half a cell
  // apart on each axis, so a body's overlaps lie in its own cell and the
  // neighbour on the nearer side along each axis (8 cells, not 27: each
  // look-up is a likely cache miss).
  cellWidth_ = cellHeight_ = 0;
  for (const Body& b : bodies) {
    cellWidth_ = std::max(cellWidth_, 4 * b.radii.xz);
    cellHeight_ = std::max(cellHeight_, 4 * b.radii.y);
  }
  if (!(cellWidth_ > 0)) cellWidth_ = 1;
  if (!(cellHeight_ > 0)) cellHeight_ = 1;
  // At most half full, so a look-up probes few slots.
  std::size_t size = 16;
  while (size < 2 * n) size *= 2;
  cells_.assign(size, {kFree, 0, 0});

  // A counting sort by cell: count, lay the cells out in table order, place
  // each body in its cell's next place (stable: index order within a cell).
  cellSlot_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t key = keyOf(cellOf(bodies[i].position));
    const std::uint32_t slot = find(key);
    cells_[slot].key = key;
    ++cells_[slot].count;
    cellSlot_[i] = slot;
  }
  std::uint32_t laid = 0;
  for (Cell& c : cells_) {
    c.first = laid;
    laid += c.count;
  }
  entries_.resize(n);
  slotOf_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    Cell& c = cells_[cellSlot_[i]];
    slotOf_[i] = c.first++;
    entries_[slotOf_[i]] = {bodies[i].position, bodies[i].radii, std::uint32_t(i)};
  }
  for (Cell& c : cells_) c.first -= c.count;
}

void pushBodiesApart(const World& world, const BodyGrid& grid, std::span<Body> bodies,
                     std::size_t first, std::size_t last, StepScratch& scratch,
                     std::span<StepReport> reports) {
  std::vector<detail::BodyCache>& caches = scratch.workspace().bodies;
  if (caches.size() < bodies.size()) caches.resize(bodies.size());
  detail::pushRange(world, grid, bodies, first, last, scratch, reports, caches);
}

namespace detail {

void pushRange(const World& world, const BodyGrid& grid, std::span<Body> bodies, std::size_t first,
               std::size_t last, StepScratch& scratch, std::span<StepReport> reports,
               std::span<BodyCache> caches) {
  if (grid.entries_.size() < 2) return;
  for (std::size_t i = first; i < last; ++i) {
    Body& body = bodies[i];
    const BodyGrid::Entry& self = grid.entries_[grid.slotOf_[i]];
    NearestPushers nearest;
    int examined = 0;
    auto examine = [&](const BodyGrid::Entry& other) {
      ++examined;
      const Vec3 apart = self.position - other.position;  // from the other towards this body
      // Overlapping ellipsoids overlap in their bounding boxes too: most
      // candidates of a walking crowd end here, before any square root.
      const float reachXZ = self.radii.xz + other.radii.xz;
      if (std::abs(apart.x()) >= reachXZ || std::abs(apart.z()) >= reachXZ ||
          std::abs(apart.y()) >= self.radii.y + other.radii.y)
        return;
      const float distance = apart.norm();
      // At one point they part horizontally (tieBreakDirection).
      const float overlap = distance > 1e-6f
                                ? effectiveRadius(apart / distance, self.radii) +
                                      effectiveRadius(apart / distance, other.radii) - distance
                                : reachXZ;
      if (overlap > 0) nearest.offer({distance > 1e-6f ? distance : 0, other.body, apart, overlap});
    };

    // Its own cell first, outwards from its own place (a cell's bodies sit
    // in index order): in a pile larger than the candidate cap, each body
    // meets the bodies nearest it in index order, not all the same few.
    const BodyGrid::Cell& own = grid.cells_[grid.cellSlot_[i]];
    const std::uint32_t slot = grid.slotOf_[i];
    for (std::uint32_t step = 1; examined < kMaxBodyCandidates; ++step) {
      const bool below = slot >= own.first + step, above = slot + step < own.first + own.count;
      if (!below && !above) break;
      if (below) examine(grid.entries_[slot - step]);
      if (above && examined < kMaxBodyCandidates) examine(grid.entries_[slot + step]);
    }
    // Then the 7 other cells that may hold an overlapping body.
    std::array<int, 3> side;
    const std::array<std::int64_t, 3> cell = grid.cellOf(self.position, &side);
    for (int corner = 1; corner < 8 && examined < kMaxBodyCandidates; ++corner) {
      const BodyGrid::Cell& around = grid.cells_[grid.find(BodyGrid::keyOf(
          {cell[0] + (corner & 1 ? side[0] : 0), cell[1] + (corner & 2 ? side[1] : 0),
           cell[2] + (corner & 4 ? side[2] : 0)}))];
      for (std::uint32_t e = around.first;
           e < around.first + around.count && examined < kMaxBodyCandidates; ++e)
        examine(grid.entries_[e]);
    }

    const std::span<const Pusher> pushers = nearest.all();
    if (pushers.empty()) continue;
    // Half of each overlap, plus half the skin so that the pair ends just
    // apart; the velocity loses only its horizontal closing speed: removing
    // it along a tilted line between centres would turn a fast body's run
    // into a jump over the other's shoulder.
    Vec3 push = Vec3::Zero();
    for (const Pusher& p : pushers) {
      const Vec3 level(p.apart.x(), 0, p.apart.z());
      const float length = level.norm();
      const Vec3 away = p.distance > 0 && length > 1e-6f ? Vec3(level / length)
                                                         : tieBreakDirection(self.body, p.body);
      push += (0.5f * p.overlap + 0.5f * body.settings.skin) * away;
      const float closing = body.velocity.dot(away);
      if (closing < 0) body.velocity -= closing * away;
    }
    // The push is a slide against the level with the body's own cache: its
    // step has just made it cover the body's surroundings.
    swapBodyCache(scratch, caches[i]);
    const SlideResult slide =
        slideAgainstLevel(world, body.position, body.position + push, body.radii, body.settings,
                          walkableNormalY(body.settings), scratch);
    swapBodyCache(scratch, caches[i]);
    body.position = slide.end;
    if (!reports.empty()) {
      recordSlide(&reports[i], slide, false);
      reports[i].bodyContacts += int(pushers.size());
    }
  }
}

}  // namespace detail

}  // namespace bspf
