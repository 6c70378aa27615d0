// SPDX-License-Identifier: MIT
// The sorted sweep's pair scan (private: runtime/src/box_pairs.h): the
// four-at-a-time scan the body phase uses must find the same pairs, in the
// same order, as the one-box-at-a-time reference, and the reference every
// pair of meeting boxes with a fast body; likewise the neighbour search's
// scan and its four-lane test of how far the bodies moved, and the
// four-at-a-time pass over a crowd that opens each build (scanCrowd).
#include "box_pairs.h"

#include <algorithm>
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

// `count` boxes in x order as the sweep lays them out (SortedBoxes), with
// the kBoxRun boxes after them that meet nothing.
struct Boxes {
  std::vector<float> lowX, highX, lowY, highY, lowZ, highZ;
  std::vector<std::uint32_t> body, fast;

  bspf::detail::SortedBoxes view() const {
    return {lowX.data(),  highX.data(), lowY.data(),
            highY.data(), lowZ.data(),  highZ.data(),
            body.data(),  fast.data(),  std::uint32_t(body.size() - bspf::detail::kBoxRun)};
  }
};

// Random boxes: clustered so that runs along x are often longer than
// kBoxRun, some sharing a face (touching must count), some slow pairs,
// some bounds infinite or NaN. Sorted by low x as the sweep sorts them (a
// float's bits, sign-flipped).
Boxes randomBoxes(std::mt19937& rng, int count) {
  std::uniform_real_distribution<float> centre(-6, 6), size(0.1f, 2.5f), unit(0, 1);
  struct Box {
    float low[3], high[3];
    std::uint32_t body, fast;
  };
  std::vector<Box> boxes;
  for (int i = 0; i < count; ++i) {
    Box b;
    for (int axis = 0; axis < 3; ++axis) {
      b.low[axis] = centre(rng);
      b.high[axis] = b.low[axis] + size(rng);
    }
    if (i > 0 && unit(rng) < 0.2f) {  // touching the last box along one axis
      const int axis = int(unit(rng) * 2.99f);
      b.low[axis] = boxes.back().high[axis];
    }
    const float odd = unit(rng);
    if (odd < 0.03f)
      b.high[0] = kInfinity;
    else if (odd < 0.06f)
      b.low[2] = -kInfinity;
    else if (odd < 0.08f)
      b.high[1] = std::numeric_limits<float>::quiet_NaN();
    else if (odd < 0.10f)
      b.low[0] = std::numeric_limits<float>::quiet_NaN();
    b.body = std::uint32_t(i);
    b.fast = unit(rng) < 0.6f ? ~0u : 0u;
    boxes.push_back(b);
  }
  auto key = [](float x) {
    const std::uint32_t bits = std::bit_cast<std::uint32_t>(x);
    return bits >> 31 ? ~bits : bits | 0x80000000u;
  };
  std::sort(boxes.begin(), boxes.end(), [&](const Box& a, const Box& b) {
    return key(a.low[0]) != key(b.low[0]) ? key(a.low[0]) < key(b.low[0]) : a.body < b.body;
  });
  Boxes out;
  for (const Box& b : boxes) {
    out.lowX.push_back(b.low[0]), out.highX.push_back(b.high[0]);
    out.lowY.push_back(b.low[1]), out.highY.push_back(b.high[1]);
    out.lowZ.push_back(b.low[2]), out.highZ.push_back(b.high[2]);
    out.body.push_back(b.body), out.fast.push_back(b.fast);
  }
  for (std::uint32_t k = 0; k < bspf::detail::kBoxRun; ++k) {
    out.lowX.push_back(kInfinity), out.highX.push_back(-kInfinity);
    out.lowY.push_back(kInfinity), out.highY.push_back(-kInfinity);
    out.lowZ.push_back(kInfinity), out.highZ.push_back(-kInfinity);
    out.body.push_back(0), out.fast.push_back(0);
  }
  return out;
}

}  // namespace

