// SPDX-License-Identifier: MIT
// The scene queries (bspf/scene_query.h): rays by a front-to-back walk of the
// BSP tree, the ellipsoid cast by the exact sweep's per-triangle test, the
// overlap and closest-point tests by a box query.
#include <bspf/scene_query.h>

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <limits>

#include "narrow_phase.h"

namespace bspf {

namespace {

// The queries' tolerance at a plane of offset `distance`, metres: the tree
// queries' margin (kSweepMarginMetres plus about 4 ulp of the offset).
float planePad(float distance) { return kSweepMarginMetres + std::abs(distance) * 4e-7f; }

// The parameter interval [enter, exit] within [0, maxDistance] over which the
// ray origin + t * direction is inside the box [low, high] padded by
// planePad; false when it never is.
bool clipToBox(const Vec3& origin, const Vec3& direction, Vec3 low, Vec3 high, float maxDistance,
               float& enter, float& exit) {
  padBounds(low, high);
  enter = 0;
  exit = maxDistance;
  for (int axis = 0; axis < 3; ++axis) {
    const float o = origin[axis], d = direction[axis];
    if (d == 0) {
      if (o < low[axis] || o > high[axis]) return false;
      continue;
    }
    float t0 = (low[axis] - o) / d, t1 = (high[axis] - o) / d;
    if (t0 > t1) std::swap(t0, t1);
    enter = std::max(enter, t0);
    exit = std::min(exit, t1);
  }
  return enter <= exit;
}

// The nearest hit found so far by a ray walk: accepted while not beyond
// `limit` (the end of the ray), then only when nearer.
struct RayBest {
  float limit;
  bool found = false;
  float distance = 0;
  std::uint32_t triangle = 0;
  bool backFace = false;
  bool accepts(float t) const { return found ? t < distance : t <= limit; }
  float reach() const { return found ? distance : limit; }
};

// Tests the triangles of `leaf` listed with boxes overlapping the segment
// [first, last] of the ray (padded), keeping the nearest hit in `best`. A
// triangle whose hit lies outside the segment may be skipped: the walk meets
// that hit in its own leaf.
void rayLeaf(const World& world, std::uint32_t leafIndex, const Vec3& origin, const Vec3& direction,
             float first, float last, RayFaces faces, RayBest& best) {
  const schema::Leaf& leaf = world.leaves()[leafIndex];
  const std::span<const std::uint32_t> references = world.leafTriangles();
  const std::span<const schema::Box> bounds = world.leafTriangleBounds();
  const std::span<const schema::TrianglePlanes> planes = world.trianglePlanes();
  const Vec3 a = origin + first * direction, b = origin + last * direction;
  Vec3 low = a.cwiseMin(b), high = a.cwiseMax(b);
  padBounds(low, high);
  const std::uint32_t end = leaf.first() + leaf.count();
  for (std::uint32_t i = leaf.first(); i < end; ++i) {
    if (!boxesOverlap(low, high, toVec3(bounds[i].min()), toVec3(bounds[i].max()))) continue;
    const std::uint32_t t = references[i];
    const schema::TrianglePlanes& tp = planes[t];
    const float startSide = signedDistance(tp.face(), origin);
    const schema::Vec3& n = tp.face().normal();
    const float approach = n.x() * direction.x() + n.y() * direction.y() + n.z() * direction.z();
    // The front is met coming from in front (startSide >= 0) moving back
    // (approach < 0); the back the other way round. Parallel never meets.
    const bool front = startSide >= 0 && approach < 0;
    const bool back = startSide <= 0 && approach > 0;
    if (!(faces == RayFaces::Front ? front : faces == RayFaces::Back ? back : front || back))
      continue;
    const float distance = -startSide / approach;
    if (!best.accepts(distance)) continue;
    const Vec3 point = origin + distance * direction;
    bool inside = true;
    for (int k = 0; k < 3 && inside; ++k) {
      const schema::Plane& edge = *tp.edges()->Get(k);
      inside = signedDistance(edge, point) >= -(1e-6f + std::abs(edge.distance()) * 4e-7f);
    }
    if (!inside) continue;
    best.found = true;
    best.distance = distance;
    best.triangle = t;
    best.backFace = !front;
  }
}

QueryScratch& threadScratch() {
  thread_local QueryScratch scratch;
  return scratch;
}

void triangleCorners(const World& world, std::uint32_t t, Eigen::Vector3d& a, Eigen::Vector3d& b,
                     Eigen::Vector3d& c) {
  const schema::Triangle& tri = world.triangles()[t];
  a = toVec3(world.vertices()[tri.v0()]).cast<double>();
  b = toVec3(world.vertices()[tri.v1()]).cast<double>();
  c = toVec3(world.vertices()[tri.v2()]).cast<double>();
}

}  // namespace

std::optional<RayHit> castRay(const World& world, const Vec3& origin, const Vec3& direction,
                              float maxDistance, RayFaces faces) {
  assert(origin.allFinite() && direction.allFinite() && direction.squaredNorm() > 0);
  assert(maxDistance >= 0);
  const Vec3 unit = direction.normalized();
  // Nothing lies outside the level's bounds: the walk covers the part of the
  // ray inside them, which also makes an infinite ray finite.
  float enter, exit;
  if (!clipToBox(origin, unit, toVec3(*world.blob().bounds_min()),
                 toVec3(*world.blob().bounds_max()), maxDistance, enter, exit))
    return std::nullopt;
  RayBest best{maxDistance};

  // Depth first, near child first; each entry is a subtree and the part
  // [first, last] of the ray inside its cell (padded by planePad at each
  // plane, so a triangle lying in a split plane, listed on one side only, is
  // reached from both). A subtree whose part starts beyond the best hit
  // cannot hold a nearer one: the walk stops there.
  struct Entry {
    std::int32_t ref;
    float first, last;
  };
  std::array<Entry, kMaxTreeDepth + 2> stack;
  std::size_t top = 0;
  stack[top++] = {world.root(), enter, exit};
  const std::span<const schema::Node> nodes = world.nodes();
  while (top > 0) {
    const Entry entry = stack[--top];
    if (entry.first > best.reach()) continue;
    const float last = std::min(entry.last, best.reach());
    if (entry.ref < 0) {
      rayLeaf(world, static_cast<std::uint32_t>(-(entry.ref + 1)), origin, unit, entry.first, last,
              faces, best);
      continue;
    }
    const schema::Node& node = nodes[entry.ref];
    const schema::Plane& split = node.split();
    const float pad = planePad(split.distance());
    const float side = signedDistance(split, origin);
    const schema::Vec3& n = split.normal();
    const float along = n.x() * unit.x() + n.y() * unit.y() + n.z() * unit.z();
    // In the near child's frame: the origin's distance to the plane (>= 0)
    // and the rate the ray moves away from the far side.
    const bool nearIsFront = side >= 0;
    const float height = nearIsFront ? side : -side;
    const float rate = nearIsFront ? along : -along;
    float nearLast = last, farFirst = entry.first, farLast = last;
    if (rate > 0) {
      farLast = std::min(last, (pad - height) / rate);  // leaving the far side's pad
    } else if (rate < 0) {
      nearLast = std::min(last, (height + pad) / -rate);  // past the near side's pad
      farFirst = std::max(entry.first, (height - pad) / -rate);
    } else if (height > pad) {
      farLast = -1;  // parallel, beyond the pad: never reaches the far side
    }
    const std::int32_t nearChild = nearIsFront ? node.front() : node.back();
    const std::int32_t farChild = nearIsFront ? node.back() : node.front();
    if (farFirst <= farLast) stack[top++] = {farChild, farFirst, farLast};
    if (entry.first <= nearLast) stack[top++] = {nearChild, entry.first, nearLast};
  }
  if (!best.found) return std::nullopt;
  const schema::TrianglePlanes& tp = world.trianglePlanes()[best.triangle];
  const Vec3 faceNormal = toVec3(tp.face().normal());
  return RayHit{best.distance,
                origin + best.distance * unit,
                best.backFace ? Vec3(-faceNormal) : faceNormal,
                best.triangle,
                0,
                best.backFace};
}

void castRays(const World& world, std::span<const Ray> rays,
              std::span<std::optional<RayHit>> hitsOut, RayFaces faces) {
  assert(hitsOut.size() >= rays.size());
  for (std::size_t i = 0; i < rays.size(); ++i)
    hitsOut[i] = castRay(world, rays[i].origin, rays[i].direction, rays[i].maxDistance, faces);
}

std::optional<EllipsoidHit> castEllipsoid(const World& world, const Vec3& from, const Vec3& to,
                                          EllipsoidRadii radii, QueryScratch& scratch) {
  assert(from.allFinite() && to.allFinite() && radii.xz > 0 && radii.y > 0);
  collectCandidateTriangles(world, from, to, radii, scratch.sweep, scratch.triangles);
  // In sphere space (the level scaled by 1 / radii) the body is the unit
  // sphere, as in the step's exact sweep.
  const Vec3 toSphere(1 / radii.xz, 1 / radii.y, 1 / radii.xz);
  const Vec3 start = from.cwiseProduct(toSphere);
  const Vec3 move = (to - from).cwiseProduct(toSphere);
  detail::Impact best;
  std::uint32_t bestTriangle = 0;
  bool penetrating = false;
  for (const std::uint32_t t : scratch.triangles) {
    const float before = best.time;
    detail::earliestImpact(detail::sphereSpaceTriangle(world, t, toSphere), start, move, best,
                           penetrating);
    if (best.time < before) bestTriangle = t;
  }
  if (!std::isfinite(best.time)) return std::nullopt;
  // The contact: the triangle's point nearest the centre at first contact
  // (one unit from it, against the sphere-space normal, unless the start
  // overlapped), in double and relative to the centre. Normals scale back by
  // toSphere again.
  using V = Eigen::Vector3d;
  const detail::Triangle tri = detail::sphereSpaceTriangle(world, bestTriangle, toSphere);
  const V centre = start.cast<double>() + double(best.time) * move.cast<double>();
  const V contact = centre + closestPointOnTriangle<V>(V::Zero(), tri.a.cast<double>() - centre,
                                                       tri.b.cast<double>() - centre,
                                                       tri.c.cast<double>() - centre);
  return EllipsoidHit{best.time, contact.cwiseQuotient(toSphere.cast<double>()).cast<float>(),
                      best.normal.cwiseProduct(toSphere).normalized(), bestTriangle, 0};
}

std::optional<EllipsoidHit> castEllipsoid(const World& world, const Vec3& from, const Vec3& to,
                                          EllipsoidRadii radii) {
  return castEllipsoid(world, from, to, radii, threadScratch());
}

bool overlapsEllipsoid(const World& world, const Vec3& centre, EllipsoidRadii radii,
                       QueryScratch& scratch, std::vector<std::uint32_t>* trianglesOut) {
  assert(centre.allFinite() && radii.xz > 0 && radii.y > 0);
  if (trianglesOut) trianglesOut->clear();
  const Vec3 extent(radii.xz, radii.y, radii.xz);
  collectBoxCandidates(world, centre - extent, centre + extent, scratch.sweep, scratch.boxed);
  using V = Eigen::Vector3d;
  const V toSphere(1.0 / radii.xz, 1.0 / radii.y, 1.0 / radii.xz);
  const V p = centre.cast<double>().cwiseProduct(toSphere);
  bool any = false;
  for (const CandidateTriangle& candidate : scratch.boxed) {
    V a, b, c;
    triangleCorners(world, candidate.triangle, a, b, c);
    // Relative to the centre, so the distance keeps its precision far from
    // the origin.
    const V q =
        closestPointOnTriangle<V>(V::Zero(), a.cwiseProduct(toSphere) - p,
                                  b.cwiseProduct(toSphere) - p, c.cwiseProduct(toSphere) - p);
    if (q.squaredNorm() > 1 + 2e-6) continue;
    any = true;
    if (!trianglesOut) return true;
    trianglesOut->push_back(candidate.triangle);
  }
  return any;
}

bool overlapsEllipsoid(const World& world, const Vec3& centre, EllipsoidRadii radii,
                       std::vector<std::uint32_t>* trianglesOut) {
  return overlapsEllipsoid(world, centre, radii, threadScratch(), trianglesOut);
}

std::optional<ClosestPoint> closestPoint(const World& world, const Vec3& point, float maxDistance,
                                         QueryScratch& scratch) {
  assert(point.allFinite() && maxDistance >= 0 && maxDistance <= 2 * kMaxCoordinate);
  const Vec3 reach = Vec3::Constant(maxDistance);
  collectBoxCandidates(world, point - reach, point + reach, scratch.sweep, scratch.boxed);
  using V = Eigen::Vector3d;
  const V p = point.cast<double>();
  double bestSquared = double(maxDistance) * maxDistance;
  std::optional<ClosestPoint> best;
  for (const CandidateTriangle& candidate : scratch.boxed) {
    // The box's nearest point first: most candidates are farther than the
    // best so far.
    const V boxGap =
        (candidate.low.cast<double>() - p).cwiseMax(p - candidate.high.cast<double>()).cwiseMax(0);
    if (boxGap.squaredNorm() > bestSquared) continue;
    V a, b, c;
    triangleCorners(world, candidate.triangle, a, b, c);
    const V q = p + closestPointOnTriangle<V>(V::Zero(), a - p, b - p, c - p);
    const double squared = (q - p).squaredNorm();
    if (squared > bestSquared || (best && squared == bestSquared)) continue;
    bestSquared = squared;
    best = ClosestPoint{float(std::sqrt(squared)), q.cast<float>(),
                        toVec3(world.trianglePlanes()[candidate.triangle].face().normal()),
                        candidate.triangle, 0};
  }
  return best;
}

std::optional<ClosestPoint> closestPoint(const World& world, const Vec3& point, float maxDistance) {
  return closestPoint(world, point, maxDistance, threadScratch());
}

}  // namespace bspf
