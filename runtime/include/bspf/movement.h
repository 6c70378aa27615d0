// bspf/movement.h: the per-frame movement and collision step.
//
// Bodies are axis-aligned ellipsoids (one radius in x and z, one in y) that
// move through a compiled level (World) and push each other apart. Units:
// metres, seconds, mass 1 (forces are accelerations, m/s^2). Y is up.
//
// One frame of one body (stepBody):
//   1. future position: friction slows the horizontal velocity (never
//      reversing it), the input force accelerates it in the xz plane, the
//      horizontal speed is capped, gravity pulls along -Y, and the desired
//      end is position + velocity * dt;
//   2. level collision, the method of "Physics in BSP-Trees: Collision
//      Detection" (2003) with its defects fixed (docs/algorithm.md): the
//      candidate triangles come from the BSP leaves the swept ellipsoid
//      touches; each is tested with the side-value pre-check and its six
//      perpendicular planes, offset by the body's effective radius, at the
//      point where the centre crosses the triangle's offset plane; the hit
//      with the lowest facing value moves the end out of it (slide), and the
//      test starts again, up to MovementSettings::maxIterations slides; a
//      move still blocked after that is refused (the body stays put); a
//      grounded body stopped by something steep may step up onto it
//      (MovementSettings::maxStepHeight, off by default);
//   3. contacts update the velocity (slide or bounce) and the ground state.
// stepBodies then pushes overlapping bodies apart, horizontally (grid broad
// phase), each push itself a move against the level, so a push never enters
// a wall.
//
// Thread safety: the World is only read. Scratch is the caller's: use one
// StepScratch per thread; bodies stepped on different threads must differ.
#pragma once

