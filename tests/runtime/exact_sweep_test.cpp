// SPDX-License-Identifier: MIT
// The exact sweep's two stages (private: runtime/src/narrow_phase.h,
// exact_sweep.cpp): the time the face stage returns for a triangle it
// leaves open is one before which the edge stage finds nothing, so the
// slide may skip the edge stage of a triangle whose time is not before the
// earliest impact found so far; and the stages' AVX paths give their
// references' results bit for bit.
#include <bit>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>

#include "narrow_phase.h"

using bspf::Vec3;
using bspf::detail::Impact;
using bspf::detail::SpherePath;
using bspf::detail::Triangle;
using bspf::detail::TriangleD;

namespace {

// A triangle as sphereSpaceTriangle makes one: float corners, the float
// normal of its winding. `size` and `thinness` (0: equilateral-ish, near
// 1: a sliver) vary how far the rounded normal lets corners leave the plane.
Triangle randomTriangle(std::mt19937& rng, float size, float thinness) {
  std::uniform_real_distribution<float> u(-1, 1);
  const Vec3 origin(u(rng) * 50, u(rng) * 50, u(rng) * 50);
  const Vec3 along = Vec3(u(rng), u(rng), u(rng)).normalized();
  Vec3 across = along.cross(Vec3(u(rng), u(rng), u(rng))).normalized();
  Triangle t;
  t.a = origin;
  t.b = origin + along * size;
  t.c = origin + along * (size * (0.5f + 0.5f * u(rng))) + across * (size * (1 - thinness));
  t.normal = (t.b - t.a).cross(t.c - t.a).normalized();
  return t;
}

// The largest float not above `time`: an earlier impact found at the very
// time the bound allows, as a float.
float floatAtOrBelow(double time) {
  const float f = float(time);
  return double(f) <= time ? f : std::nextafter(f, -std::numeric_limits<float>::infinity());
}

// Whether the edge stage, against an earlier impact at `time`, leaves that
// impact as it was: no edge or corner of `triangle` is met before it.
bool edgeStageMeetsNothingBefore(const TriangleD& triangle, const SpherePath& path, float time) {
  Impact earlier{time, Vec3::UnitY()};
  const Impact before = earlier;
  bspf::detail::edgeImpact(triangle, path, earlier);
  return earlier.time == before.time && earlier.normal == before.normal;
}

// Edge k of `triangle` (corner k to corner k + 1), its unit normal, and the
// unit direction in the plane across the edge, out of the triangle: where
// the tests place points near an edge.
struct EdgeFrame {
  Eigen::Vector3d from, to, normal, outward;
};

EdgeFrame edgeFrame(const TriangleD& triangle, int k) {
  const Eigen::Vector3d corners[3] = {triangle.a, triangle.b, triangle.c};
  EdgeFrame edge{corners[k], corners[(k + 1) % 3], triangle.normal.normalized(), {}};
  edge.outward = (edge.to - edge.from).cross(edge.normal).normalized();
  return edge;
}

}  // namespace

