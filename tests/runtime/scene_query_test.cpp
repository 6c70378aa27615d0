// SPDX-License-Identifier: MIT
// The scene queries (bspf/scene_query.h): each against brute force over every
// triangle of the samples, a deep random soup and the shared levels, and the
// behaviours a game relies on, in a room.
#include <bspc/compile.h>
#include <bspf/scene_query.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <iostream>
#include <limits>
#include <random>
#include <thread>

#include "narrow_phase.h"
#include "support/test_support.h"

using bspf::EllipsoidRadii;
using bspf::RayFaces;
using bspf::Vec3;
using V = Eigen::Vector3d;

namespace {

constexpr float kInfinity = std::numeric_limits<float>::infinity();

void corners(const bspf::World& world, std::uint32_t t, V& a, V& b, V& c) {
  const auto& tri = world.triangles()[t];
  a = bspf::toVec3(world.vertices()[tri.v0()]).cast<double>();
  b = bspf::toVec3(world.vertices()[tri.v1()]).cast<double>();
  c = bspf::toVec3(world.vertices()[tri.v2()]).cast<double>();
}

// ---- Rays: brute force in double over every triangle ----

// The ray's crossing of each triangle's plane, from a side `faces` allows,
// with how far the crossing point lies outside the triangle (0 inside) and
// how far inside it is from the nearest edge (0 outside).
struct Crossing {
  double distance;
  double outside, inset;  // metres
  std::uint32_t triangle;
};

std::vector<Crossing> bruteCrossings(const bspf::World& world, const V& origin, const V& direction,
                                     double maxDistance, RayFaces faces) {
  std::vector<Crossing> out;
  for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
    V a, b, c;
    corners(world, t, a, b, c);
    const V n = (b - a).cross(c - a).normalized();
    const double approach = n.dot(direction);
    const double startSide = n.dot(origin - a);
    const bool front = startSide >= 0 && approach < 0, back = startSide <= 0 && approach > 0;
    if (!(faces == RayFaces::Front ? front : faces == RayFaces::Back ? back : front || back))
      continue;
    const double distance = -startSide / approach;
    if (distance > maxDistance) continue;
    const V p = origin + distance * direction;
    double inset = kInfinity;
    for (const auto& [e0, e1] : {std::pair{a, b}, {b, c}, {c, a}})
      inset = std::min(inset, n.cross(e1 - e0).normalized().dot(p - e0));
    out.push_back({distance, (bspf::closestPointOnTriangle<V>(p, a, b, c) - p).norm(),
                   std::max(inset, 0.0), t});
  }
  return out;
}

struct Agreement {
  int queries = 0, hits = 0, sameTriangle = 0, withinTolerance = 0;
};

// The runtime's ray against the brute force: a ray crossing a triangle
// farther inside than the tolerance must hit, no farther than that crossing
// and no nearer than any crossing within the tolerance of its triangle; a hit
// must be a crossing of its own triangle at its distance; no crossing near a
// triangle means a miss.
void checkRay(const bspf::World& world, const Vec3& origin, const Vec3& direction,
              float maxDistance, RayFaces faces, Agreement& agreement) {
  const std::optional<bspf::RayHit> hit =
      bspf::castRay(world, origin, direction, maxDistance, faces);
  const V o = origin.cast<double>(), d = direction.cast<double>().normalized();
  const std::vector<Crossing> crossings = bruteCrossings(world, o, d, maxDistance + 1e-3, faces);
  const double tolerance = 1e-5 * (1 + o.cwiseAbs().maxCoeff());
  double nearestInside = kInfinity, nearestNear = kInfinity;
  std::uint32_t nearTriangle = 0;
  for (const Crossing& c : crossings) {
    if (c.inset > tolerance && c.distance <= maxDistance - tolerance)
      nearestInside = std::min(nearestInside, c.distance);
    if (c.outside <= tolerance && c.distance < nearestNear) {
      nearestNear = c.distance;
      nearTriangle = c.triangle;
    }
  }
  ++agreement.queries;
  INFO("ray from " << origin.transpose() << " along " << direction.transpose() << " to "
                   << maxDistance << ", faces " << int(faces) << ": brute force inside at "
                   << nearestInside << ", near at " << nearestNear);
  if (!hit) {
    REQUIRE(!std::isfinite(nearestInside));
    return;
  }
  ++agreement.hits;
  REQUIRE(hit->distance >= 0);
  REQUIRE(hit->distance <= maxDistance);
  REQUIRE(hit->distance <= nearestInside + tolerance);
  REQUIRE(hit->distance >= nearestNear - tolerance);
  REQUIRE((hit->point - (origin + hit->distance * direction.normalized())).norm() <= tolerance);
  REQUIRE(std::abs(hit->normal.norm() - 1) < 1e-5f);
  REQUIRE(hit->normal.dot(direction) < 0);  // faces the ray's origin
  REQUIRE(
      hit->backFace ==
      (faces == RayFaces::Back ||
       (faces == RayFaces::Both &&
        bspf::toVec3(world.trianglePlanes()[hit->triangle].face().normal()).dot(direction) > 0)));
  REQUIRE(hit->surface == 0);
  const auto own = std::find_if(crossings.begin(), crossings.end(),
                                [&](const Crossing& c) { return c.triangle == hit->triangle; });
  REQUIRE(own != crossings.end());
  REQUIRE(std::abs(own->distance - hit->distance) <= tolerance);
  REQUIRE(own->outside <= tolerance);
  if (hit->triangle == nearTriangle)
    ++agreement.sameTriangle;
  else
    ++agreement.withinTolerance;
}