TEST_CASE("the four-at-a-time pair scan finds the pairs the one-by-one scan finds, in its order",
          "[runtime][movement]") {
  std::mt19937 rng(20261128);
  for (int trial = 0; trial < 400; ++trial) {
    const int count = trial % 70;
    const Boxes boxes = randomBoxes(rng, count);
    INFO("trial " << trial << ", " << count << " boxes");
    std::vector<std::uint64_t> fourAtATime, oneByOne;
    bspf::detail::appendMeetingPairs(boxes.view(), fourAtATime);
    bspf::detail::appendMeetingPairsOneByOne(boxes.view(), oneByOne);
    REQUIRE(fourAtATime == oneByOne);
  }
}

TEST_CASE("the one-by-one pair scan finds every pair of meeting boxes with a fast body",
          "[runtime][movement]") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 200; ++trial) {
    const int count = trial % 50;
    const Boxes boxes = randomBoxes(rng, count);
    INFO("trial " << trial << ", " << count << " boxes");
    std::vector<std::uint64_t> found;
    bspf::detail::appendMeetingPairsOneByOne(boxes.view(), found);
    std::sort(found.begin(), found.end());
    // Every pair, tested as boxesMeet tests: closed intervals, and NaN
    // bounds meeting nothing.
    std::vector<std::uint64_t> expected;
    for (int i = 0; i < count; ++i)
      for (int j = i + 1; j < count; ++j) {
        auto meets = [&](const std::vector<float>& low, const std::vector<float>& high) {
          return low[i] <= high[j] && low[j] <= high[i];
        };
        if ((boxes.fast[i] | boxes.fast[j]) != 0 && meets(boxes.lowX, boxes.highX) &&
            meets(boxes.lowY, boxes.highY) && meets(boxes.lowZ, boxes.highZ)) {
          const std::uint32_t a = std::min(boxes.body[i], boxes.body[j]),
                              b = std::max(boxes.body[i], boxes.body[j]);
          expected.push_back(std::uint64_t(a) << 32 | b);
        }
      }
    std::sort(expected.begin(), expected.end());
    REQUIRE(found == expected);
  }
}

namespace {

// `count` centres sorted by x as the neighbour search lays them out, then
// the kCentreRun at x +infinity: clustered (runs within reach longer than
// four), some sharing an x, some exactly a reach apart along an axis.
std::vector<bspf::detail::SortedCentre> randomCentres(std::mt19937& rng, std::uint32_t count,
                                                      float reach) {
  std::uniform_real_distribution<float> cluster(-8, 8), spread(-1.2f, 1.2f);
  std::vector<bspf::detail::SortedCentre> centres;
  for (std::uint32_t i = 0; i < count; ++i) {
    bspf::detail::SortedCentre c{cluster(rng) * 0.2f + spread(rng), spread(rng), spread(rng), i};
    if (i % 7 == 3 && i > 0) c.x = centres.back().x;           // the same x
    if (i % 11 == 5 && i > 0) c.z = centres.back().z + reach;  // exactly a reach apart
    centres.push_back(c);
  }
  std::sort(centres.begin(), centres.end(), [](const auto& a, const auto& b) { return a.x < b.x; });
  for (std::uint32_t k = 0; k < bspf::detail::kCentreRun; ++k)
    centres.push_back({kInfinity, 0, 0, ~0u});
  return centres;
}

// A pair of centres as their places in `centres`: first << 32 | second.
std::uint64_t places(const std::vector<bspf::detail::SortedCentre>& centres,
                     const bspf::detail::SortedCentre* first,
                     const bspf::detail::SortedCentre* second) {
  return std::uint64_t(first - centres.data()) << 32 | std::uint64_t(second - centres.data());
}

}  // namespace