TEST_CASE(
    "no edge or corner of a triangle the face stage leaves open is touched before the time it "
    "returns, on random triangles and paths that touch the plane just outside them",
    "[runtime][exact-sweep]") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(0, 1);
  int open = 0, boundAfterPlane = 0, edgeTouched = 0;
  for (int round = 0; round < 200000; ++round) {
    const float size = round % 4 == 0 ? 200.0f : float(0.2 + 10 * unit(rng));
    const float thinness = round % 3 == 0 ? float(1 - std::pow(10.0, -1 - 3 * unit(rng))) : 0.0f;
    const Triangle tri = randomTriangle(rng, size, thinness);
    const TriangleD triangle(tri);
    // The point where the sphere touches the plane: just beyond an edge
    // (by up to 0.3, often much less), in the plane.
    const EdgeFrame frame = edgeFrame(triangle, int(rng() % 3));
    const Eigen::Vector3d &from = frame.from, &to = frame.to, &n = frame.normal,
                          &outward = frame.outward;
    const double beyond = 0.3 * std::pow(unit(rng), 3);
    const Eigen::Vector3d touch = from + (to - from) * (-0.1 + 1.2 * unit(rng)) + outward * beyond;
    // A move that reaches the plane at `touchTime` there, approaching it
    // from 10 degrees to head-on, sliding along it at up to 1.5.
    const double touchTime = 0.05 + 0.9 * unit(rng);
    const double approach = 0.005 + unit(rng);
    const Eigen::Vector3d tangent =
        n.cross(Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5)).normalized();
    const Eigen::Vector3d move = -n * approach + tangent * (1.5 * unit(rng));
    const Eigen::Vector3d start = touch + n - touchTime * move;
    const SpherePath path(start.cast<float>(), move.cast<float>());

    Impact face;
    bool penetrating = false;
    const double bound = bspf::detail::faceImpact(triangle, path, face, penetrating);
    if (face.time <= 1 || penetrating || !(bound < 1)) continue;  // met on the face, or closed
    ++open;
    Impact first;
    bspf::detail::edgeImpact(triangle, path, first);
    if (first.time <= 1) ++edgeTouched;
    // The plane's time, as the face stage computes it: the bound the slide
    // used before this one, which skipped the edge stage against an earlier
    // impact at that time or before.
    const double planeTime =
        (-triangle.normal.dot(triangle.a - path.start) - 1) / -triangle.normal.dot(path.move);
    const float latest = floatAtOrBelow(bound);
    if (!(latest > planeTime)) continue;
    ++boundAfterPlane;
    // What the slide now skips too: the edge stage against an earlier
    // impact at (as a float) the bound. It must find nothing earlier.
    INFO("round " << round << " bound " << bound << " plane " << planeTime << " edge time "
                  << first.time << " rise " << triangle.rise);
    REQUIRE(edgeStageMeetsNothingBefore(triangle, path, latest));
  }
  // The rounds must reach the cases the bound is for: open triangles whose
  // edges are touched soon after the plane, the bound later than the plane.
  CHECK(open > 50000);
  CHECK(edgeTouched > 20000);
  CHECK(boundAfterPlane > 20000);
}

TEST_CASE(
    "for a start within reach of a triangle's plane but not of the triangle, no edge or corner is "
    "touched before the time the face stage returns, nor at all when it settles the triangle",
    "[runtime][exact-sweep]") {
  std::mt19937 rng(14);
  std::uniform_real_distribution<double> unit(0, 1);
  int settledMovingAway = 0, boundAfterLength = 0, edgeTouched = 0;
  for (int round = 0; round < 200000; ++round) {
    const float size = round % 4 == 0 ? 200.0f : float(0.2 + 10 * unit(rng));
    const Triangle tri = randomTriangle(rng, size, round % 3 == 0 ? 0.9f : 0.0f);
    const TriangleD triangle(tri);
    // A start beside an edge (1 to 1.5 out from it, the triangle's plane
    // within reach), a move in any direction: away from the triangle,
    // passing by, or onto its edge.
    const EdgeFrame frame = edgeFrame(triangle, int(rng() % 3));
    const Eigen::Vector3d &from = frame.from, &to = frame.to, &n = frame.normal,
                          &outward = frame.outward;
    const Eigen::Vector3d start = from + (to - from) * (0.1 + 0.8 * unit(rng)) +
                                  outward * (1 + 0.5 * unit(rng)) + n * (0.95 * unit(rng));
    const Eigen::Vector3d direction =
        Eigen::Vector3d(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5).normalized();
    const SpherePath path(start.cast<float>(), (direction * (3 * unit(rng))).cast<float>());
    if (!(-triangle.normal.dot(triangle.a - path.start) < 1)) continue;  // not within reach

    Impact face;
    bool penetrating = false;
    const double bound = bspf::detail::faceImpact(triangle, path, face, penetrating);
    Impact edge;
    bspf::detail::edgeImpact(triangle, path, edge);
    INFO("round " << round << " bound " << bound << " edge time " << edge.time);
    REQUIRE_FALSE(penetrating);
    if (edge.time <= 1) ++edgeTouched;
    const Eigen::Vector3d closest = bspf::closestPointOnTriangle<Eigen::Vector3d>(
        path.start, triangle.a, triangle.b, triangle.c);
    const double gap = (closest - path.start).norm() - 1;
    if (!(bound < 1)) {
      // Settled: no edge or corner is touched within the move.
      REQUIRE(edge.time > 1);
      settledMovingAway += path.move.dot(path.start - closest) > 0 && gap < path.length;
      continue;
    }
    // Later than the gap over the move's whole length (the bound it
    // improves on) by more than rounding: the edge stage, against an
    // earlier impact at the bound (as a float), finds nothing earlier.
    if (bound > 1.001 * gap / path.length) ++boundAfterLength;
    REQUIRE(edgeStageMeetsNothingBefore(triangle, path, floatAtOrBelow(bound)));
  }
  // The rounds must reach every case: moves settled though long enough to
  // reach the triangle, bounds later than the gap over the length, edges
  // and corners touched.
  CHECK(settledMovingAway > 5000);
  CHECK(boundAfterLength > 5000);
  CHECK(edgeTouched > 5000);
}