// ---- Random queries over a level ----

struct Probe {
  Vec3 point;      // in the bounds, half of them near a surface
  Vec3 direction;  // unit
  float length;
  float spare[3];  // uniform in [0, 1), for the query's other parameters
};

std::vector<Probe> randomProbes(const bspf::World& world, int count, std::uint32_t seed,
                                float nearSurface) {
  bspf::test::LevelSampler random(world, seed);
  std::vector<Probe> probes;
  for (int i = 0; i < count; ++i) {
    Probe p;
    if (i % 2 == 0) {
      const std::uint32_t t = random.triangle();
      const float u = random.unit(), v = random.unit();
      const Vec3 offset = random.direction() * (nearSurface * random.unit());
      p.point = bspf::test::pointOnTriangle(world, t, u, v) + offset;
    } else {
      p.point = random.inBounds();
    }
    p.direction = random.direction();
    p.length =
        i % 5 == 0 ? kInfinity : (random.high - random.low).norm() * random.unit() * random.unit();
    for (float& spare : p.spare) spare = random.unit();
    probes.push_back(p);
  }
  return probes;
}

Agreement checkRays(const bspf::World& world, int count, std::uint32_t seed) {
  Agreement agreement;
  int k = 0;
  for (const Probe& p : randomProbes(world, count, seed, 2.0f)) {
    const RayFaces faces = k % 4 == 3   ? RayFaces::Back
                           : k % 4 == 2 ? RayFaces::Both
                                        : RayFaces::Front;
    ++k;
    checkRay(world, p.point, p.direction * (1 + float(k % 3)), p.length, faces, agreement);
  }
  // Many rays must hit something, or the test proves little.
  REQUIRE(agreement.hits > agreement.queries / 10);
  return agreement;
}

