// SPDX-License-Identifier: MIT
// Reference geometry for the judges (the accuracy oracle and the tests):
// double precision, brute force, and deliberately a different algorithm from
// the runtime's (bspf/geometry.h), so that a mistake in one is not repeated in
// the other. Depends on Eigen only, never on runtime code.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>

namespace bspf::reference {

using Point = Eigen::Vector3d;

/// The point of segment ab closest to `p` (a itself when the segment is a
/// point).
inline Point closestPointOnSegment(const Point& p, const Point& a, const Point& b) {
  const Point ab = b - a;
  const double length2 = ab.squaredNorm();
  if (length2 == 0) return a;
  return a + ab * std::clamp((p - a).dot(ab) / length2, 0.0, 1.0);
}

/// The point of triangle abc closest to `p`. The foot of the perpendicular on
/// the triangle's plane is the answer when its barycentric coordinates are
/// all non-negative; otherwise the closest point of a convex shape lies on its
/// boundary, the nearest of the three edges' closest points. A triangle of
/// zero area is handled as its edges.
inline Point closestPointOnTriangle(const Point& p, const Point& a, const Point& b,
                                    const Point& c) {
  const Point normal = (b - a).cross(c - a);
  const double area2 = normal.squaredNorm();
  if (area2 > 0) {
    const Point foot = p - normal * (normal.dot(p - a) / area2);
    // Each coordinate is the signed area of the sub-triangle opposite its
    // corner, over the whole.
    const double u = normal.dot((c - b).cross(foot - b)) / area2;
    const double v = normal.dot((a - c).cross(foot - c)) / area2;
    const double w = normal.dot((b - a).cross(foot - a)) / area2;
    if (u >= 0 && v >= 0 && w >= 0) return foot;
  }
  Point best = closestPointOnSegment(p, a, b);
  for (const Point& candidate : {closestPointOnSegment(p, b, c), closestPointOnSegment(p, c, a)})
    if ((candidate - p).squaredNorm() < (best - p).squaredNorm()) best = candidate;
  return best;
}

}  // namespace bspf::reference
