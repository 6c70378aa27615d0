// SPDX-License-Identifier: MIT
#include "stability/scenes.h"

#include <bspc/compile.h>
#include <bspf/world.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <optional>
#include <stdexcept>

#include "oracle.h"
#include "support/mesh_blob.h"

namespace bspf::stability {

namespace {

using V3 = Eigen::Vector3d;

constexpr float kPi = std::numbers::pi_v<float>;
const EllipsoidRadii kRadii{0.45f, 0.85f};
/// A body's centre height when it stands on a floor at y = 0 (with the skin).
constexpr float kStandY = 0.851f;
/// Input force of a walker, m/s^2: reaches 6 m/s within 0.15 s.
constexpr float kWalkForce = 60.0f;

float radians(float degrees) { return degrees * kPi / 180; }

std::string format(const char* pattern, double value) {
  char text[160];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

// A convex solid from its corner points and faces (polygons of point
// indices, any winding): each face fan-triangulated and turned to face away
// from the centroid, so the solid is closed and outward-facing.
void addConvex(bspc::Mesh& mesh, const std::vector<V3>& points,
               const std::vector<std::vector<int>>& faces) {
  V3 centroid = V3::Zero();
  for (const V3& p : points) centroid += p;
  centroid /= double(points.size());
  const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
  mesh.vertices.insert(mesh.vertices.end(), points.begin(), points.end());
  for (const std::vector<int>& face : faces) {
    for (std::size_t k = 1; k + 1 < face.size(); ++k) {
      std::array<std::uint32_t, 3> t{base + face[0], base + face[k], base + face[k + 1]};
      const V3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
      if ((b - a).cross(c - a).dot(a - centroid) < 0) std::swap(t[1], t[2]);
      mesh.triangles.push_back(t);
    }
  }
}

// A parallelepiped: corner `origin` and edge vectors u, v, w.
void addBlock(bspc::Mesh& mesh, const V3& origin, const V3& u, const V3& v, const V3& w) {
  std::vector<V3> points;
  for (int i = 0; i < 8; ++i)
    points.push_back(origin + (i & 1 ? u : V3::Zero()) + (i & 2 ? v : V3::Zero()) +
                     (i & 4 ? w : V3::Zero()));
  addConvex(mesh, points,
            {{0, 1, 3, 2}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 3, 7, 6}, {0, 2, 6, 4}, {1, 3, 7, 5}});
}

void addBox(bspc::Mesh& mesh, const V3& low, const V3& high) {
  const V3 size = high - low;
  addBlock(mesh, low, {size.x(), 0, 0}, {0, size.y(), 0}, {0, 0, size.z()});
}

// A box whose six faces are each split into a grid of cells about `cell`
// metres wide (two triangles a cell): many coplanar triangles with internal
// edges between them.
void addTessellatedBox(bspc::Mesh& mesh, const V3& low, const V3& high, double cell) {
  const V3 centre = (low + high) / 2;
  for (int axis = 0; axis < 3; ++axis) {
    for (const double side : {-1.0, 1.0}) {
      const int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
      const int n1 = std::max(1, int(std::lround((high[a1] - low[a1]) / cell)));
      const int n2 = std::max(1, int(std::lround((high[a2] - low[a2]) / cell)));
      const auto base = static_cast<std::uint32_t>(mesh.vertices.size());
      for (int i = 0; i <= n1; ++i) {
        for (int j = 0; j <= n2; ++j) {
          V3 p;
          p[axis] = side < 0 ? low[axis] : high[axis];
          p[a1] = low[a1] + (high[a1] - low[a1]) * i / n1;
          p[a2] = low[a2] + (high[a2] - low[a2]) * j / n2;
          mesh.vertices.push_back(p);
        }
      }
      auto index = [&](int i, int j) { return base + std::uint32_t(i * (n2 + 1) + j); };
      for (int i = 0; i < n1; ++i) {
        for (int j = 0; j < n2; ++j) {
          for (auto t :
               {std::array<std::uint32_t, 3>{index(i, j), index(i + 1, j), index(i + 1, j + 1)},
                std::array<std::uint32_t, 3>{index(i, j), index(i + 1, j + 1), index(i, j + 1)}}) {
            const V3 &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]], &c = mesh.vertices[t[2]];
            if ((b - a).cross(c - a).dot(a - centre) < 0) std::swap(t[1], t[2]);
            mesh.triangles.push_back(t);
          }
        }
      }
    }
  }
}

