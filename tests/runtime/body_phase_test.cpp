// SPDX-License-Identifier: MIT
// The body-against-body phase (runtime/src/body_phase.cpp) and stepping many
// bodies on several threads (stepBodies with a ThreadPool, and the phases a
// game's job system drives itself).
#include <bspf/movement.h>
#include <bspf/thread_pool.h>

#include <algorithm>
#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <limits>
#include <memory>
#include <random>
#include <thread>
#include <vector>

#include "support/test_support.h"

using bspf::Body;
using bspf::Vec3;

namespace {

constexpr float kDt = 1.0f / 60.0f;

// A 40 m floor with a 10 m walled yard on it and a pillar in the yard.
bspc::Mesh yard() {
  bspc::Mesh mesh = bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20});
  bspf::test::append(mesh, bspf::test::boxMesh({-6, 0, -6}, {6, 2, -5}));
  bspf::test::append(mesh, bspf::test::boxMesh({-6, 0, 5}, {6, 2, 6}));
  bspf::test::append(mesh, bspf::test::boxMesh({-6, 0, -5}, {-5, 2, 5}));
  bspf::test::append(mesh, bspf::test::boxMesh({5, 0, -5}, {6, 2, 5}));
  bspf::test::append(mesh, bspf::test::boxMesh({0.5, 0, 0.5}, {1.5, 2, 1.5}));
  return mesh;
}

// 300 bodies of three sizes packed in the yard, some in the air, some sharing
// a point, each walking its own way.
struct Crowd {
  std::vector<Body> bodies;
  std::vector<Vec3> forces;
};
// Adds the crowd's body number `i` at `position`: of three sizes by i, and
// walking in a direction of its own (golden-angle steps).
void addCrowdBody(Crowd& crowd, int i, const Vec3& position, bspf::CollisionMethod method) {
  Body b;
  b.position = position;
  b.radii = i % 3 == 0 ? bspf::EllipsoidRadii{0.3f, 0.5f} : bspf::EllipsoidRadii{0.45f, 0.85f};
  if (i % 7 == 0) b.radii = {0.6f, 1.0f};
  b.settings.method = method;
  crowd.bodies.push_back(b);
  const float angle = 2.399963f * float(i);
  crowd.forces.emplace_back(std::cos(angle) * 60, 0, std::sin(angle) * 60);
}

Crowd packedCrowd(bspf::CollisionMethod method) {
  Crowd crowd;
  for (int i = 0; i < 300; ++i) {
    const int k = i % 100;
    addCrowdBody(crowd, i,
                 Vec3(-4.2f + 0.85f * float(k % 10), 0.9f + 0.4f * float(i / 100),
                      -4.2f + 0.85f * float(k / 10)),
                 method);
  }
  return crowd;
}

bool sameBits(const Vec3& a, const Vec3& b) { return (a.array() == b.array()).all(); }

void requireSameFrame(std::span<const Body> expected, std::span<const Body> actual,
                      std::span<const bspf::StepReport> expectedReports,
                      std::span<const bspf::StepReport> actualReports) {
  REQUIRE(expected.size() == actual.size());
  for (std::size_t i = 0; i < expected.size(); ++i) {
    INFO("body " << i);
    REQUIRE(sameBits(expected[i].position, actual[i].position));
    REQUIRE(sameBits(expected[i].velocity, actual[i].velocity));
    REQUIRE(expected[i].grounded == actual[i].grounded);
    REQUIRE(expectedReports[i].bodyContacts == actualReports[i].bodyContacts);
    REQUIRE(expectedReports[i].contactCount == actualReports[i].contactCount);
    REQUIRE(expectedReports[i].iterations == actualReports[i].iterations);
    REQUIRE(expectedReports[i].stoppedByBody == actualReports[i].stoppedByBody);
  }
}

// Steps `makeCrowd()` for `frames` frames with stepBodies on one thread and
// on pools of 1 to `maxThreads` threads, requiring the same frame from each;
// returns the body contacts and the bodies stopped by the sweep, summed over
// the frames.
template <typename MakeCrowd>
std::pair<int, int> requireSameOnThreads(MakeCrowd makeCrowd, int frames, int maxThreads) {
  const bspf::test::CompiledMesh level(yard());
  Crowd reference = makeCrowd();
  std::vector<bspf::StepReport> referenceReports(reference.bodies.size());
  bspf::StepScratch scratch;
  std::vector<Crowd> threaded;
  std::vector<std::unique_ptr<bspf::ThreadPool>> pools;
  std::vector<std::vector<bspf::StepScratch>> scratches;
  std::vector<std::vector<bspf::StepReport>> reports;
  for (int threads = 1; threads <= maxThreads; ++threads) {
    threaded.push_back(makeCrowd());
    pools.push_back(std::make_unique<bspf::ThreadPool>(threads));
    scratches.emplace_back(threads);
    reports.emplace_back(reference.bodies.size());
  }
  int contacts = 0, stopped = 0;
  for (int frame = 0; frame < frames; ++frame) {
    bspf::stepBodies(level.world, reference.bodies, reference.forces, kDt, scratch,
                     referenceReports);
    for (const auto& r : referenceReports) contacts += r.bodyContacts, stopped += r.stoppedByBody;
    for (std::size_t t = 0; t < threaded.size(); ++t) {
      INFO("frame " << frame << ", " << t + 1 << " threads");
      bspf::stepBodies(level.world, threaded[t].bodies, threaded[t].forces, kDt, *pools[t],
                       scratches[t], reports[t]);
      requireSameFrame(reference.bodies, threaded[t].bodies, referenceReports, reports[t]);
    }
  }
  return {contacts, stopped};
}

}  // namespace

TEST_CASE("stepping a crowd on 1, 2, 3 or 4 threads gives bit-identical trajectories",
          "[runtime][threads]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO((method == bspf::CollisionMethod::Planes ? "planes" : "exact"));
  const int contacts = requireSameOnThreads([method] { return packedCrowd(method); }, 40, 4).first;
  REQUIRE(contacts > 300);  // the crowd is dense: the body phase did work
}