// The ellipsoid cast against the exact sweep's test of every triangle.
int checkEllipsoidCasts(const bspf::World& world, int count, std::uint32_t seed) {
  bspf::QueryScratch scratch;
  int hits = 0;
  for (const Probe& p : randomProbes(world, count, seed, 3.0f)) {
    const EllipsoidRadii radii{0.1f + p.spare[0], 0.1f + 1.5f * p.spare[1]};
    const Vec3 to = p.point + p.direction * (std::isfinite(p.length) ? 6 * p.spare[2] : 0.f);
    const std::optional<bspf::EllipsoidHit> hit =
        bspf::castEllipsoid(world, p.point, to, radii, scratch);
    const Vec3 toSphere(1 / radii.xz, 1 / radii.y, 1 / radii.xz);
    bspf::detail::Impact best;
    bool penetrating = false;
    for (std::uint32_t t = 0; t < world.triangles().size(); ++t)
      bspf::detail::earliestImpact(bspf::detail::sphereSpaceTriangle(world, t, toSphere),
                                   p.point.cwiseProduct(toSphere),
                                   (to - p.point).cwiseProduct(toSphere), best, penetrating);
    INFO("cast from " << p.point.transpose() << " to " << to.transpose() << " radii " << radii.xz
                      << ", " << radii.y);
    REQUIRE(hit.has_value() == std::isfinite(best.time));
    if (!hit) continue;
    ++hits;
    REQUIRE(hit->fraction == best.time);
    REQUIRE(hit->fraction >= 0);
    REQUIRE(hit->fraction <= 1);
    REQUIRE(std::abs(hit->normal.norm() - 1) < 1e-5f);
    // The contact point is on the reported triangle and on the ellipsoid's
    // surface at the contact.
    V a, b, c;
    corners(world, hit->triangle, a, b, c);
    const V q = hit->point.cast<double>();
    const double scale = 1e-4 * (1 + q.cwiseAbs().maxCoeff());
    REQUIRE((bspf::closestPointOnTriangle<V>(q, a, b, c) - q).norm() < scale);
    // On the ellipsoid's surface, or inside it for a start that overlaps.
    const Vec3 centre = p.point + hit->fraction * (to - p.point);
    const float reach = (hit->point - centre).cwiseProduct(toSphere).norm();
    REQUIRE(reach < 1 + 1e-3f);
    if (hit->fraction > 0) REQUIRE(reach > 1 - 1e-3f);
  }
  return hits;
}

// The overlap test against the closest point of every triangle, in sphere
// space, with the same triangles listed.
int checkOverlaps(const bspf::World& world, int count, std::uint32_t seed) {
  bspf::QueryScratch scratch;
  std::vector<std::uint32_t> listed, expected;
  int overlapping = 0;
  for (const Probe& p : randomProbes(world, count, seed, 1.5f)) {
    const EllipsoidRadii radii{0.1f + p.spare[0], 0.1f + 1.5f * p.spare[1]};
    const V toSphere(1.0 / radii.xz, 1.0 / radii.y, 1.0 / radii.xz);
    const V centre = p.point.cast<double>().cwiseProduct(toSphere);
    expected.clear();
    // Triangles within rounding of touching are left out of the comparison.
    std::vector<std::uint32_t> borderline;
    for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
      V a, b, c;
      corners(world, t, a, b, c);
      const double distance =
          (bspf::closestPointOnTriangle<V>(centre, a.cwiseProduct(toSphere),
                                           b.cwiseProduct(toSphere), c.cwiseProduct(toSphere)) -
           centre)
              .norm();
      if (std::abs(distance - 1) < 1e-5)
        borderline.push_back(t);
      else if (distance < 1)
        expected.push_back(t);
    }
    INFO("ellipsoid at " << p.point.transpose() << " radii " << radii.xz << ", " << radii.y);
    const bool any = bspf::overlapsEllipsoid(world, p.point, radii, scratch, &listed);
    REQUIRE(any == !listed.empty());
    REQUIRE(bspf::overlapsEllipsoid(world, p.point, radii, scratch) == any);
    std::sort(listed.begin(), listed.end());
    std::vector<std::uint32_t> extra;
    std::set_difference(listed.begin(), listed.end(), expected.begin(), expected.end(),
                        std::back_inserter(extra));
    for (const std::uint32_t t : extra)
      REQUIRE(std::binary_search(borderline.begin(), borderline.end(), t));
    REQUIRE(std::includes(listed.begin(), listed.end(), expected.begin(), expected.end()));
    overlapping += any;
  }
  // Both answers must be common.
  REQUIRE(overlapping > count / 10);
  REQUIRE(overlapping < count - count / 10);
  return overlapping;
}