// A vertical wall on the floor: one long face runs from `start` along the
// unit horizontal `along` for `length` metres; the wall's thickness lies on
// the side of unit horizontal `solidSide`.
void addWall(bspc::Mesh& mesh, const V3& start, const V3& along, double length, const V3& solidSide,
             double thickness, double height) {
  addBlock(mesh, start, along * length, {0, height, 0}, solidSide * thickness);
}

Body walker(const Vec3& position, const Vec3& velocity = Vec3::Zero(), float maxSpeed = 6) {
  Body b;
  b.position = position;
  b.velocity = velocity;
  b.radii = kRadii;
  b.settings.maxHorizontalSpeed = maxSpeed;
  return b;
}

Vec3 horizontal(float x, float z) { return Vec3(x, 0, z).normalized(); }

// One constant force per body.
std::function<Vec3(std::size_t, int)> constantForces(std::vector<Vec3> forces) {
  return [forces = std::move(forces)](std::size_t body, int) { return forces[body]; };
}

// Largest distance between the run and the reference run, metres, after
// moving the reference by `offset` (in double: a level far from the origin
// is compared with the same level at the origin).
double maxDeviation(const Trajectory& run, const Trajectory& reference,
                    const V3& offset = V3::Zero()) {
  double worst = 0;
  for (std::size_t f = 0; f < run.size() && f < reference.size(); ++f)
    for (std::size_t b = 0; b < run[f].size(); ++b)
      worst = std::max(
          worst, (run[f][b].cast<double>() - (reference[f][b].cast<double>() + offset)).norm());
  return worst;
}

// A goal met when the run stays within `tolerance` metres of the reference.
std::function<GoalResult(const Trajectory&, const Trajectory*)> followsReference(
    double tolerance, const std::string& what, V3 offset = V3::Zero()) {
  return [=](const Trajectory& run, const Trajectory* reference) {
    const double deviation = maxDeviation(run, *reference, offset);
    return GoalResult{deviation <= tolerance,
                      format(("max deviation from " + what + " %.3f m").c_str(), deviation),
                      {deviation}};
  };
}

bspc::Mesh floorSlab(double half = 30) {
  bspc::Mesh m;
  addBox(m, {-half, -1, -half}, {half, 0, half});
  return m;
}

// Jitter (CaseResult::jitter) of one body over the frames [first, end).
double lineFitResidual(const Trajectory& run, std::size_t body, std::size_t first) {
  const std::size_t n = run.size() - first;
  if (n < 3) return 0;
  V3 meanP = V3::Zero();
  double meanT = 0;
  for (std::size_t f = first; f < run.size(); ++f) {
    meanP += run[f][body].cast<double>();
    meanT += double(f);
  }
  meanP /= double(n);
  meanT /= double(n);
  V3 covariance = V3::Zero();
  double variance = 0;
  for (std::size_t f = first; f < run.size(); ++f) {
    covariance += (double(f) - meanT) * (run[f][body].cast<double>() - meanP);
    variance += (double(f) - meanT) * (double(f) - meanT);
  }
  const V3 slope = covariance / variance;
  double worst = 0;
  for (std::size_t f = first; f < run.size(); ++f)
    worst = std::max(worst,
                     (run[f][body].cast<double>() - (meanP + slope * (double(f) - meanT))).norm());
  return worst;
}