TEST_CASE("a game's own split of the two phases gives the same frame as stepBodies",
          "[runtime][threads]") {
  const bspf::test::CompiledMesh level(yard());
  Crowd reference = packedCrowd(bspf::CollisionMethod::Planes);
  Crowd split = reference;
  const std::size_t n = reference.bodies.size();
  std::vector<bspf::StepReport> referenceReports(n), splitReports(n);
  bspf::StepScratch scratch, other;
  bspf::BodyGrid grid;
  // Uneven ranges, run last first, as jobs may finish in any order.
  const std::vector<std::size_t> cuts{0, 7, 100, 101, 230, n};
  for (int frame = 0; frame < 20; ++frame) {
    bspf::stepBodies(level.world, reference.bodies, reference.forces, kDt, scratch,
                     referenceReports);
    for (std::size_t c = cuts.size() - 1; c > 0; --c) {
      const std::size_t first = cuts[c - 1], count = cuts[c] - first;
      bspf::stepBodiesAgainstLevel(level.world, std::span(split.bodies).subspan(first, count),
                                   std::span(split.forces).subspan(first, count), kDt, other,
                                   std::span(splitReports).subspan(first, count));
    }
    grid.build(split.bodies);
    REQUIRE(grid.size() == n);
    for (std::size_t c = cuts.size() - 1; c > 0; --c)
      bspf::pushBodiesApart(level.world, grid, split.bodies, cuts[c - 1], cuts[c], other,
                            splitReports);
    INFO("frame " << frame);
    requireSameFrame(reference.bodies, split.bodies, referenceReports, splitReports);
  }
}

TEST_CASE(
    "a job system's two threads, each frame taking any of the ranges and building their own "
    "grids, give stepBodies's frames and keep every body's tree query",
    "[runtime][threads]") {
  const bspf::test::CompiledMesh level(yard());
  Crowd reference = packedCrowd(bspf::CollisionMethod::Planes);
  Crowd jobs = reference, alone = reference;
  const std::size_t n = reference.bodies.size();
  std::vector<bspf::StepReport> referenceReports(n), jobReports(n), aloneReports(n);
  bspf::StepScratch scratch, aloneScratch;
  std::array<bspf::StepScratch, 2> threadScratches;
  bspf::BodyCaches shared, aloneCaches;
  shared.resize(n);
  aloneCaches.resize(n);
  bspf::BodyGrid prepared, aloneGrid;
  std::array<bspf::BodyGrid, 2> grids;
  const std::vector<std::size_t> cuts{0, 7, 100, 101, 230, n};
  const std::size_t ranges = cuts.size() - 1;
  std::mt19937 rng(7);
  // Each range to either thread, drawn afresh for every phase.
  auto onTwoThreads = [&](auto&& job) {
    std::vector<int> owner(ranges);
    for (int& o : owner) o = int(rng() % 2);
    auto run = [&](int thread) {
      for (std::size_t r = 0; r < ranges; ++r)
        if (owner[r] == thread) job(thread, cuts[r], cuts[r + 1]);
    };
    std::thread other(run, 1);
    run(0);
    other.join();
  };
  for (int frame = 0; frame < 20; ++frame) {
    bspf::stepBodies(level.world, reference.bodies, reference.forces, kDt, scratch,
                     referenceReports);
    // Each range's thread takes what the grid reads of its bodies; each
    // pushing thread builds its own grid from that, as the pool does.
    prepared.startPreparing(n);
    onTwoThreads([&](int thread, std::size_t first, std::size_t last) {
      bspf::stepBodiesAgainstLevel(level.world, jobs.bodies, jobs.forces, kDt, first, last,
                                   threadScratches[thread], shared, jobReports);
      prepared.prepare(jobs.bodies, first, last);
    });
    std::array<bool, 2> built{false, false};
    onTwoThreads([&](int thread, std::size_t first, std::size_t last) {
      if (!built[thread]) grids[thread].buildPrepared(prepared), built[thread] = true;
      bspf::pushBodiesApart(level.world, grids[thread], jobs.bodies, first, last,
                            threadScratches[thread], shared, jobReports);
    });
    // The same crowd as one range on one thread, with caches of its own.
    bspf::stepBodiesAgainstLevel(level.world, alone.bodies, alone.forces, kDt, 0, n, aloneScratch,
                                 aloneCaches, aloneReports);
    aloneGrid.build(alone.bodies);
    bspf::pushBodiesApart(level.world, aloneGrid, alone.bodies, 0, n, aloneScratch, aloneCaches,
                          aloneReports);
    INFO("frame " << frame);
    requireSameFrame(reference.bodies, jobs.bodies, referenceReports, jobReports);
    requireSameFrame(reference.bodies, alone.bodies, referenceReports, aloneReports);
  }
  // Whichever thread took a body, it queried the tree no more often than
  // on one thread: its cache went with it.
  REQUIRE(shared.queries() == aloneCaches.queries());
  REQUIRE(shared.queries() >= n);
  REQUIRE(shared.size() == n);
}

TEST_CASE(
    "a grid built from prepared inputs pushes bodies stacked in columns as a grid built from the "
    "bodies does",
    "[runtime][threads]") {
  // Columns of bodies 1.2 m apart along y (more than one y radius, less
  // than two: the cells' height decides which pairs the grid examines), a
  // little apart along x and z so each push has a level direction; 48
  // bodies (the sorted neighbour search) or 120 (the hashed cells).
  const int columns = GENERATE(8, 20);
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20}));
  std::vector<Body> bodies;
  for (int c = 0; c < columns; ++c)
    for (int k = 0; k < 6; ++k) {
      Body b;
      b.radii = {0.45f, 0.85f};
      b.position = Vec3(3.0f * float(c % 5) + 0.05f * float(k), 0.9f + 1.2f * float(k),
                        3.0f * float(c / 5) + 0.03f * float(k % 2));
      b.lastStepStart = b.position;
      bodies.push_back(b);
    }
  INFO(bodies.size() << " bodies");
  std::vector<Body> fromBodies = bodies, fromPrepared = bodies;
  std::vector<bspf::StepReport> reportsA(bodies.size()), reportsB(bodies.size());
  bspf::StepScratch scratchA, scratchB;
  bspf::BodyGrid grid, prepared, built;
  grid.build(fromBodies);
  bspf::pushBodiesApart(level.world, grid, fromBodies, 0, fromBodies.size(), scratchA, reportsA);
  prepared.startPreparing(bodies.size());
  prepared.prepare(fromPrepared, 0, fromPrepared.size());
  built.buildPrepared(prepared);
  bspf::pushBodiesApart(level.world, built, fromPrepared, 0, fromPrepared.size(), scratchB,
                        reportsB);
  requireSameFrame(fromBodies, fromPrepared, reportsA, reportsB);
  // Every body of a column touches the one above or below it.
  int contacts = 0;
  for (const auto& r : reportsA) contacts += r.bodyContacts;
  REQUIRE(contacts == 2 * columns * 5);
}

