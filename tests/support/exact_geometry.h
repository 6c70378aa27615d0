// SPDX-License-Identifier: MIT
// Exact reference geometry for tests (double precision, no tolerances): the
// oracle the runtime's fast paths are checked against. Built on
// samples/reference_geometry.h, never on the runtime's own geometry.
#pragma once

#include <bspf/geometry.h>

#include <Eigen/Core>

namespace bspf::test {

// Closest points on triangles: bspf::reference::closestPointOnTriangle
// (samples/reference_geometry.h).

/// Squared distance between segments p0p1 and q0q1.
double segmentSegmentDistance2(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                               const Eigen::Vector3d& q0, const Eigen::Vector3d& q1);

/// Squared distance between segment p0p1 and triangle abc (0 when they cross).
double segmentTriangleDistance2(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                const Eigen::Vector3d& c);

/// Whether the ellipsoid with `radii` swept from `from` to `to` touches
/// triangle abc (closed sets: touching counts). Exact: works in the space
/// where the ellipsoid is the unit sphere.
bool sweptEllipsoidTouchesTriangle(const Eigen::Vector3d& from, const Eigen::Vector3d& to,
                                   EllipsoidRadii radii, const Eigen::Vector3d& a,
                                   const Eigen::Vector3d& b, const Eigen::Vector3d& c);

/// Whether triangle abc has a point in the box [low, high] (closed sets:
/// touching counts). Separating axes: the box's three, the triangle's
/// normal, and the nine cross products of their edges.
bool triangleTouchesBox(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c, const Eigen::Vector3d& low,
                        const Eigen::Vector3d& high);

}  // namespace bspf::test
