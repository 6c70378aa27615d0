#include "support/exact_geometry.h"

#include <Eigen/Geometry>
#include <algorithm>

namespace bspf::test {

using V = Eigen::Vector3d;

V closestPointOnTriangle(const V& p, const V& a, const V& b, const V& c) {
  // Regions of the triangle's Voronoi diagram, by barycentric signs.
  const V ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const V bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const V cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

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
  double best = (closestPointOnTriangle(p0, a, b, c) - p0).squaredNorm();
  best = std::min(best, (closestPointOnTriangle(p1, a, b, c) - p1).squaredNorm());
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

}  // namespace bspf::test