Scene thinWall() {
  Scene s;
  s.name = "thin wall (5 cm) hit at 120 m/s";
  s.goal = "no centre ever reaches the wall (x < 5)";
  addBox(s.level, {-20, -1, -250}, {20, 0, 250});
  addBox(s.level, {5, 0, -200}, {5.05, 4, 200});
  std::vector<Vec3> forces;
  int k = 0;
  for (const float degrees : {0.0f, 15.0f, 30.0f, 45.0f, -30.0f, 60.0f}) {
    const Vec3 direction(std::cos(radians(degrees)), 0, std::sin(radians(degrees)));
    s.bodies.push_back(walker({0, kStandY, -10.0f + 4.0f * float(k++)}, direction * 120, 120));
    forces.push_back(direction * 1200.0f);
  }
  s.force = constantForces(forces);
  s.frames = 60;
  s.checkGoal = [](const Trajectory& run, const Trajectory*) {
    float furthest = -1e30f;
    for (const auto& frame : run)
      for (const Vec3& p : frame) furthest = std::max(furthest, p.x());
    return GoalResult{
        furthest < 5, format("furthest centre x %.3f (wall face at 5)", furthest), {furthest}};
  };
  return s;
}

Scene crease(float degrees) {
  Scene s;
  s.name = format("acute crease, %.0f degrees, walked into", degrees);
  s.goal = "ends wedged at the tip (within 5 cm of the deepest clear point) and settles";
  s.level = floorSlab();
  const double half = radians(degrees) / 2;
  const double c = std::cos(half), sn = std::sin(half);
  // The crease opens towards -x with its tip on the y axis; each wall's inner
  // face runs from just beyond the tip along the crease.
  for (const double side : {1.0, -1.0}) {
    const V3 along(-c, 0, side * sn);
    const V3 solid(sn, 0, side * c);
    addWall(s.level, -along * 0.5, along, 14, solid, 0.3, 3);
  }
  const float tipDistance = kRadii.xz / float(sn);
  s.bodies.push_back(walker({-tipDistance - 6, kStandY, 0}));
  s.force = constantForces({horizontal(1, 0.1f) * kWalkForce});
  s.frames = 300;
  s.checkGoal = [tipDistance](const Trajectory& run, const Trajectory*) {
    const float gap = -run.back()[0].x() - tipDistance;
    const double jitter = lineFitResidual(run, 0, run.size() - 30);
    return GoalResult{gap < 0.05f && jitter < 0.01,
                      format("ends %.3f m short of the deepest clear point", gap) +
                          format(", jitter %.4f m", jitter),
                      {gap, jitter}};
  };
  return s;
}

Scene ghostCorners() {
  Scene s;
  s.name = "outer corners and edges passed closely (ghost collisions)";
  s.goal = "passes as if the obstacle were not there (within 1 cm of the open-floor run)";
  s.level = floorSlab();
  s.referenceLevel = floorSlab();
  std::vector<Vec3> forces;
  // Pillars: each body walks diagonally past a corner at 1.1, 1.25 and 1.4
  // times its radius: clear of the rounded corner, inside the squared one.
  const Vec3 direction = horizontal(1, 1);
  const Vec3 away = horizontal(1, -1);
  float z = -20;
  for (const float clearance : {1.1f, 1.25f, 1.4f}) {
    addBox(s.level, {0, 0, z}, {1, 3, z + 1});
    const Vec3 corner(1, kStandY, z);
    s.bodies.push_back(
        walker(corner + away * (clearance * kRadii.xz) - direction * 4, direction * 6));
    forces.push_back(direction * kWalkForce);
    z += 8;
  }
  // Curbs 0.3 m high: bodies walk along them 0.40 and 0.44 m from the side.
  // The ellipsoid is only 0.343 m wide at the curb's top: it clears the edge.
  z = 6;
  for (const float gap : {0.40f, 0.44f}) {
    addBox(s.level, {-10, 0, z}, {10, 0.3, z + 1});
    s.bodies.push_back(walker({-8, kStandY, z - gap}, {6, 0, 0}));
    forces.push_back({kWalkForce, 0, 0});
    z += 6;
  }
  s.force = constantForces(forces);
  s.frames = 120;
  s.checkGoal = followsReference(0.01, "the open-floor run");
  return s;
}