TEST_CASE(
    "the four-at-a-time neighbour scan finds the pairs the one-by-one scan finds, in its order",
    "[runtime][bodies]") {
  std::mt19937 rng(5);
  std::size_t found = 0;
  for (int round = 0; round < 400; ++round) {
    const std::uint32_t count = 1 + std::uint32_t(rng() % 80);
    const float reach = 0.9f, reachY = round % 2 == 0 ? 1.7f : 0.4f;
    const auto centres = randomCentres(rng, count, reach);
    std::vector<std::uint64_t> fast, reference;
    bspf::detail::forNearCentres(
        centres.data(), count, reach, reachY,
        [&](const auto* self, const auto* other) { fast.push_back(places(centres, self, other)); });
    bspf::detail::forNearCentresOneByOne(centres.data(), count, reach, reachY,
                                         [&](const auto* self, const auto* other) {
                                           reference.push_back(places(centres, self, other));
                                         });
    INFO("round " << round);
    REQUIRE(fast == reference);
    found += fast.size();
  }
  CHECK(found > 5000);  // the comparison means something
}

TEST_CASE("the one-by-one neighbour scan finds every pair of centres within reach on each axis",
          "[runtime][bodies]") {
  std::mt19937 rng(6);
  for (int round = 0; round < 200; ++round) {
    const std::uint32_t count = 1 + std::uint32_t(rng() % 60);
    const float reach = 0.9f, reachY = 1.7f;
    const auto centres = randomCentres(rng, count, reach);
    std::vector<std::uint64_t> pairs;
    bspf::detail::forNearCentresOneByOne(centres.data(), count, reach, reachY,
                                         [&](const auto* self, const auto* other) {
                                           pairs.push_back(places(centres, self, other));
                                         });
    std::vector<std::uint64_t> expected;
    for (std::uint32_t k = 0; k < count; ++k)
      for (std::uint32_t l = k + 1; l < count; ++l)
        if (std::abs(centres[l].x - centres[k].x) < reach &&
            std::abs(centres[k].z - centres[l].z) < reach &&
            std::abs(centres[k].y - centres[l].y) < reachY)
          expected.push_back(std::uint64_t(k) << 32 | l);
    INFO("round " << round);
    REQUIRE(pairs == expected);
  }
}

namespace {

// What the neighbour search's entries hold, as BodyGrid lays them out.
struct Record {
  bspf::Vec3 position;
  bspf::EllipsoidRadii radii;
  std::uint32_t body;
};

}  // namespace

TEST_CASE(
    "the four-lane move test answers as the one-by-one test: within the slack along x and z and "
    "the slack along y, beyond either, and not finite",
    "[runtime][bodies]") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> place(-50, 50), move(-0.6f, 0.6f), moveY(-1.1f, 1.1f);
  const float slack = 0.45f, slackY = 0.85f, nan = std::numeric_limits<float>::quiet_NaN();
  int within = 0, beyond = 0, withinOnlyByY = 0;
  for (int round = 0; round < 2000; ++round) {
    const std::size_t count = 1 + rng() % 70;
    std::vector<Record> then(count), now(count);
    for (std::size_t i = 0; i < count; ++i) {
      then[i] = {bspf::Vec3(place(rng), place(rng), place(rng)), {0.45f, 0.85f}, std::uint32_t(i)};
      // Most records move a little; a round's few move up to a slack,
      // exactly a slack, or beyond it, along one axis or in a radius.
      now[i] = then[i];
      now[i].position += 0.1f * bspf::Vec3(move(rng), move(rng), move(rng));
    }
    const std::size_t k = rng() % count;
    switch (round % 10) {
      case 0: now[k].position.x() = then[k].position.x() + move(rng); break;
      case 1: now[k].position.y() = then[k].position.y() + moveY(rng); break;
      case 2: now[k].position.z() = then[k].position.z() - slack; break;
      case 3: now[k].radii.xz = then[k].radii.xz + move(rng); break;
      case 4: now[k].position[round / 10 % 3] = nan; break;
      case 5: now[k].position[round / 10 % 3] = kInfinity; break;
      case 6: now[k].radii.y = round / 10 % 2 ? nan : kInfinity; break;
      case 7: now[k].radii.xz = nan; break;
      case 8:
        now[k].position.y() = then[k].position.y() + (round / 10 % 2 ? slackY : -slackY);
        break;
      default: break;
    }
    const bool reference = bspf::detail::movedWithinOneByOne<Record>(now, then, slack, slackY);
    INFO("round " << round);
    REQUIRE(bspf::detail::movedWithin<Record>(now, then, slack, slackY) == reference);
    (reference ? within : beyond) += 1;
    // Within only because y has its own slack: a lane's slack mixed up
    // with another's would answer otherwise here.
    withinOnlyByY +=
        reference && !bspf::detail::movedWithinOneByOne<Record>(now, then, slack, slack);
  }
  CHECK(withinOnlyByY > 100);
  // The reference itself: 0.6 m along y is within the slacks, along x or z
  // beyond them.
  const std::vector<Record> at{{bspf::Vec3(1, 2, 3), {0.45f, 0.85f}, 0}};
  for (int axis = 0; axis < 3; ++axis) {
    INFO("axis " << axis);
    std::vector<Record> moved = at;
    moved[0].position[axis] += 0.6f;
    CHECK(bspf::detail::movedWithinOneByOne<Record>(moved, at, slack, slackY) == (axis == 1));
    CHECK(bspf::detail::movedWithin<Record>(moved, at, slack, slackY) == (axis == 1));
  }
  // Both answers came up often: the comparison means something.
  CHECK(within > 500);
  CHECK(beyond > 500);
}

