// SPDX-License-Identifier: MIT
// bspf::closestPointOnTriangle (runtime) against the independent reference
// (samples/reference_geometry.h), region by region and on random points, in
// float and in double.
#include <bspf/geometry.h>

#include <array>
#include <catch2/catch.hpp>
#include <cmath>
#include <random>
#include <string>

#include "reference_geometry.h"

namespace {

using Point = Eigen::Vector3d;

struct Triangle {
  Point a, b, c;
  Point unitNormal() const { return (b - a).cross(c - a).normalized(); }
};

// The part of the triangle a region's closest point lies on.
struct RegionPoint {
  std::string region;
  Point query;
  Point expected;  // known by construction
};

// In the plane of `t`, the unit direction away from the triangle across edge
// from->to.
Point outwardAcross(const Triangle& t, const Point& from, const Point& to) {
  return (to - from).cross(t.unitNormal()).normalized();
}

// One query per Voronoi region (3 corners, 3 edges, the face), `height` off
// the plane, with the closest point each must have.
std::vector<RegionPoint> onePointPerRegion(const Triangle& t, double height) {
  const Point up = t.unitNormal() * height;
  const std::array<Point, 3> corners{t.a, t.b, t.c};
  const std::array<std::string, 3> names{"a", "b", "c"};
  std::vector<RegionPoint> points;
  for (int i = 0; i < 3; ++i) {
    const Point& from = corners[i];
    const Point& to = corners[(i + 1) % 3];
    const Point& previous = corners[(i + 2) % 3];
    const std::string edge = names[i] + names[(i + 1) % 3];
    // Beyond an edge, level with a point a third of the way along it.
    const Point onEdge = from + (to - from) / 3.0;
    points.push_back({"edge " + edge, onEdge + outwardAcross(t, from, to) * 0.7 + up, onEdge});
    // Beyond a corner: outside both edges that meet there, past each one's
    // end, so the corner itself is the closest point.
    const Point beyondCorner = (from - to).normalized() + (from - previous).normalized();
    points.push_back({"corner " + names[i], from + beyondCorner.normalized() * 0.8 + up, from});
  }
  const Point inside = (t.a * 0.2 + t.b * 0.3 + t.c * 0.5);
  points.push_back({"face", inside + up, inside});
  return points;
}

template <typename Vector>
Point runtimeClosest(const Point& p, const Triangle& t) {
  using Scalar = typename Vector::Scalar;
  const Vector result = bspf::closestPointOnTriangle<Vector>(
      p.cast<Scalar>(), t.a.cast<Scalar>(), t.b.cast<Scalar>(), t.c.cast<Scalar>());
  return result.template cast<double>();
}

// A scalene, tilted triangle: no symmetry to hide a swapped edge or corner.
const Triangle kTilted{{0.3, -0.2, 0.1}, {2.9, 0.4, -0.3}, {1.1, 1.3, 1.7}};

}  // namespace

TEST_CASE("the reference closest point is the corner, edge point or face point by construction",
          "[runtime][geometry]") {
  for (const double height : {0.0, 0.6, -0.9}) {
    for (const RegionPoint& r : onePointPerRegion(kTilted, height)) {
      INFO(r.region << ", " << height << " off the plane");
      const Point got =
          bspf::reference::closestPointOnTriangle(r.query, kTilted.a, kTilted.b, kTilted.c);
      CHECK((got - r.expected).norm() < 1e-12);
    }
  }
}

TEST_CASE("closestPointOnTriangle finds the right point in each of the seven regions",
          "[runtime][geometry]") {
  for (const double height : {0.0, 0.6, -0.9}) {
    for (const RegionPoint& r : onePointPerRegion(kTilted, height)) {
      INFO(r.region << ", " << height << " off the plane");
      CHECK((runtimeClosest<Eigen::Vector3d>(r.query, kTilted) - r.expected).norm() < 1e-12);
      CHECK((runtimeClosest<Eigen::Vector3f>(r.query, kTilted) - r.expected).norm() < 1e-5);
    }
  }
}

TEST_CASE("closestPointOnTriangle agrees with the reference on random triangles and points",
          "[runtime][geometry]") {
  std::mt19937 rng(20261123);
  std::uniform_real_distribution<double> coordinate(-3, 3);
  auto randomPoint = [&] { return Point(coordinate(rng), coordinate(rng), coordinate(rng)); };
  int corners = 0, edges = 0, faces = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Triangle t{randomPoint(), randomPoint(), randomPoint()};
    // Slivers make the float answer ill-conditioned; the regions are what
    // this test is about.
    const double longest = std::max({(t.b - t.a).norm(), (t.c - t.b).norm(), (t.a - t.c).norm()});
    if ((t.b - t.a).cross(t.c - t.a).norm() < 0.2 * longest * longest) continue;
    const Point p = randomPoint();
    const Point expected = bspf::reference::closestPointOnTriangle(p, t.a, t.b, t.c);
    INFO("trial " << trial << ": p " << p.transpose() << ", triangle " << t.a.transpose() << " / "
                  << t.b.transpose() << " / " << t.c.transpose());
    REQUIRE((runtimeClosest<Eigen::Vector3d>(p, t) - expected).norm() < 1e-9);
    REQUIRE((runtimeClosest<Eigen::Vector3f>(p, t) - expected).norm() < 1e-4);
    const bool atCorner = (expected - t.a).norm() < 1e-9 || (expected - t.b).norm() < 1e-9 ||
                          (expected - t.c).norm() < 1e-9;
    const bool onFace = (expected - p).cross(t.unitNormal()).norm() < 1e-9;
    (atCorner ? corners : onFace ? faces : edges)++;
  }
  // Every kind of region was visited often.
  CHECK(corners > 1000);
  CHECK(edges > 1000);
  CHECK(faces > 1000);
}