// Bodies for the seam scenes: one slides along the wall at x = 5 (pushing
// into it at 27 degrees), one walks diagonally across the floor.
void addSeamWalkers(Scene& s) {
  s.bodies.push_back(walker({3, kStandY, -8}));
  s.bodies.push_back(walker({-8, kStandY, -8}));
  s.force = constantForces({horizontal(1, 2) * kWalkForce, horizontal(1, 0.7f) * kWalkForce});
  s.frames = 100;  // both stay on the 20 m floor
}

Scene tessellatedSeams() {
  Scene s;
  s.name = "seams between coplanar triangles: floor and wall in 0.5 m cells";
  s.goal = "slides as on untessellated faces (within 1 cm of that run)";
  addTessellatedBox(s.level, {-10, -1, -10}, {10, 0, 10}, 0.5);
  addTessellatedBox(s.level, {5, 0, -10}, {5.5, 3, 10}, 0.5);
  bspc::Mesh plain;
  addBox(plain, {-10, -1, -10}, {10, 0, 10});
  addBox(plain, {5, 0, -10}, {5.5, 3, 10});
  s.referenceLevel = plain;
  addSeamWalkers(s);
  s.checkGoal = followsReference(0.01, "the untessellated run");
  return s;
}

Scene abuttingSlabs() {
  Scene s;
  s.name = "seams between abutting solids: floor and wall of 2 m blocks";
  s.goal = "slides as on one solid (within 1 cm of that run)";
  for (int k = 0; k < 10; ++k) {
    addBox(s.level, {-10.0 + 2 * k, -1, -10}, {-8.0 + 2 * k, 0, 10});
    addBox(s.level, {5, 0, -10.0 + 2 * k}, {5.5, 3, -8.0 + 2 * k});
  }
  bspc::Mesh plain;
  addBox(plain, {-10, -1, -10}, {10, 0, 10});
  addBox(plain, {5, 0, -10}, {5.5, 3, 10});
  s.referenceLevel = plain;
  addSeamWalkers(s);
  s.checkGoal = followsReference(0.01, "the one-solid run");
  return s;
}

// A floor whose far half is 1 cm higher (two abutting slabs: the raised
// one's side shows a 1 cm lip); one body walks straight over the lip, one
// crosses it at 30 degrees.
Scene lip() {
  Scene s;
  s.name = "a 1 cm lip between abutting floor slabs, walked over";
  s.goal = "keeps at least 95% of the path it walks on a flat floor";
  addBox(s.level, {-20, -1, -10}, {0, 0, 10});
  addBox(s.level, {0, -1, -10}, {20, 0.01, 10});
  s.referenceLevel = floorSlab();
  s.bodies.push_back(walker({-4, kStandY, -3}));
  s.bodies.push_back(walker({-4, kStandY, 3}));
  s.force = constantForces({horizontal(1, 0) * kWalkForce, horizontal(1, 0.577f) * kWalkForce});
  s.frames = 120;
  s.checkGoal = [](const Trajectory& run, const Trajectory* reference) {
    // The worst body's horizontal path as a fraction of its flat-floor one.
    double kept = 1;
    for (std::size_t b = 0; b < run.front().size(); ++b) {
      auto path = [&](const Trajectory& t) {
        const Vec3 d = t.back()[b] - t.front()[b];
        return std::hypot(double(d.x()), double(d.z()));
      };
      kept = std::min(kept, path(run) / path(*reference));
    }
    return GoalResult{
        kept >= 0.95, format("keeps %.0f%% of its flat-floor path", 100 * kept), {kept}};
  };
  return s;
}