TEST_CASE("the four-lane link bits answer as the one-by-one bits, for every crowd size to 64",
          "[runtime][bodies]") {
  std::mt19937 rng(11);
  constexpr std::uint32_t kNone = ~std::uint32_t(0);
  int linked = 0, unlinked = 0;
  for (std::size_t count = 0; count <= 64; ++count)
    for (int round = 0; round < 20; ++round) {
      std::vector<std::uint32_t> heads(count);
      // Unlinked most often, as in a walking crowd; a link's index may be
      // anything but `none` (0 included).
      for (std::uint32_t& h : heads) h = rng() % 4 == 0 ? std::uint32_t(rng() % 3) : kNone;
      const std::uint64_t reference = bspf::detail::linkedBitsOneByOne(heads, kNone);
      INFO("bodies " << count << ", round " << round);
      REQUIRE(bspf::detail::linkedBits(heads, kNone) == reference);
      for (std::size_t i = 0; i < count; ++i) {
        REQUIRE((reference >> i & 1) == (heads[i] != kNone ? 1u : 0u));
        (heads[i] != kNone ? linked : unlinked) += 1;
      }
      if (count < 64) REQUIRE(reference >> count == 0);
    }
  CHECK(linked > 1000);
  CHECK(unlinked > 1000);
}

