// SPDX-License-Identifier: MIT
// bspf geometry primitives: small, header-only, free functions.
//
// Units are metres throughout. Planes follow the blob's convention (see
// docs/format.md): the plane {p : dot(n, p) == d} with unit normal n, and
// dot(n, p) - d > 0 on its front side.
#pragma once

#include <bspf/bspf_generated.h>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace bspf {

using Vec3 = Eigen::Vector3f;

/// An axis-aligned ellipsoid's semi-axes in metres: `xz` along X and Z, `y`
/// along Y. Both must be > 0.
struct EllipsoidRadii {
  float xz = 0.45f;
  float y = 0.85f;
};

/// The blob's vector type as an Eigen vector (a copy of three floats).
inline Vec3 toVec3(const schema::Vec3& v) { return {v.x(), v.y(), v.z()}; }

/// Signed distance in metres from `p` to `plane`: positive on its front side.
inline float signedDistance(const schema::Plane& plane, const Vec3& p) {
  const schema::Vec3& n = plane.normal();
  return n.x() * p.x() + n.y() * p.y() + n.z() * p.z() - plane.distance();
}

/// Distance in metres from an ellipsoid's centre to its tangent plane with unit
/// normal `n`: the ellipsoid's extent along `n` (its support function). This is
/// the article's "collision radius". Precondition: `n` has unit length.
inline float effectiveRadius(const Vec3& n, EllipsoidRadii radii) {
  const float x = radii.xz * n.x();
  const float y = radii.y * n.y();
  const float z = radii.xz * n.z();
  return std::sqrt(x * x + y * y + z * z);
}

inline float effectiveRadius(const schema::Vec3& n, EllipsoidRadii radii) {
  return effectiveRadius(toVec3(n), radii);
}

/// The point of triangle abc closest to `p` (any Eigen 3-vector type, float
/// or double). Works by the region of the triangle's Voronoi diagram `p`
/// falls in: a corner, an edge, or the face. Precondition: abc has non-zero
/// area.
template <typename Vector>
Vector closestPointOnTriangle(const Vector& p, const Vector& a, const Vector& b, const Vector& c) {
  using Scalar = typename Vector::Scalar;
  const Vector ab = b - a, ac = c - a, ap = p - a;
  const Scalar d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector bp = p - b;
  const Scalar d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const Scalar vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vector cp = p - c;
  const Scalar d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const Scalar vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const Scalar va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const Scalar denom = Scalar(1) / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

}  // namespace bspf