TEST_CASE("a small and a big overlapping body are pushed apart by equal halves",
          "[runtime][movement]") {
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20}));
  // Listed either way round: the grid's cells come from the biggest body, so
  // the pair is found whichever cell each centre falls in.
  const bool smallFirst = GENERATE(true, false);
  INFO((smallFirst ? "small body first" : "big body first"));
  Body small, big;
  small.radii = {0.25f, 0.5f};
  big.radii = {1.2f, 1.6f};
  small.position = Vec3(0.3f, 0.5f, 0.2f);
  big.position = Vec3(1.5f, 1.6f, 0.2f);  // 1.2 m apart, 1.45 m of radii
  std::vector<Body> bodies = smallFirst ? std::vector{small, big} : std::vector{big, small};
  const std::size_t s = smallFirst ? 0 : 1, b = 1 - s;
  const std::vector<Vec3> forces(2, Vec3::Zero());
  std::vector<bspf::StepReport> reports(2);
  bspf::StepScratch scratch;
  const Vec3 smallStart = bodies[s].position, bigStart = bodies[b].position;
  bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  REQUIRE(reports[s].bodyContacts == 1);
  REQUIRE(reports[b].bodyContacts == 1);
  const Vec3 smallMove = bodies[s].position - smallStart, bigMove = bodies[b].position - bigStart;
  // Horizontal, opposite, equal: the small body is not shoved the whole way.
  REQUIRE(smallMove.x() < -0.05f);
  REQUIRE(bigMove.x() > 0.05f);
  REQUIRE(smallMove.x() == Approx(-bigMove.x()).margin(1e-5));
  REQUIRE(std::abs(smallMove.z()) < 1e-6f);
  for (int frame = 0; frame < 30; ++frame)
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  const Vec3 apart = bodies[s].position - bodies[b].position;
  const Vec3 direction = apart.normalized();
  const float touching = bspf::effectiveRadius(direction, bodies[s].radii) +
                         bspf::effectiveRadius(direction, bodies[b].radii);
  REQUIRE(apart.norm() >= touching - 1e-3f);
  REQUIRE(bodies[s].position.y() == Approx(0.5f).margin(3e-3));
  REQUIRE(bodies[b].position.y() == Approx(1.6f).margin(3e-3));
}

TEST_CASE(
    "bodies piled at one point are each pushed by at most kMaxBodyPushes and spread out "
    "in every direction",
    "[runtime][movement]") {
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-50, -1, -50}, {50, 0, 50}));
  const Vec3 point(3, 0.86f, -2);
  std::vector<Body> bodies(2000);
  for (Body& b : bodies) b.position = point;
  const std::vector<Vec3> forces(bodies.size(), Vec3::Zero());
  std::vector<bspf::StepReport> reports(bodies.size());
  bspf::StepScratch scratch;
  int mostPushers = 0;
  for (int frame = 0; frame < 60; ++frame) {
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
    for (const auto& r : reports) mostPushers = std::max(mostPushers, r.bodyContacts);
  }
  REQUIRE(mostPushers == bspf::kMaxBodyPushes);
  // Spread over the floor around the point, in all four quadrants, none
  // still at the point, none sunk into the floor.
  int quadrants[4] = {0, 0, 0, 0};
  float farthest = 0;
  for (const Body& b : bodies) {
    const Vec3 d = b.position - point;
    REQUIRE(std::hypot(d.x(), d.z()) > 1e-3f);
    REQUIRE(b.position.y() > 0.85f - 2e-3f);
    ++quadrants[(d.x() > 0) + 2 * (d.z() > 0)];
    farthest = std::max(farthest, std::hypot(d.x(), d.z()));
  }
  for (const int q : quadrants) REQUIRE(q > 200);
  REQUIRE(farthest > 2);
}

TEST_CASE(
    "bodies spawned along a line a few centimetres long are each pushed at most half their "
    "deepest overlap in a frame, not the sum of all their shares",
    "[runtime][movement]") {
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20}));
  // Eight bodies 1 cm apart along x: each end body has all seven others on
  // one side, and the halves of those overlaps (about 0.45 m each) summed
  // would fling it 3 m in one frame.
  std::vector<Body> bodies(8);
  for (std::size_t k = 0; k < bodies.size(); ++k)
    bodies[k].position = Vec3(0.01f * float(k), 0.851f, 0.3f);
  const std::vector<Body> start = bodies;
  const std::vector<Vec3> forces(bodies.size(), Vec3::Zero());
  std::vector<bspf::StepReport> reports(bodies.size());
  bspf::StepScratch scratch;
  bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  const float deepestHalf = 0.5f * 2 * bodies[0].radii.xz + 0.5f * bodies[0].settings.skin;
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    INFO("body " << k);
    REQUIRE(reports[k].bodyContacts == 7);
    const Vec3 move = bodies[k].position - start[k].position;
    REQUIRE(std::hypot(move.x(), move.z()) <= deepestHalf + 1e-4f);
  }
  // The end bodies still part outwards at once.
  REQUIRE(bodies.front().position.x() < start.front().position.x() - 0.3f);
  REQUIRE(bodies.back().position.x() > start.back().position.x() + 0.3f);
}

TEST_CASE(
    "a body overlapped by more than kMaxBodyPushes bodies is pushed by the nearest ones, "
    "not by the first found",
    "[runtime][movement]") {
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20}));
  // Body 0 in the middle of one grid cell (1.8 m: four radii), kMaxBodyPushes
  // bodies just overlapping it on its +x side, listed first, and one deep
  // in it on its -x side, listed last: all in body 0's cell.
  const float y = 0.85f;
  std::vector<Body> bodies;
  Body centre;
  centre.position = Vec3(0.9f, y, 0.9f);
  bodies.push_back(centre);
  for (int k = 0; k < bspf::kMaxBodyPushes; ++k) {
    const float angle =
        (-40.0f + 80.0f * float(k) / float(bspf::kMaxBodyPushes - 1)) * 3.14159265f / 180.0f;
    Body b;
    b.position = centre.position + 0.85f * Vec3(std::cos(angle), 0, std::sin(angle));
    bodies.push_back(b);
  }
  Body deep;
  deep.position = centre.position - Vec3(0.3f, 0, 0);
  bodies.push_back(deep);
  const std::vector<Vec3> forces(bodies.size(), Vec3::Zero());
  std::vector<bspf::StepReport> reports(bodies.size());
  bspf::StepScratch scratch;
  bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  REQUIRE(reports[0].bodyContacts == bspf::kMaxBodyPushes);
  // The deep overlap (0.6 m, half of it a push to +x) outweighs the shallow
  // ones (0.05 m each, pushing to -x): it must be among the pushers.
  REQUIRE(bodies[0].position.x() > centre.position.x() + 0.05f);
}