TEST_CASE(
    "the four-at-a-time crowd scan gives the one-by-one scan's cell size and asks movedFast of "
    "the same bodies",
    "[runtime][bodies]") {
  std::mt19937 rng(13);
  std::uniform_real_distribution<float> place(-50, 50), unit(-1, 1), share(0.95f, 1.03f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int asked = 0, fast = 0, slowCrowds = 0;
  for (int round = 0; round < 3000; ++round) {
    const std::size_t count = rng() % 70;
    std::vector<bspf::Body> bodies(count);
    for (std::size_t i = 0; i < count; ++i) {
      bspf::Body& b = bodies[i];
      b.radii = {0.2f + 0.5f * std::abs(unit(rng)), 0.3f + 0.8f * std::abs(unit(rng))};
      b.lastStepStart = bspf::Vec3(place(rng), place(rng), place(rng));
      // Moves about the surely-slow bound (half the smaller radius, less 1%)
      // in every direction, or short; what follows each vector in the body
      // (velocity, a ground triangle's index) anything.
      const float radius = std::min(b.radii.xz, b.radii.y);
      const float length = rng() % 4 == 0 ? 0.5f * radius * share(rng) : 0.1f * radius;
      const bspf::Vec3 direction = bspf::Vec3(unit(rng), unit(rng), unit(rng)).normalized();
      b.position = b.lastStepStart + length * direction;
      b.velocity = bspf::Vec3(place(rng), unit(rng), place(rng));
      b.groundTriangles[0] = std::uint32_t(rng() % 5000);
    }
    if (count > 0) {
      bspf::Body& b = bodies[rng() % count];
      switch (round % 12) {
        case 0: b.radii.xz = nan; break;
        case 1: b.radii.y = nan; break;
        case 2: b.position.y() = nan; break;
        case 3: b.position.x() = kInfinity; break;
        case 4: b.radii.y = 3; break;  // the tallest, anywhere in the crowd
        default: break;
      }
    }
    // Fast where the move is longer than 0.497 of the smaller radius: a
    // test, not the step's; which bodies are asked is what is compared.
    std::vector<const bspf::Body*> askedByReference, askedByLanes;
    auto movedFast = [](std::vector<const bspf::Body*>& log) {
      return [&log](const bspf::Body& b) {
        log.push_back(&b);
        const float radius = std::min(b.radii.xz, b.radii.y);
        return (b.position - b.lastStepStart).norm() > 0.497f * radius;
      };
    };
    const bspf::detail::CrowdScan reference =
        bspf::detail::scanCrowdOneByOne(bodies, movedFast(askedByReference));
    const bspf::detail::CrowdScan lanes = bspf::detail::scanCrowd(bodies, movedFast(askedByLanes));
    INFO("round " << round << ", bodies " << count);
    REQUIRE(std::bit_cast<std::uint32_t>(lanes.width) ==
            std::bit_cast<std::uint32_t>(reference.width));
    REQUIRE(std::bit_cast<std::uint32_t>(lanes.height) ==
            std::bit_cast<std::uint32_t>(reference.height));
    REQUIRE(lanes.anyFast == reference.anyFast);
    REQUIRE(askedByLanes == askedByReference);
    asked += int(askedByReference.size());
    fast += reference.anyFast;
    slowCrowds += count > 0 && !reference.anyFast;
  }
  // Bodies near the bound were asked, crowds with and without a fast body.
  CHECK(asked > 2000);
  CHECK(fast > 1000);
  CHECK(slowCrowds > 300);
  // The reference's bound: a move of 0.49 of the smaller radius is surely
  // slow, one of 0.5 is not.
  bspf::Body body;
  body.radii = {0.45f, 0.85f};
  body.position = body.lastStepStart + bspf::Vec3(0.49f * 0.45f, 0, 0);
  CHECK(bspf::detail::movedSurelySlow(body));
  body.position = body.lastStepStart + bspf::Vec3(0, 0, 0.5f * 0.45f);
  CHECK_FALSE(bspf::detail::movedSurelySlow(body));
}

namespace {

bool sameBitsOrBothNaN(float a, float b) {
  return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b) ||
         (std::isnan(a) && std::isnan(b));
}

// What the neighbour search keeps of a listed pair (BodyGrid's
// OverlappingPair).
struct MeasuredPair {
  std::uint64_t pair;
  float distance, overlap;
};

}  // namespace