// The closest point against every triangle's.
int checkClosestPoints(const bspf::World& world, int count, std::uint32_t seed) {
  bspf::QueryScratch scratch;
  int found = 0;
  for (const Probe& p : randomProbes(world, count, seed, 4.0f)) {
    const float maxDistance = 5 * p.spare[0];
    const V q = p.point.cast<double>();
    double nearest = kInfinity;
    for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
      V a, b, c;
      corners(world, t, a, b, c);
      nearest = std::min(nearest, (bspf::closestPointOnTriangle<V>(q, a, b, c) - q).norm());
    }
    const std::optional<bspf::ClosestPoint> got =
        bspf::closestPoint(world, p.point, maxDistance, scratch);
    INFO("point " << p.point.transpose() << " within " << maxDistance << ": brute force "
                  << nearest);
    const double tolerance = 1e-5 * (1 + q.cwiseAbs().maxCoeff());
    if (std::abs(nearest - maxDistance) < tolerance) continue;  // on the limit: either
    REQUIRE(got.has_value() == (nearest <= maxDistance));
    if (!got) continue;
    ++found;
    REQUIRE(std::abs(got->distance - nearest) < tolerance);
    REQUIRE(std::abs((got->point - p.point).norm() - got->distance) < tolerance);
    V a, b, c;
    corners(world, got->triangle, a, b, c);
    const V on = got->point.cast<double>();
    REQUIRE((bspf::closestPointOnTriangle<V>(on, a, b, c) - on).norm() < tolerance);
  }
  REQUIRE(found > count / 10);
  return found;
}

void checkAllQueries(const std::string& name, const bspf::World& world, int rays, int others) {
  const Agreement agreement = checkRays(world, rays, 17);
  const int casts = checkEllipsoidCasts(world, others, 18);
  const int overlaps = checkOverlaps(world, others, 19);
  const int closest = checkClosestPoints(world, others, 20);
  // The figures for docs/queries.md (ctest shows them with -V).
  std::cout << "scene queries against brute force, " << name << " (" << world.triangles().size()
            << " triangles): " << agreement.queries << " rays, " << agreement.hits << " hits, "
            << agreement.sameTriangle << " same triangle, " << agreement.withinTolerance
            << " another at the same distance; " << others << " ellipsoid casts (" << casts
            << " hits), overlaps (" << overlaps << " true), closest points (" << closest
            << " found): all agree\n";
}

// A random soup of small triangles in a deep tree: many planes to get wrong.
bspf::test::CompiledMesh soup() {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> coordinate(-8, 8), offset(-2, 2);
  bspc::Mesh mesh;
  for (std::uint32_t i = 0; i < 500; ++i) {
    const V a(coordinate(rng), coordinate(rng), coordinate(rng));
    for (int k = 0; k < 3; ++k)
      mesh.vertices.push_back(a + V(offset(rng), offset(rng), offset(rng)) * (k > 0));
    mesh.triangles.push_back({3 * i, 3 * i + 1, 3 * i + 2});
  }
  return bspf::test::CompiledMesh(mesh);
}

}  // namespace

TEST_CASE("each scene query gives the brute-force answer on the samples and a random soup",
          "[runtime][query][scene-query]") {
  for (const std::string name : {"arena", "box_room", "slopes"}) {
    SECTION(name) { checkAllQueries(name, bspf::test::compileSample(name), 3000, 600); }
    // The small samples are a leaf or a few at the default reach: at 1 m,
    // their faces lie in split planes the walk must see across.
    SECTION(name + ", split at 1 m") {
      checkAllQueries(name + " (1 m reach)", bspf::test::compileSampleWithSplits(name), 3000, 600);
    }
  }
  SECTION("soup") {
    const bspf::test::CompiledMesh level = soup();
    REQUIRE(level.world.treeDepth() > 6);
    checkAllQueries("soup", level.world, 3000, 600);
  }
}

// Not in the Windows build (tests/windows): it compiles OBJ files (assimp).
#ifndef _WIN32
namespace {
bspf::World compileShared(const std::string& name) {
  const std::filesystem::path out = bspf::test::freshTempDir("scene_query") / (name + ".bspf");
  bspc::compileFile(bspf::test::sharedLevelsDir() / (name + ".obj"), out, {});
  const bspf::OpenResult opened = bspf::openWorld(out);
  REQUIRE(opened);
  return *opened.world;
}
}  // namespace

TEST_CASE("each scene query gives the brute-force answer on the shared levels",
          "[runtime][query][scene-query][shared-levels]") {
  BSPF_SKIP_WITHOUT_SHARED_LEVELS();
  for (const std::string& name : bspf::test::sharedLevelNames()) {
    SECTION(name) {
      const bspf::World world = compileShared(name);
      // Brute force costs a pass over every triangle per query: fewer on
      // the large levels, at least a thousand rays each.
      const int budget =
          int(std::clamp<std::size_t>(60'000'000 / world.triangles().size(), 1000, 3000));
      checkAllQueries(name, world, budget, budget / 5);
    }
  }
}
#endif

