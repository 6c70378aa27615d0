// SPDX-License-Identifier: MIT
// bullet_peer.h: a Bullet-based peer of the runtime's movement step, for the
// speed/accuracy sweep (bspf_sweep). Built only when CMake finds Bullet.
//
// The level's triangles go into one btBvhTriangleMeshShape, every vertex
// scaled by (1/rxz, 1/ry, 1/rxz): in that space the body's ellipsoid is the
// unit sphere (btSphereShape(1)). A step uses the runtime's velocity model
// (friction when grounded, input force in xz, horizontal speed cap, gravity),
// then "collide and slide": up to maxIterations convex sweeps of the sphere
// (ClosestConvexResultCallback), each advancing to the hit, backing off
// `skin` metres along the hit normal and projecting the rest of the move onto
// the hit plane; a move still blocked after that is refused (the body stays
// at its last safe position). The velocity model is the runtime's own
// (runtime/src/velocity.h), before and after the slides.
//
// Margins: the sphere's margin is its radius (Bullet models a sphere as a
// point plus margin), so the sweep is exact for it; the mesh's margin is set
// to 0, so triangles are not inflated. Bullet's triangle mesh is two-sided
// (the runtime's triangles are one-sided); hit normals are oriented against
// the motion.
#pragma once

#include <bspf/movement.h>
#include <bspf/world.h>

#include <memory>

namespace bspf::bench {

class BulletPeer {
 public:
  /// Builds the mesh of `world` for bodies of `radii` (every body stepped
  /// must have these radii). The world must outlive nothing: the peer copies
  /// the triangles.
  BulletPeer(const World& world, EllipsoidRadii radii);
  ~BulletPeer();
  BulletPeer(const BulletPeer&) = delete;
  BulletPeer& operator=(const BulletPeer&) = delete;

  /// Advances `body` by `dt` (its settings' frictions, speed cap, gravity,
  /// walkable slope, skin and restitution apply, as in the runtime) with at most
  /// `maxIterations` slides. Fills `report`'s iterations, refused and grounded.
  void step(Body& body, const Vec3& force, float dt, int maxIterations, StepReport& report) const;

  /// Bullet's ray test (btCollisionWorld::rayTest, closest hit, either face)
  /// of the segment `from` -> `to` (metres): the fraction of the segment at
  /// the hit, or -1 for a miss. Run in the peer's scaled space, which keeps
  /// fractions (for the scene-query benchmark, bench/query_bench.cpp).
  float rayFraction(const Vec3& from, const Vec3& to) const;

  /// Bullet's convex cast (convexSweepTest, closest hit) of the body's
  /// ellipsoid from centre `from` to `to` (metres), as the step sweeps it:
  /// the fraction of the path at first contact, or -1 for a miss.
  float castFraction(const Vec3& from, const Vec3& to) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace bspf::bench
