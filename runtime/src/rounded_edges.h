// SPDX-License-Identifier: MIT
// The planes method's rounded edge test (docs/algorithm.md, "Ghost edges"):
// the six planes square off a triangle's edges and corners, so a steep face
// blocks a body whose centre passes above its top edge although the rounded
// body would ride over that edge (the top edge of a 1 cm lip, the sides of
// a gap in a floor narrower than the body). There the planes slide asks
// what the exact sweep's rounded body would meet.
// Private to the runtime.
#pragma once

#include <bspf/geometry.h>
#include <bspf/world.h>

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace bspf::detail {

/// Whether `point` lies beyond one of the triangle's own (not grown) edge
/// or corner planes: a body centred there, in reach of the face plane,
/// would meet the edge or corner, not the face.
inline bool beyondEdges(const schema::TrianglePlanes& planes, const Vec3& point) {
  for (int k = 0; k < 3; ++k) {
    if (signedDistance(*planes.edges()->Get(k), point) < 0) return true;
    if (signedDistance(*planes.caps()->Get(k), point) < 0) return true;
  }
  return false;
}

/// The largest y of triangle `triangle`'s corners.
inline float highestCornerY(const World& world, std::uint32_t triangle) {
  const schema::Triangle& corners = world.triangles()[triangle];
  return std::max({world.vertices()[corners.v0()].y(), world.vertices()[corners.v1()].y(),
                   world.vertices()[corners.v2()].y()});
}

/// Whether a steep triangle's six planes block a body centred at `point`
/// only through a squared-off edge that the rounded body would ride over
/// (the exact sweep's rule for the edge of a step): `point`, where the
/// planes were met on the move start -> end, lies beyond the triangle's own
/// edges, and the whole triangle lies so far below the whole move that the
/// body, coming at it level, would first touch it where its own normal is
/// walkable (y at least `walkableNormalY`): for the default 0.45 by 0.85 m
/// body and 45 degrees, 0.75 m below the centre, that is under 0.10 m above
/// its bottom. The centre's path never crosses such a triangle. The
/// walkable surface behind its edge holds the body instead (the top of a
/// 1 cm lip, the floor beside a gap narrower than the body).
/// `highest`: highestCornerY(world, triangle), which the slide keeps with
/// the triangle's grown planes (GrownTriangle::highestY).
inline bool ridesOverEdge(const World& world, std::uint32_t triangle, float highest,
                          const Vec3& point, const Vec3& start, const Vec3& end,
                          EllipsoidRadii radii, float walkableNormalY) {
  const float below = std::min(start.y(), end.y()) - highest;
  // A triangle reaching above the centre's path (most walls a body walks
  // into) fails the test below whatever `least` is: no square root for it.
  if (!(below >= 0)) return false;
  // The unit sphere's normal at a point `a` below its centre (and
  // sqrt(1 - a^2) across) is, in world space, along (sqrt(1 - a^2) / rxz,
  // a / ry); it is walkable from a = least on.
  const float w2 = walkableNormalY * walkableNormalY;
  const float inverseXz2 = 1 / (radii.xz * radii.xz), inverseY2 = 1 / (radii.y * radii.y);
  const float least = std::sqrt(w2 * inverseXz2 / ((1 - w2) * inverseY2 + w2 * inverseXz2));
  return below >= least * radii.y && beyondEdges(world.trianglePlanes()[triangle], point);
}

}  // namespace bspf::detail