// ---- Behaviour, in samples/box_room: a 6 x 3 x 6 m room (floor top y = 0,
// ceiling y = 3, inner wall faces at x, z = +-3), walls 0.5 m thick ----

TEST_CASE("a ray from inside a room hits the nearest wall, its front, with its normal",
          "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  const auto hit = bspf::castRay(world, {1, 1.5f, 0.5f}, {1, 0, 0}, 100);
  REQUIRE(hit);
  CHECK(hit->distance == Approx(2).margin(1e-5));
  CHECK(hit->point.isApprox(Vec3(3, 1.5f, 0.5f), 1e-5f));
  CHECK(hit->normal.isApprox(Vec3(-1, 0, 0), 1e-5f));
  CHECK_FALSE(hit->backFace);
  CHECK(hit->surface == 0);
  // Straight down: the floor, 1.5 m below.
  const auto floor = bspf::castRay(world, {1, 1.5f, 0.5f}, {0, -3, 0}, kInfinity);
  REQUIRE(floor);
  CHECK(floor->distance == Approx(1.5).margin(1e-5));
  CHECK(floor->normal.isApprox(Vec3(0, 1, 0), 1e-5f));
  // Diagonally into the corner region: the wall it reaches first.
  const auto diagonal = bspf::castRay(world, {0, 1.5f, 0}, Vec3(2, 0, 1), 100);
  REQUIRE(diagonal);
  CHECK(diagonal->distance == Approx(std::sqrt(5.0f) * 1.5f).margin(1e-4));
  CHECK(diagonal->point.x() == Approx(3).margin(1e-5));
}

TEST_CASE("a ray stops at maxDistance: a wall beyond it is a miss, at it a hit",
          "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  CHECK_FALSE(bspf::castRay(world, {1, 1.5f, 0}, {1, 0, 0}, 1.99f));
  CHECK(bspf::castRay(world, {1, 1.5f, 0}, {1, 0, 0}, 2.0f));
  CHECK_FALSE(bspf::castRay(world, {1, 1.5f, 0}, {1, 0, 0}, 0));
}

TEST_CASE("a ray starting on a wall's face, going into the wall, meets that face at distance 0",
          "[runtime][query][scene-query]") {
  // The room's inner faces lie in the tree's split planes (at a 1 m
  // reach), listed on one side only: the walk must reach them from the
  // other side too.
  const bspf::World world = bspf::test::compileSampleWithSplits("box_room");
  const std::pair<Vec3, Vec3> starts[] = {
      {{3, 1.5f, 0.5f}, {1, 0, 0}},   {{-3, 1.5f, 0.5f}, {-1, 0, 0}}, {{0.5f, 1.5f, 3}, {0, 0, 1}},
      {{0.5f, 1.5f, -3}, {0, 0, -1}}, {{0.5f, 0, 0.5f}, {0, -1, 0}},  {{0.5f, 3, 0.5f}, {0, 1, 0}}};
  for (const auto& [origin, into] : starts) {
    INFO("from " << origin.transpose() << " along " << into.transpose());
    const auto hit = bspf::castRay(world, origin, into, 10);
    REQUIRE(hit);
    CHECK(hit->distance == 0);
    CHECK(hit->normal.isApprox(-into));
  }
}

TEST_CASE("a ray parallel to a face misses it, tilted towards it hits",
          "[runtime][query][scene-query]") {
  const bspf::test::CompiledMesh slab(bspf::test::boxMesh({-5, -1, -5}, {5, 0, 5}));
  // Over the slab's top, along it: nothing to meet.
  CHECK_FALSE(bspf::castRay(slab.world, {-4, 0.25f, 0}, {1, 0, 0}, 100, RayFaces::Both));
  const auto tilted = bspf::castRay(slab.world, {-4, 0.25f, 0}, {1, -0.05f, 0}, 100);
  REQUIRE(tilted);
  CHECK(tilted->distance == Approx(0.25 * std::sqrt(1 + 0.05 * 0.05) / 0.05).margin(1e-3));
}

