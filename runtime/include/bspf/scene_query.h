// SPDX-License-Identifier: MIT
// bspf/scene_query.h: what a game asks a level besides moving a body.
//
// Ray casts (line of sight, bullets, cameras, spawn placement), an ellipsoid
// cast without sliding (a mantle check, a grenade, a camera's collision),
// an overlap test (spawning, teleports, "can I stand up here") and the
// closest point of the level. All use the level's BSP tree (bspf/query.h)
// and read the World in place, never copying geometry.
//
// Units are metres. Thread safety: every function only reads the World, so
// any number of threads may query one World at once (and while bodies step
// on it); castRay and castRays need no scratch at all, the others take a
// caller-owned QueryScratch (one per thread) or, in the overloads without
// one, use one per thread owned by the runtime (thread_local).
//
// Every query returns std::optional of a result struct, empty on a miss
// (overlapsEllipsoid returns bool).
//
//   if (auto hit = bspf::castRay(world, eye, forward, 100.0f))
//     spawnDecal(hit->point, hit->normal);
#pragma once

#include <bspf/geometry.h>
#include <bspf/query.h>
#include <bspf/world.h>

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace bspf {

/// Which sides of a triangle a ray meets. A triangle's front is the side its
/// normal points to (counter-clockwise winding seen from there): a closed
/// room's walls face into the room.
enum class RayFaces : std::uint8_t {
  /// Only fronts: a ray from inside a solid passes out through its faces.
  Front,
  /// Both sides, as a two-sided surface.
  Both,
  /// Only backs: whether a point is inside a closed solid.
  Back,
};

/// Where a ray met the level.
struct RayHit {
  /// Metres from the origin along the (normalised) direction, in
  /// [0, maxDistance].
  float distance = 0;
  /// The point met: origin + distance * direction, metres.
  Vec3 point = Vec3::Zero();
  /// The triangle's unit face normal, turned to point back against the ray
  /// on a back-face hit (it always faces the side the ray came from).
  Vec3 normal = Vec3::Zero();
  /// The triangle's index in World::triangles().
  std::uint32_t triangle = 0;
  /// The triangle's surface id (0 until the level records surfaces).
  std::uint32_t surface = 0;
  /// Whether the ray met the triangle's back (only with RayFaces::Both or
  /// RayFaces::Back).
  bool backFace = false;
};

/// The first triangle the ray from `origin` along `direction` meets within
/// `maxDistance` metres, or nothing. `direction` need not be unit length (it
/// is normalised; distances are metres). A triangle counts when the ray
/// crosses its plane, from the side `faces` allows, inside the triangle or on
/// its boundary (within 1e-6 m plus 4e-7 of the coordinates' size, so a ray
/// through an edge shared by two triangles meets one of them); a ray
/// starting on a triangle's plane meets it at distance 0; a ray parallel to a
/// triangle's plane never meets it. At equal distances, the triangle tested
/// first wins.
///
/// Cost: a front-to-back walk of the BSP tree along the ray, stopping at the
/// first leaf past which nothing can be nearer: O(leaves the ray crosses
/// before its hit + their triangles), usually a few hundred nanoseconds; a
/// ray that meets nothing crosses every leaf to maxDistance. No allocation,
/// no scratch: the walk's stack is on the call stack.
/// Preconditions: finite origin and direction, direction not zero,
/// maxDistance >= 0 (may be infinite: to the edge of the tree).
/// Returns nothing for a miss.
std::optional<RayHit> castRay(const World& world, const Vec3& origin, const Vec3& direction,
                              float maxDistance, RayFaces faces = RayFaces::Front);

/// One ray of a batch (castRays): origin and direction as castRay's, metres.
struct Ray {
  Vec3 origin = Vec3::Zero();
  Vec3 direction = Vec3::UnitX();
  float maxDistance = 0;
};

/// castRay for each of `rays`, writing hitsOut[i] for rays[i] (empty on a
/// miss). For a game's AI sensing or a renderer's probes: no allocation, no
/// per-call setup beyond castRay's; rays near each other in the span share
/// the tree's hot nodes in cache, so order them by origin when you can. Split
/// the span across threads for more: the calls share nothing.
/// Preconditions: hitsOut.size() >= rays.size(); each ray as castRay's.
/// Cost: the sum of the rays' castRay costs.
void castRays(const World& world, std::span<const Ray> rays,
              std::span<std::optional<RayHit>> hitsOut, RayFaces faces = RayFaces::Front);

/// Per-thread scratch of the ellipsoid and point queries: the tree query's
/// leaves and stamps and the candidate list. Reusable across worlds and
/// queries; grows to the largest query, never shrinks.
struct QueryScratch {
  SweepScratch sweep;
  std::vector<std::uint32_t> triangles;
  std::vector<CandidateTriangle> boxed;
};

/// Where an ellipsoid cast first touched the level.
struct EllipsoidHit {
  /// The fraction of the path from `from` to `to` at first contact, [0, 1]:
  /// the centre there is from + fraction * (to - from).
  float fraction = 0;
  /// The contact point on the triangle, metres.
  Vec3 point = Vec3::Zero();
  /// Unit normal at the contact, pointing from the contact point towards the
  /// ellipsoid's centre (the face normal on a face; on an edge or corner, the
  /// ellipsoid's surface normal there).
  Vec3 normal = Vec3::Zero();
  /// The triangle touched, and its surface id, as in RayHit.
  std::uint32_t triangle = 0;
  std::uint32_t surface = 0;
};

/// The ellipsoid with `radii` (axis-aligned: rxz along X and Z, ry along Y)
/// swept from centre `from` to centre `to` (metres), without sliding: the
/// first contact with a triangle's face, edge or corner, exactly (the
/// movement step's exact sweep, CollisionMethod::ExactSweep, in double
/// precision), or nothing. Triangles are one-sided as in the step: a
/// triangle whose plane the centre starts behind is ignored. An ellipsoid
/// that starts overlapping a triangle reports fraction 0 on it when the path
/// leads deeper, and passes out of it when the path leads away (test the
/// start with overlapsEllipsoid). A zero-length path meets nothing.
///
/// Cost: the tree query of the swept volume (collectCandidateTriangles: every
/// leaf along the whole path) and the exact test of each candidate whose box
/// meets the volume's; a few microseconds for a body-sized path. Allocates
/// only when `scratch` must grow. Preconditions: finite points, radii > 0.
/// Returns nothing for a miss.
std::optional<EllipsoidHit> castEllipsoid(const World& world, const Vec3& from, const Vec3& to,
                                          EllipsoidRadii radii, QueryScratch& scratch);
/// castEllipsoid with this thread's runtime-owned scratch.
std::optional<EllipsoidHit> castEllipsoid(const World& world, const Vec3& from, const Vec3& to,
                                          EllipsoidRadii radii);

/// Whether the ellipsoid with `radii` centred at `centre` (metres)
/// intersects any triangle of the level, either side (touching counts,
/// within 1e-6 relative rounding). When `trianglesOut` is given it is
/// cleared and receives every triangle the ellipsoid intersects, in the
/// tree's order; otherwise the test stops at the first.
///
/// Cost: one box query of the ellipsoid's bounding box
/// (collectBoxCandidates) and a closest-point test of each candidate, in
/// double precision. Allocates only when `scratch` or `trianglesOut` must
/// grow. Preconditions: finite centre, radii > 0. Returns false in free
/// space.
bool overlapsEllipsoid(const World& world, const Vec3& centre, EllipsoidRadii radii,
                       QueryScratch& scratch, std::vector<std::uint32_t>* trianglesOut = nullptr);
/// overlapsEllipsoid with this thread's runtime-owned scratch.
bool overlapsEllipsoid(const World& world, const Vec3& centre, EllipsoidRadii radii,
                       std::vector<std::uint32_t>* trianglesOut = nullptr);

/// The level's point nearest a query point.
struct ClosestPoint {
  /// Metres from the query point to `point`.
  float distance = 0;
  /// The nearest point of the level, metres.
  Vec3 point = Vec3::Zero();
  /// The triangle's unit face normal (whichever side the query point is).
  Vec3 normal = Vec3::Zero();
  /// The nearest triangle, and its surface id, as in RayHit.
  std::uint32_t triangle = 0;
  std::uint32_t surface = 0;
};

/// The point of the level (either side of any triangle) nearest `point`, if
/// one is within `maxDistance` metres (inclusive); nothing otherwise. At
/// equal distances (a shared edge or corner) one of the triangles is
/// reported.
///
/// Cost: one box query of the cube of half-size maxDistance around `point`
/// (collectBoxCandidates) and a closest-point test of each candidate: keep
/// maxDistance to what you need (a few metres), since a distance the size of
/// the level tests every triangle. Allocates only when `scratch` must grow.
/// Preconditions: finite point, 0 <= maxDistance <= 2 * kMaxCoordinate.
/// Returns nothing when no triangle is within maxDistance.
std::optional<ClosestPoint> closestPoint(const World& world, const Vec3& point, float maxDistance,
                                         QueryScratch& scratch);
/// closestPoint with this thread's runtime-owned scratch.
std::optional<ClosestPoint> closestPoint(const World& world, const Vec3& point, float maxDistance);

}  // namespace bspf