TEST_CASE(
    "the four-lane pair measure keeps the pairs the one-by-one measure keeps, with the same "
    "distances and overlaps to the bit",
    "[runtime][bodies]") {
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> place(-3, 3), near(-1.2f, 1.2f), radius(0.2f, 0.9f);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  int kept = 0, dropped = 0, atOnePoint = 0, oneAboveOther = 0;
  for (int round = 0; round < 3000; ++round) {
    const std::size_t bodies = 2 + rng() % 40;
    std::vector<Record> records(bodies);
    for (std::size_t i = 0; i < bodies; ++i)
      records[i] = {bspf::Vec3(place(rng), place(rng), place(rng)),
                    {radius(rng), radius(rng)},
                    std::uint32_t(i)};
    // Every length to 13 (whole groups of four and every remainder), the
    // second body most often near the first; some at the same point, right
    // above it, or not finite.
    const std::size_t count = rng() % 14;
    std::vector<MeasuredPair> lanes(count), reference(count);
    for (std::size_t k = 0; k < count; ++k) {
      const std::uint32_t a = std::uint32_t(rng() % bodies),
                          b = std::uint32_t((a + 1 + rng() % (bodies - 1)) % bodies);
      Record& q = records[b];
      q.position = records[a].position + bspf::Vec3(near(rng), near(rng), near(rng));
      switch (rng() % 24) {
        case 0: q.position = records[a].position; break;
        case 1:
          q.position.x() = records[a].position.x(), q.position.z() = records[a].position.z();
          break;
        case 2: q.position.y() = nan; break;
        case 3: q.position.x() = kInfinity; break;
        case 4: q.radii.y = nan; break;
        default: break;
      }
      lanes[k] = reference[k] = {std::uint64_t(a) << 32 | b, -1, -1};
    }
    // A pair's bodies are measured where the last pair left them.
    for (std::size_t k = 0; k < count; ++k) {
      const Record &p = records[reference[k].pair >> 32],
                   &q = records[std::uint32_t(reference[k].pair)];
      atOnePoint += p.position == q.position;
      oneAboveOther += p.position.x() == q.position.x() && p.position.z() == q.position.z();
    }
    const std::size_t expected =
        bspf::detail::keepOverlappingOneByOne(records.data(), reference.data(), count);
    INFO("round " << round << ", pairs " << count);
    REQUIRE(bspf::detail::keepOverlapping(records.data(), lanes.data(), count) == expected);
    for (std::size_t k = 0; k < expected; ++k) {
      REQUIRE(lanes[k].pair == reference[k].pair);
      // The same bits, or both NaN: which NaN an operation passes on
      // depends on its operands' order, which a compiler may swap (clang
      // does); a NaN distance is never read (apartKnown is false for it).
      REQUIRE(sameBitsOrBothNaN(lanes[k].distance, reference[k].distance));
      REQUIRE(sameBitsOrBothNaN(lanes[k].overlap, reference[k].overlap));
    }
    kept += int(expected);
    dropped += int(count - expected);
  }
  // Both, on bodies of xz radius 0.5 whose centres are 0.8 apart along x
  // (they overlap by 0.2), 1.6 apart along z (not at all), exactly 1 apart
  // (touching: no overlap), and at one point, with xz radii 0.5 and 0.25
  // (by their sum).
  const std::vector<Record> five{{bspf::Vec3(0, 0, 0), {0.5f, 1}, 0},
                                 {bspf::Vec3(0.8f, 0, 0), {0.5f, 1}, 1},
                                 {bspf::Vec3(0, 0, 1.6f), {0.5f, 1}, 2},
                                 {bspf::Vec3(1, 0, 0), {0.5f, 1}, 3},
                                 {bspf::Vec3(0, 0, 0), {0.25f, 1}, 4}};
  for (const bool lanesToo : {false, true}) {
    std::vector<MeasuredPair> measured{{1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {4, 0, 0}};
    INFO((lanesToo ? "four lanes" : "one by one"));
    REQUIRE((lanesToo
                 ? bspf::detail::keepOverlapping(five.data(), measured.data(), 4)
                 : bspf::detail::keepOverlappingOneByOne(five.data(), measured.data(), 4)) == 2);
    CHECK(measured[0].pair == 1);
    CHECK(measured[0].distance == Approx(0.8f));
    CHECK(measured[0].overlap == Approx(0.2f));
    CHECK(measured[1].pair == 4);
    CHECK(measured[1].distance == 0);
    CHECK(measured[1].overlap == 0.75f);
  }
  // Both answers came up often, and the corner cases were there.
  CHECK(kept > 3000);
  CHECK(dropped > 3000);
  CHECK(atOnePoint > 100);
  CHECK(oneAboveOther > 200);
}