// A ramp rising along +x from x = 0 at `degrees` to a 3 m high platform; one
// body walks up it, one is set down on it (no input). `stepHeight` > 0: with
// the step-up mitigation, which must not climb a steep slope either.
Scene slope(float degrees, float stepHeight = 0) {
  Scene s;
  const bool walkable = degrees <= 45;
  s.name = format("slope at %.0f degrees (walkable limit 45)", degrees);
  if (stepHeight > 0) s.name += format(", step-up %.2f m (mitigation)", stepHeight);
  s.goal = walkable ? "walks up onto the platform; a body set on the slope stays (< 1 cm)"
                    : "cannot walk up (rises < 0.3 m); a body set on the slope slides down";
  s.level = floorSlab();
  const double height = 3, length = height / std::tan(radians(degrees));
  std::vector<V3> wedge;
  for (const double z : {-6.0, 6.0})
    for (const V3& p : {V3(0, 0, z), V3(length, 0, z), V3(length, height, z)}) wedge.push_back(p);
  addConvex(s.level, wedge, {{0, 1, 2}, {3, 4, 5}, {0, 1, 4, 3}, {1, 2, 5, 4}, {0, 2, 5, 3}});
  addBox(s.level, {length, 0, -6}, {length + 30, height, 6});
  s.bodies.push_back(walker({-3, kStandY, -2}));
  // Set down 1 cm off the slope, half-way up.
  const Vec3 normal(-std::sin(radians(degrees)), std::cos(radians(degrees)), 0);
  const float reach = effectiveRadius(normal, kRadii);
  s.bodies.push_back(
      walker(Vec3(float(length / 2), float(height / 2), 2) + normal * (reach + 0.01f)));
  for (Body& b : s.bodies) b.settings.maxStepHeight = stepHeight;
  s.force = constantForces({Vec3(kWalkForce, 0, 0), Vec3::Zero()});
  s.frames = 240;
  s.checkGoal = [walkable, height](const Trajectory& run, const Trajectory*) {
    float highest = -1e30f;
    for (const auto& frame : run) highest = std::max(highest, frame[0].y());
    const float rise = highest - kStandY;
    if (walkable) {
      // Standing still from frame 30 on (after it settled on the slope).
      const float moved = (run.back()[1] - run[30][1]).norm();
      return GoalResult{rise > float(height) - 0.02f && moved < 0.01f,
                        format("walker rises %.2f m", rise) + format(" of %.0f", height) +
                            format(", set-down body moves %.4f m", moved),
                        {rise, moved}};
    }
    const float drop = run[0][1].y() - run.back()[1].y();
    return GoalResult{
        rise < 0.3f && drop > 0.5f,
        format("walker rises %.2f m", rise) + format(", set-down body drops %.2f m", drop),
        {rise, drop}};
  };
  return s;
}

// `stepHeight` > 0: with the step-up mitigation (MovementSettings::maxStepHeight).
Scene stairs(float riser, float stepHeight = 0) {
  Scene s;
  s.name = format("stairs, %.2f m risers", riser);
  if (stepHeight > 0) s.name += format(", step-up %.2f m (mitigation)", stepHeight);
  s.goal = "walks to the top of 8 steps";
  s.level = floorSlab();
  constexpr int kSteps = 8;
  constexpr double kTread = 0.35;
  for (int k = 0; k < kSteps; ++k)
    addBox(s.level, {k * kTread, 0, -2}, {kSteps * kTread + 30, (k + 1) * riser, 2});
  s.bodies.push_back(walker({-2, kStandY, 0}));
  s.bodies.back().settings.maxStepHeight = stepHeight;
  s.force = constantForces({Vec3(kWalkForce, 0, 0)});
  s.frames = 180;
  const float top = kSteps * riser;
  s.checkGoal = [top](const Trajectory& run, const Trajectory*) {
    float climbed = 0;
    for (const auto& frame : run) climbed = std::max(climbed, frame[0].y() - kStandY);
    return GoalResult{climbed > top - 0.02f,
                      format("climbs %.2f m", climbed) + format(" of %.2f m", top),
                      {climbed}};
  };
  return s;
}

// A floor with a wall at x = 5 and one at z = 5 (a corner), at `offset`.
bspc::Mesh cornerRoom(const V3& offset) {
  bspc::Mesh m;
  addBox(m, offset + V3(-10, -1, -10), offset + V3(10, 0, 10));
  addBox(m, offset + V3(5, 0, -10), offset + V3(5.5, 3, 10));
  addBox(m, offset + V3(-10, 0, 5), offset + V3(5, 3, 5.5));
  return m;
}