#include <bspf/geometry.h>
#include <bspf/query.h>
#include <bspf/world.h>

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace bspf {

/// How a body collides with the level's triangles. Both use the same leaf
/// traversal and report the same diagnostics.
enum class CollisionMethod {
  /// The article's: side-value pre-check, six perpendicular planes offset by
  /// the body's extent, slide by moving the end out along the normal. Fast;
  /// over-approximates a triangle's edges and corners (ghost contacts).
  Planes,
  /// Exact continuous collision: in the space where the ellipsoid is the unit
  /// sphere, the earliest time of impact against each candidate's face, edges
  /// and corners; the body advances to the contact, keeps `skin` along the
  /// contact normal, and slides the rest of the move along the tangent plane.
  /// A body that starts in penetration is first pushed out.
  ExactSweep,
};

/// How a body moves. The defaults suit a walking character of about 1.7 m.
struct MovementSettings {
  /// Narrow phase against the level. Default: the article's method.
  CollisionMethod method = CollisionMethod::Planes;
  /// Gravity, m/s^2, along -Y. >= 0. Default 9.81.
  float gravity = 9.81f;
  /// Horizontal deceleration from friction while grounded, m/s^2. It brings
  /// the horizontal speed towards 0 and never reverses it. >= 0. Default 20
  /// (a body at 6 m/s stops in 0.3 s).
  float groundFriction = 20.0f;
  /// The same while airborne, m/s^2. >= 0. Default 0.
  float airFriction = 0.0f;
  /// Horizontal speed limit, m/s. > 0. Default 6.
  float maxHorizontalSpeed = 6.0f;
  /// Steepest walkable slope, degrees from horizontal, 0 to 89. A contact
  /// this flat or flatter grounds the body. Default 45.
  float walkableSlopeDegrees = 45.0f;
  /// Slides per step against the level; a move still blocked after this many
  /// is refused. 1 to 32. Default 5, as in the article. Too few refuses moves
  /// in creases and corners (the body sticks); more costs time only there.
  int maxIterations = 5;
  /// Restitution e, 0 to 1: 0 slides along a surface; e > 0 reflects the
  /// velocity's normal component scaled by e and keeps the tangential one.
  /// Default 0.
  float restitution = 0.0f;
  /// Gap, metres, kept between the ellipsoid and a surface it slid against,
  /// so float rounding never starts the next step inside the surface's
  /// offset plane. > 0 and well under the radii. Default 0.001.
  float skin = 0.001f;
  /// Highest ledge, metres, a grounded body steps up onto: when something
  /// steep stops its horizontal move, the move is retried lifted by this much
  /// and set down again, and kept if it lands on walkable ground further on
  /// (stairs). 0 to 2 * radii.y. Default 0: off, as in the article. About
  /// 0.35 suits a 1.7 m character on game stairs (docs/stability.md). Costs
  /// three more slides, only in steps blocked while grounded.
  float maxStepHeight = 0.0f;
};

/// A moving ellipsoid. Position and velocity are the body's state; the step
/// reads and writes them. `grounded` is the ground state after the last step.
struct Body {
  Vec3 position = Vec3::Zero();  ///< centre, metres
  Vec3 velocity = Vec3::Zero();  ///< metres per second
  EllipsoidRadii radii;          ///< metres, both > 0
  MovementSettings settings;
  bool grounded = false;
};

/// The most contact normals a StepReport keeps.
inline constexpr int kMaxReportedContacts = 8;

/// What happened in one step of one body, for diagnostics.
struct StepReport {
  /// Slides against the level (0 when nothing was in the way).
  int iterations = 0;
  /// The move was still blocked after maxIterations slides. Planes: the body
  /// stayed at its start. ExactSweep: it stopped at its last contact point
  /// (already a safe position).
  bool refused = false;
  /// A walkable contact this step.
  bool grounded = false;
  /// Unit normals of the surfaces slid against, in order (level first, then
  /// pushes from other bodies); at most kMaxReportedContacts kept.
  int contactCount = 0;
  std::array<Vec3, kMaxReportedContacts> contactNormals;
  /// Bodies this body was pushed apart from (stepBodies only).
  int bodyContacts = 0;
};

class StepScratch;
namespace detail {
void pushBodiesApart(const World&, std::span<Body>, StepScratch&, std::span<StepReport>);
struct StepWorkspace;  // the narrow phases' working lists, private to the runtime
}  // namespace detail

/// Per-thread scratch for the step. Reusable across worlds and frames; it
/// allocates only while growing. Movable, not copyable.
class StepScratch {
 public:
  StepScratch();
  ~StepScratch();
  StepScratch(StepScratch&&) noexcept;
  StepScratch& operator=(StepScratch&&) noexcept;

  SweepScratch sweep;
  /// The triangles near the body being moved (see NearbyTriangles): kept
  /// from step to step, so a body stepped alone with its own scratch reuses
  /// it over frames; stepBodies keeps one per body.
  NearbyTriangles nearby;

  /// How many triangles the last slide's narrow phase tested: the nearby
  /// triangles whose box overlaps the slide's (diagnostics).
  std::size_t lastSlideCandidates() const;
  /// The narrow phases' working lists. Private to the runtime.
  detail::StepWorkspace& workspace();

 private:
  friend void detail::pushBodiesApart(const World&, std::span<Body>, StepScratch&,
                                      std::span<StepReport>);
  friend void stepBodies(const World&, std::span<Body>, std::span<const Vec3>, float, StepScratch&,
                         std::span<StepReport>);
  std::vector<NearbyTriangles> bodyNearby_;  // parallel to stepBodies' bodies
  std::vector<std::uint64_t> cellKeys_;
  std::vector<std::uint32_t> order_;
  std::unique_ptr<detail::StepWorkspace> workspace_;
};

/// Advances one body by `dt` seconds against the level. `force` is the input
/// acceleration, m/s^2; only its x and z count (input acts in the xz plane).
/// Preconditions (asserted): dt > 0 and finite, radii > 0, settings in range.
/// Never leaves the body inside the level's offset surfaces if it started
/// outside them; a refused move leaves the position unchanged.
void stepBody(const World& world, Body& body, const Vec3& force, float dt, StepScratch& scratch,
              StepReport* report = nullptr);

/// Advances every body by `dt`: each against the level (as stepBody, in
/// order), then overlapping bodies are pushed apart, each by half the
/// overlap (measured along the line between centres) horizontally away from
/// the other; a push is a move against the level, so it never ends inside a
/// wall. Pushes are horizontal so that a crowd never lifts a body (onto a
/// wall's top, say): bodies do not stand on each other's heads. The broad
/// phase is a uniform grid: cost about linear in the number of bodies.
/// `forces` is parallel to `bodies`; `reports` is empty or parallel too.
void stepBodies(const World& world, std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                StepScratch& scratch, std::span<StepReport> reports = {});

}  // namespace bspf