TEST_CASE(
    "two bodies overlapping across a grid cell border, along any axis or across a corner, "
    "push each other apart",
    "[runtime][movement]") {
  // Cells are 1.8 m wide (four radii) and 3.4 m tall, with borders at 0. A
  // third body 10 km away makes the occupied cells' box too large for the
  // occupancy bits, so both ways of finding a neighbour cell are used.
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-20, -1, -20}, {20, 0, 20}));
  const bool farBody = GENERATE(false, true);
  const Vec3 offset = GENERATE(Vec3(0.5f, 0, 0), Vec3(0, 0, 0.5f), Vec3(0.4f, 0, 0.4f),
                               Vec3(-0.5f, 0, 0), Vec3(0, 0, -0.5f), Vec3(-0.4f, 0, 0.4f));
  INFO("offset " << offset.transpose() << (farBody ? ", a body 10 km away" : ""));
  for (const float border : {0.0f, 1.8f, -1.8f}) {
    INFO("border at " << border);
    // Each centre 0.1 to 0.3 m from the border, on either side of it.
    const Vec3 middle(border + 0.0123f, 0.851f, border - 0.0077f);
    std::vector<Body> bodies(2);
    bodies[0].position = middle - 0.5f * offset;
    bodies[1].position = middle + 0.5f * offset;
    if (farBody) {
      bodies.emplace_back();
      bodies.back().position = Vec3(10000, 0.851f, 0);
    }
    const std::vector<Body> start = bodies;
    const std::vector<Vec3> forces(bodies.size(), Vec3::Zero());
    std::vector<bspf::StepReport> reports(bodies.size());
    bspf::StepScratch scratch;
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
    REQUIRE(reports[0].bodyContacts == 1);
    REQUIRE(reports[1].bodyContacts == 1);
    const Vec3 before = start[1].position - start[0].position;
    const Vec3 after = bodies[1].position - bodies[0].position;
    REQUIRE(after.norm() > before.norm() + 0.3f);
  }
}

TEST_CASE(
    "two bodies overlapping one above the other across grid cells push each other apart "
    "equally",
    "[runtime][movement]") {
  // Cells are twice as tall as the tallest body (3.4 m): the lower body's
  // centre at y = 1.53 and the upper's 1.5 m above it, 0.3 m aside. In
  // cells half as tall, the upper body's nearer neighbour cell would be the
  // one above it, and it would never see the lower body.
  const bspf::test::CompiledMesh level(bspf::test::boxMesh({-20, -1, -20}, {20, 0.68, 20}));
  Body low, high;
  low.position = Vec3(0.9f, 1.53f, 0.9f);
  high.position = Vec3(1.2f, 3.03f, 0.9f);
  for (const bool lowFirst : {true, false}) {
    INFO((lowFirst ? "lower body first" : "upper body first"));
    std::vector<Body> bodies = lowFirst ? std::vector{low, high} : std::vector{high, low};
    const std::size_t l = lowFirst ? 0 : 1, h = 1 - l;
    const std::vector<Vec3> forces(2, Vec3::Zero());
    std::vector<bspf::StepReport> reports(2);
    bspf::StepScratch scratch;
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
    REQUIRE(reports[l].bodyContacts == 1);
    REQUIRE(reports[h].bodyContacts == 1);
    const float lowMove = bodies[l].position.x() - low.position.x();
    const float highMove = bodies[h].position.x() - high.position.x();
    REQUIRE(lowMove < -0.01f);
    REQUIRE(highMove > 0.01f);
    REQUIRE(lowMove == Approx(-highMove).margin(1e-5));
  }
}

TEST_CASE(
    "a body pressed into a wall by another is not pushed into it, and its next step carries "
    "the push along the wall",
    "[runtime][movement]") {
  const bspf::test::CompiledMesh level(yard());
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO((method == bspf::CollisionMethod::Planes ? "planes" : "exact"));
  // The yard's east wall has its face at x = 5. The body at the wall rests
  // 2 mm from it; the other overlaps it from the west and the south, so the
  // push on it points east (into the wall) and north (along it).
  std::vector<Body> bodies(2);
  for (Body& b : bodies) b.settings.method = method;
  const float wallX = 5, clear = wallX - bodies[0].radii.xz;
  bodies[0].position = Vec3(clear - 0.002f, 0.851f, 0);
  bodies[1].position = bodies[0].position - Vec3(0.5f, 0, 0.4f);
  const std::vector<Body> start = bodies;
  const std::vector<Vec3> forces(2, Vec3::Zero());
  std::vector<bspf::StepReport> reports(2);
  bspf::StepScratch scratch;
  bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  REQUIRE(reports[0].bodyContacts == 1);
  REQUIRE(reports[1].bodyContacts == 1);
  // The other, on open floor, is pushed away at once; the one at the wall
  // keeps its place and carries its push, east and north.
  REQUIRE(bodies[1].deferredPush == Vec3::Zero());
  REQUIRE(bodies[1].position.x() < start[1].position.x() - 0.05f);
  REQUIRE(bodies[1].position.z() < start[1].position.z() - 0.05f);
  const Vec3 carried = bodies[0].deferredPush;
  REQUIRE(carried.x() > 0.05f);
  REQUIRE(carried.z() > 0.05f);
  REQUIRE(carried.y() == 0);
  REQUIRE(bodies[0].position.x() <= clear);
  // The next step moves it north along the wall by the carried push, never
  // into the wall, and spends it.
  const Vec3 before = bodies[0].position;
  bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
  REQUIRE(bodies[0].position.x() <= clear);
  REQUIRE(bodies[0].position.z() > before.z() + 0.9f * carried.z());
  REQUIRE(bodies[0].deferredPush.x() >= 0);  // pushed again, if at all, into the wall
  // The step says what it carried (the sweep allows for it).
  REQUIRE(bodies[0].lastStepPush == carried);
  REQUIRE(bodies[1].lastStepPush == Vec3::Zero());
  // The pair parts within a few frames, the body at the wall never entering it.
  for (int frame = 0; frame < 30; ++frame) {
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
    REQUIRE(bodies[0].position.x() <= clear);
  }
  REQUIRE(reports[0].bodyContacts == 0);
  REQUIRE(bodies[0].deferredPush == Vec3::Zero());
}

