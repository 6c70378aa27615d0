// The accuracy oracle: exact answers to "how wrong is this position?", for
// walkers, the tests and the benchmarks. Slow and simple on purpose (double
// precision, no approximations); never used by the runtime itself.
#pragma once

#include <bspf/movement.h>
#include <bspf/query.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace bspf::oracle {

/// How deep an ellipsoid at `centre` is in the level, as a fraction of its
/// size: 1 - (distance from the centre to the nearest triangle it faces, in
/// the space where the ellipsoid is the unit sphere). 0 when it touches
/// nothing; 0.1 means the surface is a tenth of the way in towards the centre
/// along the contact direction. Triangles whose back the centre sees are
/// ignored (they are one-sided, as in the runtime).
inline double penetration(const World& world, const Vec3& centre, EllipsoidRadii radii,
                          SweepScratch& scratch, std::vector<std::uint32_t>& candidates) {
  collectCandidateTriangles(world, centre, centre, radii, scratch, candidates);
  const Eigen::Vector3d toSphere(1.0 / radii.xz, 1.0 / radii.y, 1.0 / radii.xz);
  const Eigen::Vector3d p = centre.cast<double>().cwiseProduct(toSphere);
  double nearest = 1;
  for (const std::uint32_t t : candidates) {
    const schema::Triangle& tri = world.triangles()[t];
    auto corner = [&](std::uint32_t v) -> Eigen::Vector3d {
      return toVec3(world.vertices()[v]).cast<double>().cwiseProduct(toSphere);
    };
    const Eigen::Vector3d a = corner(tri.v0()), b = corner(tri.v1()), c = corner(tri.v2());
    if ((b - a).cross(c - a).dot(p - a) < 0) continue;  // behind a one-sided triangle
    nearest = std::min(nearest, (closestPointOnTriangle(p, a, b, c) - p).norm());
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