TEST_CASE("back faces are ignored by default, met with RayFaces::Both or Back",
          "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  // From inside the +x wall's slab, towards the room: the wall's inner face
  // is met from behind 0.25 m away; the front face beyond is the -x wall's.
  const Vec3 origin(3.25f, 1.5f, 0), west(-1, 0, 0);
  const auto front = bspf::castRay(world, origin, west, 100);
  REQUIRE(front);
  CHECK(front->distance == Approx(6.25).margin(1e-5));
  CHECK_FALSE(front->backFace);
  for (const RayFaces faces : {RayFaces::Both, RayFaces::Back}) {
    const auto back = bspf::castRay(world, origin, west, 100, faces);
    REQUIRE(back);
    CHECK(back->distance == Approx(0.25).margin(1e-5));
    CHECK(back->backFace);
    CHECK(back->normal.isApprox(Vec3(1, 0, 0), 1e-5f));  // against the ray
  }
  // From inside the room nothing is met from behind before the walls' far
  // faces: the back of the +x wall's outer face, 2.5 m away.
  const auto fromRoom = bspf::castRay(world, {1, 1.5f, 0}, {1, 0, 0}, 100, RayFaces::Back);
  REQUIRE(fromRoom);
  CHECK(fromRoom->distance == Approx(2.5).margin(1e-5));
}

TEST_CASE("a batch of rays gives each ray's castRay answer", "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("arena");
  std::vector<bspf::Ray> rays;
  for (const Probe& p : randomProbes(world, 500, 3, 2.0f))
    rays.push_back({p.point, p.direction, p.length});
  // Filled with a hit no query gives, so an entry left unwritten shows.
  std::vector<std::optional<bspf::RayHit>> hits(rays.size(), bspf::RayHit{-1.0f});
  bspf::castRays(world, rays, hits, RayFaces::Both);
  int met = 0;
  for (std::size_t i = 0; i < rays.size(); ++i) {
    const auto one = bspf::castRay(world, rays[i].origin, rays[i].direction, rays[i].maxDistance,
                                   RayFaces::Both);
    REQUIRE(one.has_value() == hits[i].has_value());
    if (!one) continue;
    ++met;
    REQUIRE(one->triangle == hits[i]->triangle);
    REQUIRE(one->distance == hits[i]->distance);
  }
  REQUIRE(met > 100);
}

TEST_CASE("an ellipsoid cast stops short of a wall at the fraction where it first touches",
          "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  const EllipsoidRadii radii{0.5f, 0.85f};
  // Towards the +x wall (x = 3) from x = 0 to 6: touches when the centre is
  // at x = 2.5, 2.5 / 6 of the path.
  const auto hit = bspf::castEllipsoid(world, {0, 1.5f, 0}, {6, 1.5f, 0}, radii);
  REQUIRE(hit);
  CHECK(hit->fraction == Approx(2.5 / 6).margin(1e-6));
  CHECK(hit->point.isApprox(Vec3(3, 1.5f, 0), 1e-5f));
  CHECK(hit->normal.isApprox(Vec3(-1, 0, 0), 1e-5f));
  CHECK(world.trianglePlanes()[hit->triangle].face().normal().x() == Approx(-1));
  CHECK(hit->surface == 0);
  // Falling onto the floor: the bottom (centre - 0.85) touches y = 0.
  const auto fall = bspf::castEllipsoid(world, {0, 2, 0}, {0, -2, 0}, radii);
  REQUIRE(fall);
  CHECK(fall->fraction == Approx((2 - 0.85) / 4).margin(1e-6));
  CHECK(fall->normal.isApprox(Vec3(0, 1, 0), 1e-5f));
  // Short of the wall: nothing; and a zero-length path meets nothing.
  CHECK_FALSE(bspf::castEllipsoid(world, {0, 1.5f, 0}, {2.4f, 1.5f, 0}, radii));
  CHECK_FALSE(bspf::castEllipsoid(world, {0, 1.5f, 0}, {0, 1.5f, 0}, radii));
  // Into the corner's edge region diagonally: the touch is on a face or the
  // edge, and the point is on the ellipsoid at that fraction.
  const auto corner = bspf::castEllipsoid(world, {0, 1.5f, 0}, {5, 1.5f, 5}, radii);
  REQUIRE(corner);
  CHECK(corner->fraction == Approx(2.5 / 5).margin(1e-5));
}

