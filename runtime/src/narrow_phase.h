// SPDX-License-Identifier: MIT
// The per-triangle primitives of the two narrow phases (slide.h), exposed
// for the microbenchmarks (bench/micro_bench.cpp). Private to the runtime:
// not installed, not part of the API. The small ones are inline: they run
// once per candidate triangle in the movement step's inner loop.
#pragma once

#include <bspf/geometry.h>
#include <bspf/world.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

namespace bspf::detail {

// ---- CollisionMethod::Planes (planes_slide.cpp; the six planes: workspace.h) ----

/// The side values of the move start -> end against a triangle's stored face
/// plane: the body's extent along the face normal and the signed distances
/// of the start and end centres, metres.
struct SideValues {
  float reach;
  float startSide;
  float endSide;
};

inline SideValues sideValues(const schema::Plane& face, const Vec3& start, const Vec3& end,
                             EllipsoidRadii radii) {
  return {effectiveRadius(face.normal(), radii), signedDistance(face, start),
          signedDistance(face, end)};
}

// Pre-check. The end must be within the offset plane, and the centre must
// start in front of the face (a triangle is one-sided; the back of a
// two-sided surface is its own triangle). Unlike the article's sign test
// (startSide - r) * (endSide - r) < 0, this also catches a body that
// starts within the offset plane, which that test lets pass through.
inline bool passesPreCheck(const SideValues& s) {
  return !(s.endSide >= s.reach || s.startSide < 0);
}

// ---- CollisionMethod::ExactSweep (exact_sweep.cpp), in sphere space ----

struct Impact {
  float time = std::numeric_limits<float>::infinity();  ///< fraction of the move, [0, 1]
  Vec3 normal = Vec3::Zero();  ///< unit, sphere space: from the contact point to the centre
  bool edge = false;           ///< on an edge or a corner of the triangle, not its face
};

struct Triangle {
  Vec3 a, b, c, normal;  // sphere space; normal unit, by the winding
};

// The earliest impact of the unit sphere moving from p along v (t in [0, 1])
// with triangle `tri`, if it comes before `best`; sets `penetrating` when the
// start is already within the unit distance of the triangle (in front of
// it). Why it works in double precision: at its definition.
void earliestImpact(const Triangle& tri, const Vec3& pf, const Vec3& vf, Impact& best,
                    bool& penetrating);

// A sphere-space triangle in double, as both stages below read it: made once
// per candidate (the conversion is exact) rather than once per test.
struct TriangleD {
  Eigen::Vector3d a, b, c, normal;
  /// How far b or c rises off the plane of `normal` through `a`, on the
  /// side the normal faces (the normal is rounded to float, so a large or
  /// thin triangle's corners leave that plane): what the face stage's bound
  /// on its edges allows for. Infinite (no bound) when the triangle seen
  /// along `normal` is wound the other way, which only a degenerate
  /// triangle's rounded normal can do.
  double rise = 0;
  /// The corners again, a coordinate at a time: a, b, c, a, b. Edge k runs
  /// from element k to element k + 1, so the stages' AVX paths load all
  /// three edges' ends with two loads a coordinate.
  double cornerX[5], cornerY[5], cornerZ[5];
  explicit TriangleD(const Triangle& t)
      : a(t.a.cast<double>()),
        b(t.b.cast<double>()),
        c(t.c.cast<double>()),
        normal(t.normal.cast<double>()),
        rise(normal.dot((b - a).cross(c - a)) > 0
                 ? std::max({0.0, normal.dot(b - a), normal.dot(c - a)})
                 : std::numeric_limits<double>::infinity()),
        cornerX{a.x(), b.x(), c.x(), a.x(), b.x()},
        cornerY{a.y(), b.y(), c.y(), a.y(), b.y()},
        cornerZ{a.z(), b.z(), c.z(), a.z(), b.z()} {}
  TriangleD() = default;
};

// A sweep's start point and move in sphere space, in double: what both
// stages below compute with, converted once per scan rather than once per
// candidate.
struct SpherePath {
  Eigen::Vector3d start, move;
  double squaredLength;  ///< |move|^2
  double length;         ///< |move|
  SpherePath(const Vec3& p, const Vec3& v)
      : start(p.cast<double>()),
        move(v.cast<double>()),
        squaredLength(move.squaredNorm()),
        length(std::sqrt(squaredLength)) {}
};

// The distance from a point to a triangle, both in sphere space, as the face
// stage last measured it (a start within reach of the triangle's plane): the
// distance from any point near `from` is at least `distance` less how far
// that point is from `from`, which settles the triangle for most of a body's
// next sweeps without measuring again. Negative: none measured.
struct MeasuredDistance {
  Eigen::Vector3d from;
  double distance = -1;
};

// earliestImpact's first stage: a start behind the triangle (no impact),
// within the unit distance of it (penetration), and a first touch inside the
// face. Returns the time (fraction of the move) before which no edge or
// corner of the triangle can be touched: its plane's, later by the time to
// reach the triangle from where the plane was touched when that point was
// tested and found outside, or, for a start within reach of the plane but
// not of the triangle, the time its distance takes to fall by the gap at
// the rate it falls at the start (the distance is convex along the move, so
// it never falls faster); infinity when no edge or corner can be touched
// within the move or improve on `best`. `measured`
// (optional): the triangle's last measured distance, read and kept up to
// date; the result is the same with or without it.
double faceImpact(const TriangleD& tri, const SpherePath& path, Impact& best, bool& penetrating,
                  MeasuredDistance* measured = nullptr);

// earliestImpact's second stage: the edges and corners.
void edgeImpact(const TriangleD& tri, const SpherePath& path, Impact& best);

/// Whether faceImpact and edgeImpact take their AVX paths on this CPU: the
/// three edges of a triangle in the lanes of one register (where the masks
/// use AVX too, availableMaskPaths). Their operations are the reference's,
/// lane by lane and in the same order, so they give the same results bit
/// for bit (the tests compare them).
bool sweepUsesAvx();
/// faceImpact and edgeImpact a coordinate at a time: the references.
double scalarFaceImpact(const TriangleD& tri, const SpherePath& path, Impact& best,
                        bool& penetrating, MeasuredDistance* measured = nullptr);
void scalarEdgeImpact(const TriangleD& tri, const SpherePath& path, Impact& best);

/// Triangle `t` of `world` scaled by `toSphere` into sphere space, with its
/// unit normal.
Triangle sphereSpaceTriangle(const World& world, std::uint32_t t, const Vec3& toSphere);

}  // namespace bspf::detail