namespace {

// Bodies of the default shape (radii 0.45 and 0.85) standing on a 400 m
// floor, without friction so that a set velocity is the move.
struct Runway {
  bspf::test::CompiledMesh level{bspf::test::boxMesh({-200, -1, -200}, {200, 0, 200})};
  std::vector<Body> bodies;
  std::vector<bspf::StepReport> reports;
  bspf::StepScratch scratch;

  Runway(bspf::CollisionMethod method, std::initializer_list<std::pair<Vec3, Vec3>> placed) {
    for (const auto& [position, velocity] : placed) {
      Body b;
      b.position = position;
      b.velocity = velocity;
      b.grounded = true;
      b.settings.method = method;
      b.settings.maxHorizontalSpeed = 10000;
      b.settings.groundFriction = 0;
      bodies.push_back(b);
    }
    reports.resize(bodies.size());
  }
  // One frame; the bodies' positions before it.
  std::vector<Vec3> step() {
    std::vector<Vec3> before;
    for (const Body& b : bodies) before.push_back(b.position);
    const std::vector<Vec3> forces(bodies.size(), Vec3::Zero());
    bspf::stepBodies(level.world, bodies, forces, kDt, scratch, reports);
    return before;
  }
};

constexpr float kStandY = 0.851f;
constexpr float kTouching = 0.9f;  // two default bodies' centres, side by side

// The least distance between two bodies' centres over a frame, each moving
// in a straight line from `fromA` to `toA` and `fromB` to `toB`: below
// kTouching, they passed into (or through) each other on the way.
float closestApproach(const Vec3& fromA, const Vec3& toA, const Vec3& fromB, const Vec3& toB) {
  const Vec3 d = fromA - fromB, v = (toA - fromA) - (toB - fromB);
  const float t = v.squaredNorm() > 0 ? std::clamp(-d.dot(v) / v.squaredNorm(), 0.0f, 1.0f) : 0;
  return (d + t * v).norm();
}

const char* methodName(bspf::CollisionMethod method) {
  return method == bspf::CollisionMethod::Planes ? "planes" : "exact";
}

}  // namespace

TEST_CASE("a body at 600 m/s stops at the body in its path instead of passing through it",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  Runway run(method,
             {{Vec3(0, kStandY, 0.1f), Vec3(600, 0, 0)}, {Vec3(5, kStandY, 0.1f), Vec3::Zero()}});
  const std::vector<Vec3> before = run.step();
  const Body &fast = run.bodies[0], &still = run.bodies[1];
  // Stopped just short of the other body, not 10 m on beyond it.
  REQUIRE(fast.position.x() < still.position.x() - kTouching + 0.01f);
  REQUIRE(fast.position.x() > still.position.x() - kTouching - 0.05f);
  REQUIRE(closestApproach(before[0], fast.position, before[1], still.position) >=
          kTouching - 1e-3f);
  REQUIRE(run.reports[0].stoppedByBody);
  // It lost its speed into the other body, and the other was not flung.
  REQUIRE(fast.velocity.x() < 1);
  REQUIRE((still.position - before[1]).norm() < 0.01f);
  // Neither ends up on the other's far side in the frames after.
  for (int frame = 0; frame < 30; ++frame) {
    run.step();
    REQUIRE(run.bodies[0].position.x() < run.bodies[1].position.x() - kTouching + 0.01f);
  }
}

TEST_CASE("a body at any speed from 20 to 6,000 m/s stops at the body in its path",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  const float speed = GENERATE(20.0f, 60.0f, 600.0f, 6000.0f);
  INFO(methodName(method) << " at " << speed << " m/s");
  // The other body halfway along the move, beyond touching distance.
  const float ahead = kTouching + 0.5f * speed * kDt;
  Runway run(method, {{Vec3(-80, kStandY, 3), Vec3(speed, 0, 0)},
                      {Vec3(-80 + ahead, kStandY, 3.2f), Vec3::Zero()}});
  const std::vector<Vec3> before = run.step();
  REQUIRE(closestApproach(before[0], run.bodies[0].position, before[1], run.bodies[1].position) >=
          kTouching - 1e-3f);
  REQUIRE(run.reports[0].stoppedByBody);
  REQUIRE(run.bodies[0].position.x() < run.bodies[1].position.x());
}

TEST_CASE("two bodies at 600 m/s head-on stop where they meet, each on its own side",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  Runway run(method,
             {{Vec3(-5, kStandY, 1), Vec3(600, 0, 0)}, {Vec3(5, kStandY, 1), Vec3(-600, 0, 0)}});
  const std::vector<Vec3> before = run.step();
  const Body &a = run.bodies[0], &b = run.bodies[1];
  REQUIRE(closestApproach(before[0], a.position, before[1], b.position) >= kTouching - 1e-3f);
  REQUIRE(run.reports[0].stoppedByBody);
  REQUIRE(run.reports[1].stoppedByBody);
  // They meet in the middle: each is stopped just short of x = 0.
  REQUIRE(a.position.x() == Approx(-0.5f * kTouching).margin(0.02));
  REQUIRE(b.position.x() == Approx(0.5f * kTouching).margin(0.02));
  REQUIRE(a.velocity.x() < 1);
  REQUIRE(b.velocity.x() > -1);
}

TEST_CASE("two fast bodies whose paths cross at an angle meet instead of passing through",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // One along x at 600 m/s, the other at 60 degrees to it at 300 m/s: both
  // reach the crossing at (0, 0) halfway through the frame.
  const Vec3 slant(std::cos(1.0472f), 0, std::sin(1.0472f));
  Runway run(method, {{Vec3(-5, kStandY, 0), Vec3(600, 0, 0)},
                      {Vec3(0, kStandY, 0) - 2.5f * slant, 300 * slant}});
  const std::vector<Vec3> before = run.step();
  REQUIRE(closestApproach(before[0], run.bodies[0].position, before[1], run.bodies[1].position) >=
          kTouching - 1e-3f);
  REQUIRE(run.reports[0].stoppedByBody);
  REQUIRE(run.reports[1].stoppedByBody);
  // Both short of the crossing.
  REQUIRE(run.bodies[0].position.x() < 0);
  REQUIRE((run.bodies[1].position - Vec3(0, kStandY, 0)).dot(slant) < 0);
}