TEST_CASE("an ellipsoid overlaps a wall it touches, not one just out of reach, nor free space",
          "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  const EllipsoidRadii radii{0.5f, 0.85f};
  std::vector<std::uint32_t> touched;
  CHECK(bspf::overlapsEllipsoid(world, {2.5f, 1.5f, 0}, radii, &touched));  // touching
  REQUIRE(!touched.empty());
  for (const std::uint32_t t : touched)
    CHECK(world.trianglePlanes()[t].face().normal().x() == Approx(-1));
  CHECK(bspf::overlapsEllipsoid(world, {2.7f, 1.5f, 0}, radii));               // into the wall
  CHECK_FALSE(bspf::overlapsEllipsoid(world, {2.49f, 1.5f, 0}, radii));        // 1 cm off
  CHECK_FALSE(bspf::overlapsEllipsoid(world, {0, 1.5f, 0}, radii, &touched));  // free space
  CHECK(touched.empty());
  // Standing on the floor touches it; 1 cm up does not.
  CHECK(bspf::overlapsEllipsoid(world, {0, 0.85f, 0}, radii));
  CHECK_FALSE(bspf::overlapsEllipsoid(world, {0, 0.86f, 0}, radii));
  // Inside the wall's slab, between its faces, it touches both.
  CHECK(bspf::overlapsEllipsoid(world, {3.25f, 1.5f, 0}, {0.3f, 0.3f}, &touched));
  CHECK(touched.size() >= 2);
}

TEST_CASE("closestPoint finds the nearest surface within maxDistance, nothing beyond",
          "[runtime][query][scene-query]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  // 1 m above the floor, far from the walls and the ceiling (2 m up).
  const Vec3 p(0.5f, 1, -0.5f);
  CHECK_FALSE(bspf::closestPoint(world, p, 0.99f));
  const auto near = bspf::closestPoint(world, p, 1.01f);
  REQUIRE(near);
  CHECK(near->distance == Approx(1).margin(1e-6));
  CHECK(near->point.isApprox(Vec3(0.5f, 0, -0.5f), 1e-6f));
  CHECK(near->normal.isApprox(Vec3(0, 1, 0), 1e-6f));
  CHECK(near->surface == 0);
  // A larger limit gives the same nearest point.
  const auto far = bspf::closestPoint(world, p, 50);
  REQUIRE(far);
  CHECK(far->distance == Approx(1).margin(1e-6));
  // Near a corner of the room: the corner is nearest, on the wall or floor.
  const auto corner = bspf::closestPoint(world, {2.9f, 0.1f, 2.9f}, 1);
  REQUIRE(corner);
  CHECK(corner->distance == Approx(0.1).margin(1e-6));
}

TEST_CASE("the scene queries give the same answers from many threads at once",
          "[runtime][query][scene-query][threads]") {
  const bspf::World world = bspf::test::compileSample("arena");
  const std::vector<Probe> probes = randomProbes(world, 400, 11, 2.0f);
  const EllipsoidRadii radii{0.4f, 0.8f};
  // A fingerprint of every query's answer.
  auto answers = [&](bspf::QueryScratch& scratch) {
    std::vector<float> out;
    for (const Probe& p : probes) {
      const auto ray = bspf::castRay(world, p.point, p.direction, p.length);
      out.push_back(ray ? ray->distance : -1);
      const auto cast = bspf::castEllipsoid(world, p.point, p.point + p.direction, radii, scratch);
      out.push_back(cast ? cast->fraction : -1);
      out.push_back(bspf::overlapsEllipsoid(world, p.point, radii, scratch));
      const auto closest = bspf::closestPoint(world, p.point, 2, scratch);
      out.push_back(closest ? closest->distance : -1);
    }
    return out;
  };
  bspf::QueryScratch mine;
  const std::vector<float> expected = answers(mine);
  std::vector<std::vector<float>> got(4);
  std::vector<std::thread> threads;
  for (auto& result : got)
    threads.emplace_back([&] {
      bspf::QueryScratch scratch;
      result = answers(scratch);
    });
  for (auto& thread : threads) thread.join();
  for (const auto& result : got) REQUIRE(result == expected);
}
