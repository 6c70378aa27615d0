// SPDX-License-Identifier: MIT
// bullet_peer.cpp: see bullet_peer.h.
#include "bullet_peer.h"

#include <btBulletCollisionCommon.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "slide.h"     // runtime/src: SlideResult, Contact
#include "velocity.h"  // runtime/src: the movement step's velocity model

namespace bspf::bench {

namespace {

btVector3 toBt(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
Vec3 fromBt(const btVector3& v) { return {v.x(), v.y(), v.z()}; }

}  // namespace

struct BulletPeer::Impl {
  EllipsoidRadii radii;
  btTriangleMesh mesh{true, false};  // 32-bit indices, 3-component vertices
  std::unique_ptr<btBvhTriangleMeshShape> levelShape;
  btDefaultCollisionConfiguration configuration;
  btCollisionDispatcher dispatcher{&configuration};
  btDbvtBroadphase broadphase;
  std::unique_ptr<btCollisionWorld> collisionWorld;
  btCollisionObject level;
  btSphereShape sphere{1.0f};  // margin = radius: a point plus margin, exact
};

BulletPeer::BulletPeer(const World& world, EllipsoidRadii radii) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.radii = radii;
  const Vec3 toSphere(1 / radii.xz, 1 / radii.y, 1 / radii.xz);
  auto corner = [&](std::uint32_t v) {
    return toBt(toVec3(world.vertices()[v]).cwiseProduct(toSphere));
  };
  m.mesh.preallocateVertices(int(world.vertices().size()));
  for (const schema::Triangle& t : world.triangles())
    m.mesh.addTriangle(corner(t.v0()), corner(t.v1()), corner(t.v2()), false);
  m.levelShape = std::make_unique<btBvhTriangleMeshShape>(&m.mesh, true, true);
  m.levelShape->setMargin(0);  // triangles are not inflated
  m.level.setCollisionShape(m.levelShape.get());
  m.level.setCollisionFlags(btCollisionObject::CF_STATIC_OBJECT);
  m.collisionWorld =
      std::make_unique<btCollisionWorld>(&m.dispatcher, &m.broadphase, &m.configuration);
  m.collisionWorld->addCollisionObject(&m.level);
  m.collisionWorld->updateAabbs();
}

BulletPeer::~BulletPeer() {
  if (impl_ && impl_->collisionWorld) impl_->collisionWorld->removeCollisionObject(&impl_->level);
}

void BulletPeer::step(Body& body, const Vec3& force, float dt, int maxIterations,
                      StepReport& report) const {
  const Impl& m = *impl_;
  report = StepReport{};
  detail::futureVelocity(body, force, dt);
  const Vec3 toSphere(1 / m.radii.xz, 1 / m.radii.y, 1 / m.radii.xz);
  const float walkableY =
      std::cos(body.settings.walkableSlopeDegrees * std::numbers::pi_v<float> / 180.0f);
  btVector3 position = toBt(body.position.cwiseProduct(toSphere));
  btVector3 target = position + toBt((body.velocity * dt).cwiseProduct(toSphere));
  SlideResult slide;  // the contacts, in the runtime's own form
  btTransform from = btTransform::getIdentity(), to = btTransform::getIdentity();
  for (int iteration = 0;; ++iteration) {
    const btVector3 move = target - position;
    if (move.length2() < 1e-12f) break;
    from.setOrigin(position);
    to.setOrigin(target);
    btCollisionWorld::ClosestConvexResultCallback hit(position, target);
    m.collisionWorld->convexSweepTest(&m.sphere, from, to, hit);
    if (!hit.hasHit()) {
      position = target;
      break;
    }
    if (iteration == maxIterations) {  // still blocked: stay at the last safe position
      report.refused = true;
      break;
    }
    btVector3 normal = hit.m_hitNormalWorld.normalized();
    if (normal.dot(move) > 0) normal = -normal;  // two-sided mesh: face the motion
    // Sphere-space normal n to world space: proportional to n / radii.
    const Vec3 worldNormal = fromBt(normal).cwiseProduct(toSphere).normalized();
    // `skin` metres along the world normal is skin / effectiveRadius in sphere space.
    const float skin = body.settings.skin / effectiveRadius(worldNormal, m.radii);
    position = position.lerp(target, hit.m_closestHitFraction) + normal * skin;
    btVector3 rest = target - position;
    rest -= normal * rest.dot(normal);
    target = position + rest;
    ++report.iterations;
    if (slide.contactCount < kMaxReportedContacts)
      // The peer knows no point or triangle of its contacts; only the
      // normals feed the contact response.
      slide.contacts[slide.contactCount++] = {worldNormal, worldNormal.y() >= walkableY, false,
                                              Vec3::Zero(), kBodyContact};
  }
  body.position = fromBt(position).cwiseQuotient(toSphere);
  detail::respondToContacts(body, slide, dt);
  body.grounded = std::any_of(slide.contacts.begin(), slide.contacts.begin() + slide.contactCount,
                              [](const Contact& c) { return c.walkable; });
  report.grounded = body.grounded;
  report.contactCount = slide.contactCount;
  for (int i = 0; i < slide.contactCount; ++i) report.contactNormals[i] = slide.contacts[i].normal;
}

float BulletPeer::rayFraction(const Vec3& from, const Vec3& to) const {
  const Impl& m = *impl_;
  const Vec3 toSphere(1 / m.radii.xz, 1 / m.radii.y, 1 / m.radii.xz);
  const btVector3 start = toBt(from.cwiseProduct(toSphere)), end = toBt(to.cwiseProduct(toSphere));
  btCollisionWorld::ClosestRayResultCallback hit(start, end);
  m.collisionWorld->rayTest(start, end, hit);
  return hit.hasHit() ? hit.m_closestHitFraction : -1.0f;
}

float BulletPeer::castFraction(const Vec3& from, const Vec3& to) const {
  const Impl& m = *impl_;
  const Vec3 toSphere(1 / m.radii.xz, 1 / m.radii.y, 1 / m.radii.xz);
  const btVector3 start = toBt(from.cwiseProduct(toSphere)), end = toBt(to.cwiseProduct(toSphere));
  btTransform startPose = btTransform::getIdentity(), endPose = btTransform::getIdentity();
  startPose.setOrigin(start);
  endPose.setOrigin(end);
  btCollisionWorld::ClosestConvexResultCallback hit(start, end);
  m.collisionWorld->convexSweepTest(&m.sphere, startPose, endPose, hit);
  return hit.hasHit() ? hit.m_closestHitFraction : -1.0f;
}

}  // namespace bspf::bench