TEST_CASE(
    "a start a hair's breadth beside a triangle's edge, moving onto it, is left open for the edge "
    "stage, which finds the touch at once",
    "[runtime][exact-sweep]") {
  // The triangle in the plane y = 0, facing up, on the -z side of its edge
  // along x; the start 0.5 above the plane and just over 1 from the edge.
  Triangle tri;
  tri.a = Vec3(0, 0, 0);
  tri.b = Vec3(10, 0, 0);
  tri.c = Vec3(0, 0, -10);
  tri.normal = Vec3::UnitY();
  const TriangleD triangle(tri);
  for (const float beyond : {1e-7f, 3e-7f, 6e-7f}) {
    const float z = float(std::sqrt(std::pow(1.0 + beyond, 2) - 0.25));
    const SpherePath path(Vec3(5, 0.5f, z), Vec3(0, 0, -0.5f));
    const double gap = std::hypot(0.5, double(z)) - 1;
    INFO("beyond " << beyond << " gap " << gap);
    REQUIRE(gap > 0);
    REQUIRE(gap < 1e-6);
    Impact face;
    bool penetrating = false;
    const double bound = bspf::detail::faceImpact(triangle, path, face, penetrating);
    REQUIRE_FALSE(penetrating);
    REQUIRE(bound < 1e-5);
    Impact edge;
    bspf::detail::edgeImpact(triangle, path, edge);
    REQUIRE(edge.time < 1e-5f);
    REQUIRE(edge.time >= bound);
  }
}

