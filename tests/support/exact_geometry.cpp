// SPDX-License-Identifier: MIT
#include "support/exact_geometry.h"

#include <Eigen/Geometry>
#include <algorithm>

#include "reference_geometry.h"

namespace bspf::test {

using V = Eigen::Vector3d;

double segmentSegmentDistance2(const V& p0, const V& p1, const V& q0, const V& q1) {
  const V d1 = p1 - p0, d2 = q1 - q0, r = p0 - q0;
  const double a = d1.squaredNorm(), e = d2.squaredNorm(), f = d2.dot(r);
  double s = 0, t = 0;
  if (a <= 0 && e <= 0) return r.squaredNorm();
  if (a <= 0) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= 0) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  return ((p0 + d1 * s) - (q0 + d2 * t)).squaredNorm();
}

namespace {
bool segmentCrossesTriangle(const V& p0, const V& p1, const V& a, const V& b, const V& c) {
  const V n = (b - a).cross(c - a);
  const double s0 = n.dot(p0 - a), s1 = n.dot(p1 - a);
  if ((s0 > 0 && s1 > 0) || (s0 < 0 && s1 < 0) || s0 == s1) return false;
  const V x = p0 + (p1 - p0) * (s0 / (s0 - s1));
  return n.dot((b - a).cross(x - a)) >= 0 && n.dot((c - b).cross(x - b)) >= 0 &&
         n.dot((a - c).cross(x - c)) >= 0;
}
}  // namespace

double segmentTriangleDistance2(const V& p0, const V& p1, const V& a, const V& b, const V& c) {
  if (segmentCrossesTriangle(p0, p1, a, b, c)) return 0;
  double best = (reference::closestPointOnTriangle(p0, a, b, c) - p0).squaredNorm();
  best = std::min(best, (reference::closestPointOnTriangle(p1, a, b, c) - p1).squaredNorm());
  best = std::min(best, segmentSegmentDistance2(p0, p1, a, b));
  best = std::min(best, segmentSegmentDistance2(p0, p1, b, c));
  best = std::min(best, segmentSegmentDistance2(p0, p1, c, a));
  return best;
}

bool sweptEllipsoidTouchesTriangle(const V& from, const V& to, EllipsoidRadii radii, const V& a,
                                   const V& b, const V& c) {
  const V toUnit(1.0 / radii.xz, 1.0 / radii.y, 1.0 / radii.xz);
  auto unit = [&](const V& p) -> V { return p.cwiseProduct(toUnit); };
  return segmentTriangleDistance2(unit(from), unit(to), unit(a), unit(b), unit(c)) <= 1.0;
}

bool triangleTouchesBox(const V& a, const V& b, const V& c, const V& low, const V& high) {
  // In the box's frame: centred on it, so its extent along an axis is
  // |axis| . half.
  const V centre = 0.5 * (low + high), half = 0.5 * (high - low);
  const V corners[3] = {a - centre, b - centre, c - centre};
  const auto separates = [&](const V& axis) {
    double lowest = corners[0].dot(axis), highest = lowest;
    for (const V& p : {corners[1], corners[2]}) {
      lowest = std::min(lowest, p.dot(axis));
      highest = std::max(highest, p.dot(axis));
    }
    const double reach = axis.cwiseAbs().dot(half);
    return lowest > reach || highest < -reach;
  };
  const V edges[3] = {b - a, c - b, a - c};
  if (separates(edges[0].cross(edges[1]))) return false;
  for (int k = 0; k < 3; ++k) {
    if (separates(V::Unit(k))) return false;
    for (const V& edge : edges)
      if (separates(V::Unit(k).cross(edge))) return false;
  }
  return true;
}

}  // namespace bspf::test