Scene farFromOrigin() {
  Scene s;
  s.name = "a level 10 km from the origin";
  s.goal = "ends where the same scene at the origin ends (within 1 cm)";
  const V3 far(10000, 0, 10000);
  s.level = cornerRoom(far);
  s.referenceLevel = cornerRoom(V3::Zero());
  s.referenceOffset = -far.cast<float>();
  const Vec3 at = far.cast<float>();
  s.bodies = {walker(at + Vec3(3, kStandY, -8)), walker(at + Vec3(-8, kStandY, -8)),
              walker(at + Vec3(0, 2.5f, 0)), walker(at + Vec3(-6, kStandY, 0))};
  s.force = constantForces({horizontal(1, 2) * kWalkForce, horizontal(1, 0.7f) * kWalkForce,
                            Vec3::Zero(), horizontal(1, 1) * kWalkForce});
  s.frames = 240;
  // Along the way positions differ by float rounding: at 10 km a float is
  // 0.98 mm coarse, and each frame's move rounds. Reported, not judged.
  s.checkGoal = [far](const Trajectory& run, const Trajectory* reference) {
    const Trajectory lastRun{run.back()}, lastReference{reference->back()};
    const double end = maxDeviation(lastRun, lastReference, far);
    const double drift = maxDeviation(run, *reference, far);
    return GoalResult{end <= 0.01,
                      format("ends %.4f m from the origin run", end) +
                          format(" (drift on the way %.3f m)", drift),
                      {end, drift}};
  };
  return s;
}

Scene crowdIntoWall() {
  Scene s;
  s.name = "18 bodies pushing each other into a wall";
  s.goal = "the crowd settles against the wall (jitter < 1 cm)";
  s.level = cornerRoom(V3::Zero());
  std::vector<Vec3> forces;
  for (int row = 0; row < 3; ++row)
    for (int k = 0; k < 6; ++k) {
      s.bodies.push_back(walker({5 - 0.451f - 0.92f * float(k), kStandY, -0.92f * float(row)}));
      forces.push_back({kWalkForce, 0, 0});
    }
  s.force = constantForces(forces);
  s.frames = 240;
  s.checkGoal = [](const Trajectory& run, const Trajectory*) {
    double jitter = 0;
    for (std::size_t b = 0; b < run[0].size(); ++b)
      jitter = std::max(jitter, lineFitResidual(run, b, run.size() - 30));
    return GoalResult{jitter < 0.01, format("jitter %.4f m", jitter), {jitter}};
  };
  return s;
}

// A 10 m square slab whose top is a fan of slivers: from one corner to
// points along the two far edges, in clusters 0.2 mm apart (triangles 14 m
// long and 0.2 mm wide at their far end, thinner still towards the corner).
// Alone: abutting blocks around it would add the seam case's ghosts.
bspc::Mesh sliverFloor(bool slivers) {
  bspc::Mesh m;
  if (!slivers) {
    addBox(m, {0, -1, 0}, {10, 0, 10});
    return m;
  }
  std::vector<V3> rim;  // the far edges, from (10, 0) to (10, 10) to (0, 10)
  for (int side = 0; side < 2; ++side)
    for (int cluster = 0; cluster <= 5; ++cluster)
      for (int k = 0; k < (cluster == 5 ? 1 : 5); ++k) {
        const double t = 2.0 * cluster + 2e-4 * k;
        if (side == 1 && t == 0) continue;  // (10, 10) is already there
        rim.push_back(side == 0 ? V3(10, 0, t) : V3(10 - t, 0, 10));
      }
  std::vector<V3> points{V3(0, 0, 0)};
  points.insert(points.end(), rim.begin(), rim.end());
  const std::size_t top = points.size();
  for (std::size_t i = 0; i < top; ++i) points.push_back(points[i] - V3(0, 1, 0));
  // Convex, so addConvex orients it: the top as a fan from the corner, then
  // the bottom and the sides as polygons.
  std::vector<std::vector<int>> faces;
  for (std::size_t i = 1; i + 1 < top; ++i) faces.push_back({0, int(i), int(i + 1)});
  std::vector<int> bottom;
  for (std::size_t i = 0; i < top; ++i) bottom.push_back(int(top + i));
  faces.push_back(bottom);
  for (std::size_t i = 0; i < top; ++i) {
    const int j = int((i + 1) % top);
    faces.push_back({int(i), j, int(top) + j, int(top + i)});
  }
  addConvex(m, points, faces);
  return m;
}