TEST_CASE("a fast body passing 5 cm beside a slow one goes on at full speed without snagging",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  Runway run(method, {{Vec3(0, kStandY, 0), Vec3(600, 0, 0)},
                      {Vec3(5, kStandY, kTouching + 0.05f), Vec3(1, 0, 0)}});
  for (int frame = 0; frame < 3; ++frame) {
    const std::vector<Vec3> before = run.step();
    INFO("frame " << frame);
    REQUIRE_FALSE(run.reports[0].stoppedByBody);
    REQUIRE_FALSE(run.reports[1].stoppedByBody);
    REQUIRE(run.reports[0].bodyContacts == 0);
    REQUIRE(run.bodies[0].position.x() == Approx(before[0].x() + 10).margin(1e-3));
    REQUIRE(run.bodies[0].velocity.x() == 600);
    REQUIRE(run.bodies[1].position.x() == Approx(before[1].x() + 1 * kDt).margin(1e-4));
  }
}

TEST_CASE(
    "a fast body that starts overlapping another runs off past it or away from it instead of "
    "sticking to it",
    "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  // Straight away from the other's centre, or past it, slightly closing
  // but never nearer than its start.
  const bool away = GENERATE(true, false);
  INFO(methodName(method) << (away ? ", running away" : ", running past"));
  const Vec3 start = away ? Vec3(0.3f, kStandY, 0) : Vec3(0, kStandY, 0.85f);
  const Vec3 velocity = away ? Vec3(600, 0, 0) : Vec3(600, 0, -30);
  Runway run(method, {{Vec3(0, kStandY, 0), Vec3::Zero()}, {start, velocity}});
  run.step();
  REQUIRE_FALSE(run.reports[1].stoppedByBody);
  REQUIRE(run.bodies[1].position.x() > start.x() + 9.9f);
}

TEST_CASE("a fast body that met another off-centre keeps its speed along it and slides past",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // Aimed 0.6 m to the side of the other's centre (touching is 0.9 m).
  Runway run(method,
             {{Vec3(0, kStandY, 0), Vec3(600, 0, 0)}, {Vec3(5, kStandY, 0.6f), Vec3::Zero()}});
  run.step();
  REQUIRE(run.reports[0].stoppedByBody);
  // What is left of its velocity runs along the other body, away from it.
  REQUIRE(run.bodies[0].velocity.x() > 100);
  REQUIRE(run.bodies[0].velocity.z() < -100);
  REQUIRE(run.bodies[0].velocity.y() <= 0);
  for (int frame = 0; frame < 5; ++frame) run.step();
  REQUIRE(run.bodies[0].position.x() > run.bodies[1].position.x() + 5);
}

TEST_CASE("a fast body running into another's shoulder from above is not thrown upward",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // 0.6 m up in the air: the contact normal tilts up by about 35 degrees.
  Runway run(method,
             {{Vec3(0, kStandY + 0.6f, 0), Vec3(600, 0, 0)}, {Vec3(5, kStandY, 0), Vec3::Zero()}});
  run.step();
  REQUIRE(run.reports[0].stoppedByBody);
  REQUIRE(run.bodies[0].velocity.x() < 600);
  REQUIRE(run.bodies[0].velocity.y() <= 0);
}

TEST_CASE("a fast body stopped short by another is not passed through by a faster one behind it",
          "[runtime][movement][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // The middle body (5 m a frame) meets the still one 0.42 of the way into
  // the frame; the one behind (10 m a frame) would have met the middle one,
  // had it gone on, at 0.62, past where it stopped: it must meet it stopped.
  Runway run(method, {{Vec3(-4, kStandY, 0), Vec3(600, 0, 0)},
                      {Vec3(0, kStandY, 0), Vec3(300, 0, 0)},
                      {Vec3(3, kStandY, 0), Vec3::Zero()}});
  const std::vector<Vec3> before = run.step();
  for (int a = 0; a < 3; ++a)
    for (int b = a + 1; b < 3; ++b) {
      INFO("bodies " << a << " and " << b);
      REQUIRE(closestApproach(before[a], run.bodies[a].position, before[b],
                              run.bodies[b].position) >= kTouching - 1e-3f);
      REQUIRE(run.bodies[a].position.x() < run.bodies[b].position.x());
    }
  for (int k = 0; k < 2; ++k) REQUIRE(run.reports[k].stoppedByBody);
}

TEST_CASE("stepping fast bodies on 1, 2 or 3 threads gives bit-identical trajectories",
          "[runtime][threads][sweep]") {
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // The packed crowd, every third body running at up to 400 m/s.
  auto fastCrowd = [method] {
    Crowd crowd = packedCrowd(method);
    for (std::size_t i = 0; i < crowd.bodies.size(); i += 3) {
      crowd.bodies[i].settings.maxHorizontalSpeed = 400;
      crowd.forces[i] *= 400;
    }
    return crowd;
  };
  const int stopped = requireSameOnThreads(fastCrowd, 20, 3).second;
  REQUIRE(stopped > 20);  // the sweep did work
}

namespace {

// `count` bodies at random in an 8 m square, each having just moved in a
// direction of its own: 1 to 3 m (too fast to be swept past each other)
// where `fast(i)`, else 5 cm (too slow to be swept itself, but in others'
// way). A fixed sequence from `seed` on every platform.
template <typename Fast>
std::vector<Body> crossingCrowd(std::size_t count, std::uint32_t seed, Fast fast) {
  std::vector<Body> bodies(count);
  std::uint32_t state = seed;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1 << 24);
  };
  for (std::size_t i = 0; i < count; ++i) {
    Body& b = bodies[i];
    b.lastStepStart = Vec3(8 * next(), 0.851f, 8 * next());
    const float angle = 6.2831853f * next(), length = fast(i) ? 1 + 2 * next() : 0.05f;
    b.position = b.lastStepStart + length * Vec3(std::cos(angle), 0, std::sin(angle));
  }
  return bodies;
}

// Builds `bodies` (kSortedSweepBodies of them: the sweep's pairs are found
// by sorting their boxes) alone and with a still body 1 km away (the grid's
// cells find the pairs instead), requiring the same stop time for each of
// them and none for the far one; returns the bodies stopped.
std::vector<std::size_t> requireCellsStopAsSorting(std::vector<Body> bodies) {
  REQUIRE(bodies.size() == std::size_t(bspf::kSortedSweepBodies));
  bspf::BodyGrid sorted;
  sorted.build(bodies);
  Body far;
  far.position = far.lastStepStart = Vec3(1000, 0.851f, 1000);
  bodies.push_back(far);
  bspf::BodyGrid cells;
  cells.build(bodies);
  std::vector<std::size_t> stopped;
  for (std::size_t i = 0; i + 1 < bodies.size(); ++i) {
    INFO("body " << i);
    REQUIRE(sorted.stopTime(i) == cells.stopTime(i));
    if (sorted.stopTime(i) < 1) stopped.push_back(i);
  }
  REQUIRE(cells.stopTime(bodies.size() - 1) == 1);
  return stopped;
}

}  // namespace

