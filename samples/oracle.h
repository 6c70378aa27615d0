// SPDX-License-Identifier: MIT
// The accuracy oracle: exact answers to "how wrong is this position?", for
// walkers, the tests and the benchmarks. Slow and simple on purpose (double
// precision, no approximations); never used by the runtime itself.
#pragma once

#include <bspf/movement.h>
#include <bspf/world.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "reference_geometry.h"

namespace bspf::oracle {

/// Every triangle of a level in double precision, with its bounding box, for
/// penetration(). Built once per world (one pass over its triangles); the
/// judge reads the blob's vertices itself and never the runtime's tree.
class LevelTriangles {
 public:
  explicit LevelTriangles(const World& world) {
    const auto vertex = [&](std::uint32_t v) -> reference::Point {
      return toVec3(world.vertices()[v]).cast<double>();
    };
    corners_.reserve(world.triangles().size());
    boxes_.reserve(world.triangles().size());
    for (const schema::Triangle& tri : world.triangles()) {
      const Corners corners{vertex(tri.v0()), vertex(tri.v1()), vertex(tri.v2())};
      // The corners are floats widened to double, so the box is exact.
      boxes_.push_back({corners.a.cwiseMin(corners.b).cwiseMin(corners.c),
                        corners.a.cwiseMax(corners.b).cwiseMax(corners.c)});
      corners_.push_back(corners);
    }
  }

  struct Corners {
    reference::Point a, b, c;
  };
  struct Box {
    reference::Point low, high;
  };
  std::size_t size() const { return corners_.size(); }
  const Corners& corners(std::size_t t) const { return corners_[t]; }
  const Box& box(std::size_t t) const { return boxes_[t]; }

 private:
  // Boxes apart from corners: the scan reads only boxes for most triangles.
  std::vector<Corners> corners_;
  std::vector<Box> boxes_;
};

/// How deep an ellipsoid at `centre` is in the level, as a fraction of its
/// size: 1 - (distance from the centre to the nearest triangle it faces, in
/// the space where the ellipsoid is the unit sphere). 0 when it touches
/// nothing; 0.1 means the surface is a tenth of the way in towards the centre
/// along the contact direction. Triangles whose back the centre sees are
/// ignored (they are one-sided, as in the runtime). Brute force over every
/// triangle; only those whose box misses the ellipsoid's box are skipped.
inline double penetration(const LevelTriangles& level, const Vec3& centre, EllipsoidRadii radii) {
  const reference::Point extent(radii.xz, radii.y, radii.xz);
  const reference::Point low = centre.cast<double>() - extent;
  const reference::Point high = centre.cast<double>() + extent;
  const reference::Point toSphere = extent.cwiseInverse();
  const reference::Point p = centre.cast<double>().cwiseProduct(toSphere);
  double nearest = 1;
  for (std::size_t t = 0; t < level.size(); ++t) {
    const LevelTriangles::Box& box = level.box(t);
    if ((box.low.array() > high.array()).any() || (box.high.array() < low.array()).any()) continue;
    const LevelTriangles::Corners& corners = level.corners(t);
    const reference::Point a = corners.a.cwiseProduct(toSphere);
    const reference::Point b = corners.b.cwiseProduct(toSphere);
    const reference::Point c = corners.c.cwiseProduct(toSphere);
    if ((b - a).cross(c - a).dot(p - a) < 0) continue;  // behind a one-sided triangle
    nearest = std::min(nearest, (reference::closestPointOnTriangle(p, a, b, c) - p).norm());
  }
  return 1 - nearest;
}

/// Whether `p` is inside a closed, outward-facing triangle mesh (the level's
/// solids), by the winding number: the sum of the solid angles of all
/// triangles seen from `p`, over 4 pi, is 1 inside a closed solid and 0
/// outside (Van Oosterom and Strackee's formula per triangle). Overlapping
/// solids add up; anything >= 0.5 counts as inside. Cost: one pass over all
/// triangles.
inline bool insideClosedMesh(const World& world, const Vec3& point) {
  const Eigen::Vector3d p = point.cast<double>();
  double solidAngle = 0;
  for (const schema::Triangle& tri : world.triangles()) {
    const Eigen::Vector3d a = toVec3(world.vertices()[tri.v0()]).cast<double>() - p;
    const Eigen::Vector3d b = toVec3(world.vertices()[tri.v1()]).cast<double>() - p;
    const Eigen::Vector3d c = toVec3(world.vertices()[tri.v2()]).cast<double>() - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double numerator = a.dot(b.cross(c));
    const double denominator = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
    solidAngle += 2 * std::atan2(numerator, denominator);
  }
  return solidAngle / (4 * M_PI) >= 0.5;
}

/// How far apart the two narrow phases end one step of `body` from the same
/// state (metres): the planes method's end against the exact sweep's, each
/// moving a copy with the same force and dt against the level alone.
inline double stepDeviation(const World& world, const Body& body, const Vec3& force, float dt,
                            StepScratch& scratch) {
  Body planes = body, exact = body;
  planes.settings.method = CollisionMethod::Planes;
  exact.settings.method = CollisionMethod::ExactSweep;
  stepBody(world, planes, force, dt, scratch);
  stepBody(world, exact, force, dt, scratch);
  return (planes.position - exact.position).cast<double>().norm();
}

/// The p-th quantile (0..1) of `values` (sorted in place); 0 when empty.
inline double quantile(std::vector<double>& values, double p) {
  if (values.empty()) return 0;
  std::sort(values.begin(), values.end());
  const auto index = static_cast<std::size_t>(std::ceil(p * double(values.size()))) - 1;
  return values[std::min(index, values.size() - 1)];
}

}  // namespace bspf::oracle