Scene slivers() {
  Scene s;
  s.name = "slivers: a floor of 0.2 mm wide triangles";
  s.goal = "walks and lands as on a plain floor (within 1 cm of that run)";
  s.level = sliverFloor(true);
  s.referenceLevel = sliverFloor(false);
  // Across the fan near its corner, across a cluster near the far edge,
  // along the slivers, and one dropped onto a cluster's far end.
  s.bodies = {walker({0.6f, kStandY, 0.6f}), walker({9.5f, kStandY, 2}),
              walker({8.2f, kStandY, 9.5f}), walker({8, 2.85f, 9.5f})};
  s.force = constantForces({horizontal(1, 1) * kWalkForce, Vec3(-kWalkForce, 0, 0),
                            horizontal(-0.2f, -1) * kWalkForce, Vec3::Zero()});
  s.frames = 90;  // all stay on the 10 m slab
  s.checkGoal = followsReference(0.01, "the plain-floor run");
  return s;
}

Scene packedRoom() {
  Scene s;
  s.name = "100 bodies in a 10 m room";
  s.goal = "all stay in the room; once input stops they settle (jitter < 1 cm)";
  addBox(s.level, {-6, -1, -6}, {6, 0, 6});
  addBox(s.level, {-6, 3, -6}, {6, 3.5, 6});
  addBox(s.level, {-5.5, 0, -6}, {-5, 3, 6});
  addBox(s.level, {5, 0, -6}, {5.5, 3, 6});
  addBox(s.level, {-5, 0, -5.5}, {5, 3, -5});
  addBox(s.level, {-5, 0, 5}, {5, 3, 5.5});
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j)
      s.bodies.push_back(walker({-4.275f + 0.95f * float(i), kStandY, -4.275f + 0.95f * float(j)}));
  constexpr int kWalkFrames = 180;
  s.force = [](std::size_t body, int frame) -> Vec3 {
    if (frame >= kWalkFrames) return Vec3::Zero();
    // A new direction every half second, from a hash of body and period.
    std::uint64_t h =
        (std::uint64_t(body) << 32 | std::uint64_t(frame / 30)) * 0x9e3779b97f4a7c15ull;
    h ^= h >> 29;
    const float angle = float(h % 3600) / 3600 * 2 * kPi;
    return Vec3(std::cos(angle), 0, std::sin(angle)) * kWalkForce;
  };
  s.frames = kWalkFrames + 120;
  s.checkGoal = [](const Trajectory& run, const Trajectory*) {
    const float wallReach = 5 - kRadii.xz + 0.002f;
    int escaped = 0;
    for (const auto& frame : run)
      for (const Vec3& p : frame)
        escaped += std::abs(p.x()) > wallReach || std::abs(p.z()) > wallReach ||
                   p.y() < kRadii.y - 0.01f || p.y() > 3 - kRadii.y + 0.01f;
    double jitter = 0;
    for (std::size_t b = 0; b < run[0].size(); ++b)
      jitter = std::max(jitter, lineFitResidual(run, b, run.size() - 30));
    return GoalResult{escaped == 0 && jitter < 0.01,
                      std::to_string(escaped) + " body-frames out of the room" +
                          format(", jitter %.4f m", jitter),
                      {double(escaped), jitter}};
  };
  return s;
}

struct RunFigures {
  Trajectory trajectory;
  std::vector<double> penetration;
  long long insideSolid = 0, refused = 0, stuck = 0;
};