TEST_CASE(
    "a small fast crowd stops where the grid's cells would stop it: a 65th body far away "
    "changes no stop time",
    "[runtime][movement][sweep]") {
  // 64 bodies (kSortedSweepBodies: their pairs are found by sorting their
  // boxes) running 1 to 3 m a frame across each other in an 8 m square, one
  // in four walking (too slow to be swept itself, but in others' way); with a
  // still body 1 km away, the grid's cells find the pairs instead.
  static_assert(bspf::kSortedSweepBodies == 64);
  const auto stopped =
      requireCellsStopAsSorting(crossingCrowd(64, 12345, [](std::size_t i) { return i % 4 != 0; }));
  REQUIRE(stopped.size() > 20);  // the crowd met itself: the comparison means something
}

TEST_CASE(
    "the grid's cells find every slow body in a fast one's way, however few cells the two share",
    "[runtime][movement][sweep]") {
  // 64 bodies, one in four running across the others, in 40 arrangements:
  // each slow body in a fast one's way is found through the cells it
  // shares with the fast path, some pairs through a single cell (each cell
  // a lookup of its own). The sorting's pairs, with no cells, are the
  // reference, as above.
  static_assert(bspf::kSortedSweepBodies == 64);
  int slowStopped = 0;
  for (std::uint32_t seed = 1; seed <= 40; ++seed) {
    INFO("seed " << seed);
    for (const std::size_t i : requireCellsStopAsSorting(
             crossingCrowd(64, seed, [](std::size_t i) { return i % 4 == 0; })))
      slowStopped += i % 4 != 0;
  }
  REQUIRE(slowStopped > 100);  // slow bodies were in the way: the comparison means something
}

TEST_CASE(
    "a small crowd with few fast bodies stops where the sorted sweep stops it, whatever runs far "
    "away",
    "[runtime][movement][sweep]") {
  // 40 bodies in an 8 m square, 12 of them running 1 to 3 m a frame across
  // the others (few enough that each fast box is tested against every
  // other); with 5 more running far away (too many fast bodies for that),
  // the sorted sweep finds the pairs instead.
  static_assert(bspf::kSortedSweepBodies == 64);
  std::vector<Body> bodies = crossingCrowd(40, 777, [](std::size_t i) { return i % 10 < 3; });
  bspf::BodyGrid few;
  few.build(bodies);
  const std::size_t crowd = bodies.size();
  for (int k = 0; k < 5; ++k) {
    Body far;
    far.lastStepStart = Vec3(500, 0.851f, 5.0f * float(k));
    far.position = far.lastStepStart + Vec3(2, 0, 0);
    bodies.push_back(far);
  }
  bspf::BodyGrid sorted;
  sorted.build(bodies);
  int stopped = 0;
  for (std::size_t i = 0; i < crowd; ++i) {
    INFO("body " << i);
    REQUIRE(few.stopTime(i) == sorted.stopTime(i));
    stopped += few.stopTime(i) < 1;
  }
  for (std::size_t i = crowd; i < bodies.size(); ++i) REQUIRE(sorted.stopTime(i) == 1);
  REQUIRE(stopped > 8);  // the fast bodies met others: the comparison means something
}

namespace {

// Steps `crowd` (at most kSortedNeighbourBodies bodies: their pushers are
// found by sorting) and the same crowd with one more body standing far
// away (the grid's cells find them instead) for `frames` frames, requiring
// the same frame for the crowd's bodies; returns the body contacts summed
// over the frames.
int requireSameAsWithFarBody(Crowd crowd, int frames) {
  REQUIRE(crowd.bodies.size() <= std::size_t(bspf::kSortedNeighbourBodies));
  const bspf::test::CompiledMesh level(yard());
  Crowd withFar = crowd;
  Body far;
  far.position = Vec3(15, 0.86f, 19);
  withFar.bodies.push_back(far);
  withFar.forces.push_back(Vec3::Zero());
  const std::size_t n = crowd.bodies.size();
  std::vector<bspf::StepReport> reports(n), farReports(n + 1);
  bspf::StepScratch scratch, farScratch;
  int contacts = 0;
  for (int frame = 0; frame < frames; ++frame) {
    INFO("frame " << frame);
    bspf::stepBodies(level.world, crowd.bodies, crowd.forces, kDt, scratch, reports);
    bspf::stepBodies(level.world, withFar.bodies, withFar.forces, kDt, farScratch, farReports);
    requireSameFrame(crowd.bodies, std::span<const Body>(withFar.bodies).first(n), reports,
                     std::span<const bspf::StepReport>(farReports).first(n));
    REQUIRE(farReports[n].bodyContacts == 0);
    for (const auto& r : reports) contacts += r.bodyContacts;
  }
  return contacts;
}

}  // namespace

TEST_CASE(
    "a small crowd is pushed as the grid's cells would push it: a 65th body far away changes "
    "no push",
    "[runtime][movement][bodies]") {
  static_assert(bspf::kSortedNeighbourBodies == 64);
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // 16 clusters of 4 overlapping bodies of three sizes, 2.4 m apart along x
  // (so that no 34 lie within 4 cells along x, which would bring the grid
  // back), along the yard's wall, walking.
  Crowd crowd;
  for (int i = 0; i < 64; ++i) {
    const int cluster = i / 4, member = i % 4;
    addCrowdBody(crowd, i,
                 Vec3(-18.0f + 2.4f * float(cluster) + 0.5f * float(member % 2), 0.9f,
                      7.0f + 0.5f * float(member / 2)),
                 method);
  }
  const int contacts = requireSameAsWithFarBody(crowd, 40);
  REQUIRE(contacts > 200);  // the crowd pushed itself: the comparison means something
}

TEST_CASE("a small pile with more candidates than the cap is pushed as the grid's cells push it",
          "[runtime][movement][bodies]") {
  // 64 bodies at one point: each has 63 others in its cell, more than
  // kMaxBodyCandidates, so which pushers a body gets depends on the grid's
  // order of examining them (the nearest, all at distance 0, by index).
  static_assert(bspf::kMaxBodyCandidates < 63);
  Crowd pile;
  pile.bodies.resize(64);
  for (Body& b : pile.bodies) b.position = Vec3(-2, 0.86f, 2);
  pile.forces.assign(64, Vec3::Zero());
  const int contacts = requireSameAsWithFarBody(pile, 30);
  REQUIRE(contacts > 64 * bspf::kMaxBodyPushes);  // the first frame alone pushes every body
}