TEST_CASE(
    "the face stage gives the same answer with a triangle's last measured distance as without, "
    "on random walks near triangles within reach of their planes",
    "[runtime][exact-sweep]") {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> unit(0, 1);
  int settledByMeasure = 0, measured = 0, open = 0;
  for (int walk = 0; walk < 5000; ++walk) {
    const Triangle tri = randomTriangle(rng, float(0.2 + 10 * unit(rng)), 0.0f);
    const TriangleD triangle(tri);
    const Eigen::Vector3d n = triangle.normal.normalized();
    const Eigen::Vector3d centre = (triangle.a + triangle.b + triangle.c) / 3;
    // Starting beside the triangle, within reach of its plane, then
    // stepping about as a walker does from one sweep to the next.
    const Eigen::Vector3d outward = (triangle.b - triangle.a).cross(n).normalized();
    Eigen::Vector3d start =
        centre + (triangle.a - centre) * 1.05 + outward * (1 + unit(rng)) + n * (0.9 * unit(rng));
    bspf::detail::MeasuredDistance last;
    for (int step = 0; step < 40; ++step) {
      Eigen::Vector3d move(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
      move *= 0.6 * unit(rng);
      const SpherePath path(start.cast<float>(), move.cast<float>());
      Impact withMeasure, without;
      bool penetratingWith = false, penetratingWithout = false;
      const bspf::detail::MeasuredDistance before = last;
      const double a =
          bspf::detail::faceImpact(triangle, path, withMeasure, penetratingWith, &last);
      const double b = bspf::detail::faceImpact(triangle, path, without, penetratingWithout);
      REQUIRE(a == b);
      REQUIRE(withMeasure.time == without.time);
      REQUIRE(withMeasure.normal == without.normal);
      REQUIRE(penetratingWith == penetratingWithout);
      if (before.distance >= 0 && last.from == before.from && last.distance == before.distance &&
          -triangle.normal.dot(triangle.a - path.start) < 1)
        ++settledByMeasure;
      else if (last.distance >= 0)
        ++measured;
      if (b < 1) ++open;
      // The next sweep starts near where this one ended, sometimes the
      // other side of the plane (the face stage then ignores the triangle).
      start += move * unit(rng);
    }
  }
  CHECK(settledByMeasure > 20000);
  CHECK(measured > 20000);
  CHECK(open > 500);
}

namespace {

// Whether two impacts are the same bit for bit (time, normal and kind).
bool sameImpact(const Impact& x, const Impact& y) {
  return std::bit_cast<std::uint32_t>(x.time) == std::bit_cast<std::uint32_t>(y.time) &&
         std::memcmp(x.normal.data(), y.normal.data(), sizeof(float) * 3) == 0 && x.edge == y.edge;
}

}  // namespace

TEST_CASE(
    "the face and edge stages' AVX paths give the reference's times and impacts bit for bit, on "
    "random triangles and paths that pass close to their edges",
    "[runtime][exact-sweep]") {
  if (!bspf::detail::sweepUsesAvx()) {
    WARN("this CPU has no AVX: the stages run their references only");
    return;
  }
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> unit(0, 1);
  int faceHits = 0, faceOpen = 0, edgeHits = 0, cornerHits = 0;
  for (int round = 0; round < 300000; ++round) {
    const float size = round % 4 == 0 ? 200.0f : float(0.05 + 10 * unit(rng));
    const float thinness = round % 3 == 0 ? float(1 - std::pow(10.0, -1 - 5 * unit(rng))) : 0.0f;
    const Triangle tri = randomTriangle(rng, size, thinness);
    const TriangleD triangle(tri);
    // A point of the plane near edge k (inside or outside it, often by
    // very little, where the side values' signs turn), the start up to 2
    // in front of it (or just behind), the move towards and along the plane.
    const EdgeFrame frame = edgeFrame(triangle, int(rng() % 3));
    const Eigen::Vector3d &from = frame.from, &to = frame.to, &n = frame.normal,
                          &outward = frame.outward;
    const double beyond = (unit(rng) < 0.5 ? -1 : 1) * 1.5 * std::pow(unit(rng), 4);
    const Eigen::Vector3d near = from + (to - from) * (-0.2 + 1.4 * unit(rng)) + outward * beyond;
    const Eigen::Vector3d start = near + n * (-0.05 + 2 * unit(rng));
    const Eigen::Vector3d wander(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5);
    const Eigen::Vector3d move = (-n * unit(rng) + wander) * (2 * std::pow(unit(rng), 2));
    const SpherePath path(start.cast<float>(), move.cast<float>());
    // Against no earlier impact, or one at a random time.
    Impact prior;
    if (round % 3 == 0) prior = {float(unit(rng)), Vec3::UnitY()};

    Impact face = prior, faceReference = prior;
    bool penetrating = false, penetratingReference = false;
    const double bound = bspf::detail::faceImpact(triangle, path, face, penetrating);
    const double boundReference =
        bspf::detail::scalarFaceImpact(triangle, path, faceReference, penetratingReference);
    INFO("round " << round);
    REQUIRE(std::bit_cast<std::uint64_t>(bound) == std::bit_cast<std::uint64_t>(boundReference));
    REQUIRE(sameImpact(face, faceReference));
    REQUIRE(penetrating == penetratingReference);
    if (face.time < prior.time) ++faceHits;
    if (bound < 1) ++faceOpen;

    Impact edge = prior, edgeReference = prior;
    bspf::detail::edgeImpact(triangle, path, edge);
    bspf::detail::scalarEdgeImpact(triangle, path, edgeReference);
    REQUIRE(sameImpact(edge, edgeReference));
    if (edge.time < prior.time) {
      // An edge's or a corner's normal is perpendicular to the edges of
      // the corner (when it is met there): counted apart, roughly.
      const Eigen::Vector3d normal = edge.normal.cast<double>();
      ++(std::abs(normal.dot((to - from).normalized())) < 1e-3 ? edgeHits : cornerHits);
    }
  }
  // The rounds must reach every outcome of both stages.
  CHECK(faceHits > 20000);
  CHECK(faceOpen > 20000);
  CHECK(edgeHits > 20000);
  CHECK(cornerHits > 5000);
}
