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

}  // namespace bspf