TEST_CASE(
    "a small crowd of mixed sizes, packed in clusters and stacked, is pushed as the grid's cells "
    "would push it",
    "[runtime][movement][bodies]") {
  static_assert(bspf::kSortedNeighbourBodies == 64);
  const bspf::CollisionMethod method =
      GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep);
  INFO(methodName(method));
  // 64 bodies (with the far one, 65: the grid's cells push those) of the
  // three sizes in 16 clusters along the yard's outside, 2.4 m apart along x
  // (so that no 34 lie within 4 cells along x, which would bring the grid
  // back), each body placed at random within 1.2 m of
  // its cluster's centre and up to 1.5 m up: pairs overlapping along every
  // axis and pairs apart along only one of them, of unequal sizes (the
  // sorting's cheap tests use the largest radii), some at one point.
  std::uint32_t state = 2024;
  auto next = [&state] {  // a fixed sequence on every platform
    state = state * 1664525u + 1013904223u;
    return float(state >> 8) / float(1 << 24);
  };
  Crowd crowd;
  for (int i = 0; i < 64; ++i) {
    const int cluster = i / 4;
    const Vec3 centre(-18.5f + 2.4f * float(cluster), 1.2f, 9.0f);
    const Vec3 offset =
        i % 9 == 0 ? Vec3::Zero() : Vec3(1.2f * next() - 0.6f, 1.5f * next(), 1.2f * next() - 0.6f);
    addCrowdBody(crowd, i, centre + offset, method);
  }
  const int contacts = requireSameAsWithFarBody(crowd, 40);
  REQUIRE(contacts > 300);  // the crowd pushed itself: the comparison means something
}

TEST_CASE(
    "bodies falling onto others' heads in a small crowd are pushed as the grid's cells would "
    "push them, from within and from beyond a list's reach along y, onto bodies at rest or "
    "jumping",
    "[runtime][movement][bodies]") {
  static_assert(bspf::kSortedNeighbourBodies == 64);
  // 32 stacks in two rows along the yard's outside, 2.4 m apart along x (no
  // 34 within 4 cells along x): a body on the floor and one of the same size
  // dropped onto it, up to 31 cm aside (so that their boxes and the bodies
  // themselves start to overlap at nearly one height). The sorted search
  // lists its pairs while no body has moved more than a slack since
  // (BodyGrid; along y a slack of its own, 1.275 m for these bodies, so a
  // list reaches 1.7 + 2 * 1.275 = 4.25 m along y): a falling body closes on
  // the one below along y, where a list short of its reach, or kept after a
  // longer fall, would miss a pair the grid (with the far body, 65) finds.
  // Dropped from 2.6 to 4.15 m higher, a list holds each pair from the
  // first frame on; from 4.3 to 5.85 m, each pair comes within reach while
  // a list made without it lasts; onto a body jumping up at 5 m/s, the pair
  // closes from both ends, as the list's reach of twice the slack allows.
  const int drop = GENERATE(0, 1, 2);
  const float above = drop == 0 ? 2.6f : 4.3f;
  INFO((drop == 0 ? "within a list's reach" : drop == 1 ? "beyond it" : "onto jumping bodies"));
  Crowd crowd;
  for (int i = 0; i < 64; ++i) {
    const int stack = i / 2;
    const bool falls = i % 2 == 1;
    addCrowdBody(crowd, i,
                 Vec3(-18.5f + 2.4f * float(stack % 16) + (falls ? 0.01f * float(stack) : 0),
                      1.01f + (falls ? above + 0.05f * float(stack) : 0), stack < 16 ? 9 : -9),
                 bspf::CollisionMethod::Planes);
    crowd.bodies.back().radii = {0.45f, 0.85f};
    if (drop == 2 && !falls) crowd.bodies.back().velocity = Vec3(0, 5, 0);
    crowd.forces.back() = Vec3::Zero();
  }
  const int contacts = requireSameAsWithFarBody(crowd, 90);
  REQUIRE(contacts > 32 * 5);  // the falling bodies landed: the comparison means something
}

TEST_CASE(
    "a body at a NaN position in a small crowd's grid changes no push between the others, "
    "whatever their order",
    "[runtime][movement][bodies]") {
  // Two overlapping bodies, with the NaN one between them in index order:
  // x order cannot be made around a NaN, so a scan along it would miss the
  // pair; the grid's cells find it. With bystanders (near the pair along x,
  // 10 m away along z), the NaN ends the scan's first run of four after the
  // lower body before it reaches the other.
  const bool bystanders = GENERATE(false, true);
  INFO((bystanders ? "three bystanders between the pair along x" : "the pair alone"));
  const bspf::test::CompiledMesh level(yard());
  auto body = [](const Vec3& at) {
    Body b;
    b.position = b.lastStepStart = at;
    return b;
  };
  const Vec3 a(-2, 0.86f, -2), b(-1.4f, 0.86f, -2);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  // b, a; or a, the bystanders, b. withNan has the NaN second.
  std::vector<Body> pair{body(b), body(a)};
  if (bystanders) {
    pair = {body(a)};
    for (const float x : {-1.9f, -1.8f, -1.7f}) pair.push_back(body(Vec3(x, 0.86f, 8)));
    pair.push_back(body(b));
  }
  std::vector<Body> withNan = pair;
  withNan.insert(withNan.begin() + 1, body(Vec3(nan, nan, nan)));
  bspf::StepScratch pairScratch, nanScratch;
  pairScratch.bodyGrid.build(pair);
  nanScratch.bodyGrid.build(withNan);
  bspf::pushBodiesApart(level.world, pairScratch.bodyGrid, pair, 0, pair.size(), pairScratch, {});
  bspf::pushBodiesApart(level.world, nanScratch.bodyGrid, withNan, 0, withNan.size(), nanScratch,
                        {});
  // pair[k] is withNan[k + 1] after the NaN.
  for (std::size_t k = 0; k < pair.size(); ++k) {
    INFO("body " << k);
    REQUIRE(withNan[k < 1 ? k : k + 1].position == pair[k].position);
  }
  // The pair was pushed apart: the comparison means something.
  REQUIRE((pair.front().position - pair.front().lastStepStart).norm() > 0.1f);
  REQUIRE((pair.back().position - pair.back().lastStepStart).norm() > 0.1f);
}