// Steps the scene's bodies in `world`; with `judge`, measures them against
// it (the same level compiled with every face kept, so the winding-number
// inside test sees closed solids).
RunFigures simulate(const World& world, const Scene& scene, CollisionMethod method,
                    const Vec3& offset, const World* judge) {
  const bool measure = judge != nullptr;
  RunFigures out;
  std::vector<Body> bodies = scene.bodies;
  for (Body& b : bodies) {
    b.settings.method = method;
    b.position += offset;
  }
  std::vector<Vec3> forces(bodies.size());
  std::vector<StepReport> reports(bodies.size());
  StepScratch scratch;
  const std::optional<oracle::LevelTriangles> judged =
      measure ? std::optional<oracle::LevelTriangles>(*judge) : std::nullopt;
  auto positions = [&] {
    std::vector<Vec3> p;
    for (const Body& b : bodies) p.push_back(b.position);
    return p;
  };
  out.trajectory.push_back(positions());
  for (int frame = 0; frame < scene.frames; ++frame) {
    for (std::size_t i = 0; i < bodies.size(); ++i) forces[i] = scene.force(i, frame);
    stepBodies(world, bodies, forces, scene.dt, scratch, reports);
    out.trajectory.push_back(positions());
    const std::vector<Vec3>& before = out.trajectory[out.trajectory.size() - 2];
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      out.refused += reports[i].refused;
      const Vec3 moved = bodies[i].position - before[i];
      out.stuck += forces[i].squaredNorm() > 0 && std::hypot(moved.x(), moved.z()) < 1e-3f;
      if (!measure) continue;
      out.penetration.push_back(oracle::penetration(*judged, bodies[i].position, bodies[i].radii));
      out.insideSolid += oracle::insideClosedMesh(*judge, bodies[i].position);
    }
  }
  return out;
}

}  // namespace

std::vector<Scene> failureScenes() {
  std::vector<Scene> scenes;
  scenes.push_back(thinWall());
  for (const float degrees : {10.0f, 30.0f, 60.0f}) scenes.push_back(crease(degrees));
  scenes.push_back(ghostCorners());
  scenes.push_back(tessellatedSeams());
  scenes.push_back(abuttingSlabs());
  scenes.push_back(lip());
  scenes.push_back(slope(44));
  scenes.push_back(slope(46));
  scenes.push_back(stairs(0.15f));
  scenes.push_back(stairs(0.30f));
  scenes.push_back(slope(44, 0.35f));
  scenes.push_back(slope(46, 0.35f));
  scenes.push_back(stairs(0.15f, 0.35f));
  scenes.push_back(stairs(0.30f, 0.35f));
  scenes.push_back(farFromOrigin());
  scenes.push_back(crowdIntoWall());
  scenes.push_back(slivers());
  scenes.push_back(packedRoom());
  return scenes;
}

CaseResult runScene(const Scene& scene, CollisionMethod method, const Tolerances& tolerances) {
  CaseResult result;
  result.scene = scene.name;
  result.method = method;
  const bench::CompiledLevel level(scene.level, {}, scene.name);
  bspc::CompileSettings keepAll;
  keepAll.dropCoveredFaces = false;
  const bench::CompiledLevel judge(scene.level, keepAll, scene.name);
  RunFigures run = simulate(level.world(), scene, method, Vec3::Zero(), &judge.world());
  result.penetrationMax = *std::max_element(run.penetration.begin(), run.penetration.end());
  result.penetrationP99 = oracle::quantile(run.penetration, 0.99);
  result.insideSolid = run.insideSolid;
  result.refusedMoves = run.refused;
  result.framesStuck = run.stuck;
  for (std::size_t b = 0; b < scene.bodies.size(); ++b)
    result.jitter =
        std::max(result.jitter, lineFitResidual(run.trajectory, b, run.trajectory.size() - 30));
  if (scene.referenceLevel) {
    const bench::CompiledLevel reference(*scene.referenceLevel, {}, scene.name);
    const RunFigures referenceRun =
        simulate(reference.world(), scene, method, scene.referenceOffset, nullptr);
    result.goal = scene.checkGoal(run.trajectory, &referenceRun.trajectory);
  } else {
    result.goal = scene.checkGoal(run.trajectory, nullptr);
  }
  result.safe = result.penetrationMax <= tolerances.penetrationMax &&
                result.insideSolid <= tolerances.insideSolid;
  return result;
}

const char* methodName(CollisionMethod method) {
  return method == CollisionMethod::ExactSweep ? "exact" : "planes";
}

}  // namespace bspf::stability
