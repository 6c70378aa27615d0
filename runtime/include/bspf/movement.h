// SPDX-License-Identifier: MIT
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
//      move still blocked after that is made by the exact sweep instead
//      (below), which refuses it only if it cannot place it either; a
//      grounded body stopped by something steep may step up onto it
//      (MovementSettings::maxStepHeight, off by default); a body that was
//      grounded and whose move left walkable ground is set back down onto
//      walkable ground within MovementSettings::maxStepDown below (ground
//      snapping: slopes and stairs going down), unless it moves upward;
//   3. contacts update the velocity (slide or bounce) and the ground state.
// stepBodies then sweeps fast bodies' moves against each other (a body that
// meets another stops there: no body passes through another at any speed;
// BodyGrid), and pushes overlapping bodies apart, horizontally (hashed grid
// broad phase, every push computed from the positions after the level phase,
// at most kMaxBodyPushes pushers per body), each body's summed push (no
// longer than its largest share) made at once where it keeps clear of the
// level, else carried into the body's next move against the level
// (Body::deferredPush), so a push never enters a wall.
//
// Many cores: stepBodies with a ThreadPool (bspf/thread_pool.h) runs both
// phases in parallel; a game with its own job system calls the phases itself
// (stepBodiesAgainstLevel on ranges, BodyGrid::build or its parts,
// pushBodiesApart on ranges, sharing one BodyCaches so that each body keeps its tree query
// whichever thread takes it). Either way the result is bit-identical to one
// thread.
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
  /// contact normal, and slides the rest of the move along the contact's
  /// tangent plane in world space (a step's edge met steep stops it as a wall).
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
  /// is refused (Planes: handed to the exact sweep first). 1 to 32. Default 5, as in the article.
  /// Too few refuses moves in creases and corners (the body sticks); more costs time only there.
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
  /// Ground snapping: the deepest drop, metres, a grounded body is set down
  /// onto walkable ground instead of leaving it. When a body that was
  /// grounded after its last step (Body::grounded) makes a move that nothing
  /// below holds (no walkable contact, and no steep contact facing up, such
  /// as a step edge it is climbing), the step slides it straight down by up
  /// to this much with its narrow phase (so it never passes through
  /// anything) and keeps that slide if it ends on walkable ground: walking
  /// down a walkable slope it keeps its horizontal speed and stays grounded
  /// every frame, and down stairs of risers up to this height it is
  /// grounded every frame. Never when the body moves upward (its vertical
  /// velocity, after this step's gravity, is above 0: walking never gives
  /// that, since a walkable contact zeroes the vertical velocity and a slope
  /// lifts the body through the slide, so it is a jump or a bounce), when
  /// nothing walkable lies within this drop (a ledge higher than it, a gap
  /// wider than the body: the body falls), when the slide down ends on
  /// steep ground only, or when the move was refused. 0 to kMaxBodyRadius;
  /// 0 turns it off. Default 0.35: stairs of game levels and, at 60 frames a
  /// second, a 45-degree slope walked down at up to 21 m/s, for a 1.7 m
  /// character (radii 0.45 and 0.85). Costs one slide down (rarely up to
  /// four: docs/algorithm.md), only in steps of grounded bodies that left
  /// the ground.
  float maxStepDown = 0.35f;
};

/// The smallest and the largest body radius, metres, the step accepts. Below
/// 1 mm a body is smaller than float positions resolve across a level, and
/// the step's unit-sphere space (coordinates divided by the radius) would
/// come near float overflow at the far edge of a level; above 1 km the
/// body's extent squared would.
inline constexpr float kMinBodyRadius = 1e-3f;
inline constexpr float kMaxBodyRadius = 1e3f;
/// The farthest, metres along any axis from the origin, that a body may be,
/// or that its step may carry it (|position| + (|velocity| + (|force| +
/// gravity) * dt) * dt, the bound on the step's desired end). Ten times
/// kMaxCoordinate: a body that fell out of a level keeps falling for about
/// 7 minutes before it reaches it.
inline constexpr float kMaxBodyCoordinate = 1e6f;

/// Why a step left a body as it was (StepReport::invalidInput). The step
/// checks its inputs on every call, in every build: a body with bad values
/// is not moved, rather than spreading NaN to the level phase's results and
/// through the body phase to other bodies.
enum class InvalidInput : std::uint8_t {
  None,      ///< the inputs are valid; the body was stepped
  Position,  ///< a component of the position is NaN or infinite
  Velocity,  ///< a component of the velocity is NaN or infinite
  Force,     ///< a component of the force is NaN or infinite
  TimeStep,  ///< dt is NaN, infinite, zero or negative
  Radii,     ///< a radius is NaN or outside [kMinBodyRadius, kMaxBodyRadius]
  /// A MovementSettings field is NaN, infinite, or outside the range its
  /// comment gives (maxIterations of -1 or 10^9, say), or skin is not
  /// below both radii.
  Settings,
  /// The position, or the end this step could reach, is beyond
  /// kMaxBodyCoordinate.
  OutOfReach,
  /// A component of Body::deferredPush is NaN or infinite.
  DeferredPush,
};

/// A short, stable name ("none", "position", "time step", ...).
const char* toString(InvalidInput invalid);

/// A moving ellipsoid. Position and velocity are the body's state; the step
/// reads and writes them. `grounded` is the ground state after the last step.
/// No triangle (an entry of Body::groundTriangles).
inline constexpr std::uint32_t kNoTriangle = 0xFFFFFFFFu;
/// How many ground triangles a Body remembers from its last step.
inline constexpr int kGroundTriangles = 4;
/// Body::groundTriangles of a body that stood on nothing.
inline constexpr std::array<std::uint32_t, kGroundTriangles> kNoGroundTriangles = {
    kNoTriangle, kNoTriangle, kNoTriangle, kNoTriangle};
/// How many wall triangles a Body remembers from its last step.
inline constexpr int kWallTriangles = 2;
/// Body::wallTriangles of a body that met no wall.
inline constexpr std::array<std::uint32_t, kWallTriangles> kNoWallTriangles = {kNoTriangle,
                                                                               kNoTriangle};

struct Body {
  Vec3 position = Vec3::Zero();  ///< centre, metres
  Vec3 velocity = Vec3::Zero();  ///< metres per second
  EllipsoidRadii radii;          ///< metres, both > 0
  MovementSettings settings;
  bool grounded = false;
  /// Centre, metres, where the body's last step started: stepBody (and
  /// stepBodiesAgainstLevel, stepBodies) sets it to `position` on entry, so
  /// a body moved by hand between steps (a teleport) is not swept. The body
  /// phase sweeps each body from here to `position` against the other
  /// bodies (BodyGrid): a game that builds a BodyGrid from bodies it did not
  /// step should set it to `position` first, or their jump is swept.
  Vec3 lastStepStart = Vec3::Zero();
  /// The walkable triangles (indices into World::triangles()) the body's
  /// last step against the level met, each once, the rest kNoTriangle: its
  /// ground. The step sets them, and the next step uses them: the planes
  /// method tests them first (a walking body meets the ground it stands on
  /// first, found then without a scan of its candidates, whose pre-check
  /// would pass every floor triangle under it), and the exact sweep slides a
  /// body resting on one of them at the skin's gap along it from the start
  /// (one sweep a walking step, where meeting the ground first took two).
  /// Any values are safe: one that is not a triangle in the body's way, or
  /// one the body does not rest on (stale, set by hand, from another level),
  /// costs one test, and a move still ends only where no triangle blocks
  /// it. They may change which of two surfaces a move meets first, or its
  /// end by float rounding, so a game that replays steps should keep them
  /// with the body's state.
  std::array<std::uint32_t, kGroundTriangles> groundTriangles = kNoGroundTriangles;
  /// The triangles too steep to walk whose faces the body's last step
  /// against the level met (walls), each once, the rest kNoTriangle; set by
  /// the exact sweep's steps (a planes step leaves none). The exact sweep's
  /// next step slides a body resting against one of them at
  /// the skin's gap, its move pressing into it, along it from the start, as
  /// it does on its ground (a body walking along a wall: one sweep a step,
  /// where meeting the ground and the wall first took three). The planes
  /// method does not use them: tested first, walls changed which surface it
  /// met first and the crowds' paths (docs/algorithm.md). Safe with any
  /// values, and kept by a game that replays steps, as groundTriangles.
  std::array<std::uint32_t, kWallTriangles> wallTriangles = kNoWallTriangles;
  /// Metres: a push from other bodies (pushBodiesApart) that would have come
  /// near the level, carried into the body's next step, which moves the body
  /// by velocity * dt plus this against the level (so the push slides along
  /// the wall it was pressed into, in the slide the step makes anyway) and
  /// sets it back to zero. Zero for a body no push reached the level with.
  /// Part of the body's state: a game that replays steps keeps it too.
  Vec3 deferredPush = Vec3::Zero();
  /// Metres: the deferredPush the body's last step carried (zero if none;
  /// set by the step, as lastStepStart is). The body phase's sweep allows
  /// for it when it asks whether the body's move was fast (kSweepMinMove): a
  /// push answers bodies the body already overlaps, and pushes were never
  /// swept (counted, they made a pile of 1,024 walkers sweep most of its
  /// bodies, on one thread).
  Vec3 lastStepPush = Vec3::Zero();
};

/// The most contacts a StepReport keeps.
inline constexpr int kMaxReportedContacts = 8;

/// The triangle index and the surface id a StepReport gives a contact with
/// another body (StepReport::contactTriangles, contactSurfaces): no
/// triangle or surface of a World has it.
inline constexpr std::uint32_t kBodyContact = 0xFFFFFFFFu;

/// What happened in one step of one body, for diagnostics.
struct StepReport {
  /// Slides against the level (0 when nothing was in the way).
  int iterations = 0;
  /// The move was still blocked after maxIterations slides, and it stopped
  /// at its last contact point (already a safe position). Planes: a move
  /// the six planes leave blocked is made by the exact sweep from the same
  /// start, with its own maxIterations slides; refused is set only when that
  /// one is still blocked too (iterations counts both).
  bool refused = false;
  /// A walkable contact this step.
  bool grounded = false;
  /// The contacts of this step, in order: the level's met by the body's own
  /// move, then (stepBodies only) one for each body that pushed it, then the
  /// level's met by that push; at most kMaxReportedContacts kept (a full
  /// list keeps the ground contact that decided `grounded`). Entries
  /// [0, contactCount) of the four arrays below describe them.
  int contactCount = 0;
  /// Unit normals, world space, pointing out of the surface met towards the
  /// body: for another body, horizontal, from it towards this one.
  std::array<Vec3, kMaxReportedContacts> contactNormals;
  /// Where the body touched, metres, world space: the point of the body's
  /// surface that touched (where its own normal is -contactNormals[i]),
  /// at the time of the contact (after that slide). It lies within the skin
  /// (MovementSettings::skin) and float rounding of the triangle's plane,
  /// in front of it; for the exact sweep on the triangle (its face, an
  /// edge or a corner), for the planes method over the triangle or, at its
  /// edges and corners (which that method meets as their planes), just
  /// beside it. For another body: the point of this body's surface
  /// towards it, at its position before the push.
  std::array<Vec3, kMaxReportedContacts> contactPoints;
  /// The triangle met, an index into World::triangles(); kBodyContact for
  /// another body.
  std::array<std::uint32_t, kMaxReportedContacts> contactTriangles;
  /// The surface of that triangle (World::triangleSurface; its name:
  /// World::surfaceName), for footstep sounds and decals; kBodyContact for
  /// another body.
  std::array<std::uint32_t, kMaxReportedContacts> contactSurfaces;
  /// Bodies this body was pushed apart from (stepBodies only).
  int bodyContacts = 0;
  /// The body has fallen out of the level: after its move against the level
  /// its top (position.y + radii.y) is below the level's lowest point
  /// (World::boundsMin().y), so nothing of the level can hold it any more.
  /// The step keeps moving it (it falls until kMaxBodyCoordinate, then its
  /// steps are refused as InvalidInput::OutOfReach): a game respawns it.
  /// Set by the level phase (stepBody, stepBodiesAgainstLevel, stepBodies).
  bool belowLevel = false;
  /// The body-against-body sweep cut this step's move short where the body
  /// met another body (stepBodies only; see BodyGrid): the body stopped at
  /// that contact and lost its velocity into the other.
  bool stoppedByBody = false;
  /// Not None when the inputs were invalid (see InvalidInput): the body was
  /// not moved (position, velocity and ground state are as they were, the
  /// other fields are zero), and stepBodies leaves it out of the body phase:
  /// it neither pushes nor is pushed, and no other body sees it.
  InvalidInput invalidInput = InvalidInput::None;
};

class StepScratch;
class BodyGrid;
class BodyCaches;
namespace detail {
struct StepWorkspace;  // the narrow phases' working lists, private to the runtime
struct BodyCache;      // what one body keeps from frame to frame, likewise
/// A body's centre, metres, and its index, for the body phase's sorting
/// along x (BodyGrid); private to the runtime.
struct SortedCentre {
  float x, y, z;
  std::uint32_t body;
};
void pushRange(const World&, const BodyGrid&, std::span<Body>, std::size_t, std::size_t,
               StepScratch&, std::span<StepReport>, std::span<BodyCache>);
}  // namespace detail

/// The most other bodies that push one body in one step: the nearest
/// overlapping ones (ties: lower index first). A body in a dense pile is
/// pushed by these only, so the body phase's work per body stays bounded.
inline constexpr int kMaxBodyPushes = 8;
/// The most other bodies examined as possible pushers of one body in one
/// step (its own grid cell first, those nearest it in index order first;
/// then the neighbouring cells). Only a pile of more than this many bodies
/// within about one body size reaches it.
inline constexpr int kMaxBodyCandidates = 32;

/// The body-against-body sweep (BodyGrid::build) sweeps a body against the
/// others when its move this step, in its own unit-sphere space (each axis
/// over its radius), is longer than this plus the push it carried
/// (Body::lastStepPush, in the same space): 0.5, 22 cm for the default body
/// (13.5 m/s at 60 frames a second). Two slower bodies cannot cross each
/// other's centre in one step (their relative move is at most half their
/// summed extent), so the push alone keeps them apart on the right sides.
inline constexpr float kSweepMinMove = 0.5f;
/// The most passes of the sweep's stop times (a body stopped early can in
/// turn stop one that would have met it later: each pass carries a chain one
/// body further). A chain longer than this within one step (never seen
/// outside a test built for it) keeps the last pass's times, and the
/// remaining overlaps are pushed apart.
inline constexpr int kMaxSweepPasses = 16;
/// A fast body's path is split into pieces of at most one grid cell along
/// each axis, each filed under the cells its box covers. A move of more than
/// this many pieces (about 460 m for the default body: a teleport, not a
/// step) is instead checked against every body: linear in the number of
/// bodies for each such move.
inline constexpr int kMaxSweepPieces = 256;
/// The most fast bodies of one grid cell a body is swept against there: a
/// slow body against the first this many of the cell's fast bodies, a fast
/// one against the next this many after it (cells list bodies in index
/// order). Bounds the sweep's work in a pile of fast bodies; a pile of more
/// than this many fast bodies within about one body size may let some of
/// them pass through each other (the push still parts them).
inline constexpr int kMaxSweepCellBodies = 64;

/// Crowds of at most this many bodies find the sweep's pairs by sorting
/// their swept boxes along x rather than through grid cells: every pair
/// whose boxes meet, which for so few bodies is cheaper than filing paths
/// under cells, and as no cell can then hold more than kMaxSweepCellBodies
/// bodies, finds every pair the cells would (so the stop times are the same
/// for bodies of one shape).
inline constexpr int kSortedSweepBodies = kMaxSweepCellBodies;

/// Crowds of at most this many bodies find each body's possible pushers by
/// sorting the bodies' centres along x rather than through the hashed grid:
/// the same pushers, so the same pushes (a pair is kept only when the grid
/// would have examined it, and the sorting is used only when no body has
/// more than kMaxBodyCandidates others within its grid cells' reach, so the
/// candidate cap cuts nothing). A body with no other body within reach then
/// costs a range check, not 8 cell look-ups.
inline constexpr int kSortedNeighbourBodies = 64;

/// The body-against-body phase for bodies [first, last) of `bodies`: first,
/// a body whose move the grid's sweep cut short (BodyGrid::build) is set
/// back along its move to where it met another body, as a move against the
/// level from its step's start (lastStepStart), and loses the velocity
/// closing on that body (never gaining upward speed from it); then each is
/// pushed apart from the overlapping bodies of `grid` (at most kMaxBodyPushes
/// of them, the nearest): by half of each overlap (measured along the line
/// between centres) plus half its skin, horizontally away from the other,
/// all summed into one push, never longer than the largest of these shares
/// (in a pile the shares from one side would add up to a fling of metres).
/// A push that stays more than a quarter of the skin clear of every
/// triangle's plane near it (the common case: the narrow phase would find
/// nothing) moves the body the whole way now; any other (a body pressed into
/// a wall by a crowd, most often) is not made here but kept in
/// Body::deferredPush, and the body's next step moves it against the level
/// with its own move, in one slide: so a push never enters a wall, and costs
/// no slide of its own (those slides were 6% of a step at 40 m/s on the
/// walkers, oa_dm5). The velocity loses its
/// horizontal closing speed towards each pusher. Pushes are horizontal so
/// that a crowd never lifts a body (onto a wall's top, say): bodies do not
/// stand on each other's heads. Two bodies at the same point, or one right
/// above the other, part along a horizontal direction fixed by their pair
/// of indices. Adds the push's contacts and the number of pushers
/// (StepReport::bodyContacts) to `reports` (empty, or parallel to
/// `bodies`).
/// Every push is computed from the positions `grid` was built from, not from
/// bodies already pushed: the result does not depend on the order or the
/// split of the ranges.
/// Preconditions: `grid` was built from `bodies` (same size and order), and
/// [first, last) lies within them.
/// Cost: a push near the level reads the body's cache in `scratch`, by its
/// index in `bodies` (see stepBodiesAgainstLevel).
/// Thread safety: reads `grid` and writes only bodies[first, last) and
/// reports[first, last): calls on disjoint ranges may run concurrently, each
/// with its own scratch, once `grid` is built.
void pushBodiesApart(const World& world, const BodyGrid& grid, std::span<Body> bodies,
                     std::size_t first, std::size_t last, StepScratch& scratch,
                     std::span<StepReport> reports = {});

/// pushBodiesApart with each body's cache kept in `caches` by its index in
/// `bodies`, as the level phase's overload with BodyCaches keeps it.
/// Preconditions: as pushBodiesApart, and bodies.size() <= caches.size().
/// Thread safety: as pushBodiesApart; the concurrent calls share `caches`.
void pushBodiesApart(const World& world, const BodyGrid& grid, std::span<Body> bodies,
                     std::size_t first, std::size_t last, StepScratch& scratch, BodyCaches& caches,
                     std::span<StepReport> reports = {});

/// The broad phase of the body-against-body phase, and its sweep.
///
/// The sweep, so that no body passes through another at any speed: each
/// body's move this step (from lastStepStart to position, a straight line)
/// is swept against the moves of the bodies near its path, as the two
/// bodies' relative motion over the step (both moving at once, in a common
/// space where the pair's summed radii are 1). The pair's shapes are taken
/// conservatively: each ellipsoid as the sphere of its largest radius in
/// that space (exact for bodies of the same shape; never later than the
/// true contact), with a gap of the pair's mean skin. A pair that meets
/// stops both bodies at the time they meet; a body met by several stops at
/// the earliest; and as a stopped body may in turn be met earlier by others,
/// the stop times are passed over again until none changes (at most
/// kMaxSweepPasses). Only pairs with a fast body are swept (kSweepMinMove):
/// a pair already overlapping at the start of a stretch is stopped only
/// when its relative move would take it through the middle of the other
/// (past half its current distance), so bodies that touch can walk past
/// each other. The sweep runs in build, on the calling thread, in a fixed
/// order: the stop times depend on the bodies only, not on the threads.
/// Its cost is nothing when no body is fast; a fast body's path is filed
/// under the cells it crosses (kMaxSweepPieces, kMaxSweepCellBodies).
///
/// Then a snapshot of the bodies' centres (where the sweep stopped them) and
/// radii in a grid of cells twice as wide as the widest body and
/// twice as tall as the tallest, found through a hash table of the occupied
/// cells. A body overlaps only bodies of its own cell and of the neighbours
/// on the sides of the cell's middle it lies: 8 cells. For at most
/// kSortedNeighbourBodies bodies, the pairs those cells would give are found
/// by sorting the centres along x instead (the order is kept from frame to
/// frame, so sorting again is nearly free), and listed with a margin of
/// twice the widest body's xz radius: until some body has moved further than
/// that radius along an axis since (or a body's xz radius changed), a build
/// tests only the listed pairs. The pairs, and so the pushes, are the
/// cells' in every case. Reusable across frames; it allocates only while
/// growing.
class BodyGrid {
 public:
  /// Snapshots `bodies` (after their move against the level, before any
  /// push). Linear in the number of bodies. Not thread-safe: build it on one
  /// thread, then share it read-only between the pushBodiesApart calls.
  void build(std::span<const Body> bodies);

  /// build() in parts, for a job system's threads (the thread pool's
  /// stepBodies builds the grid so): startPreparing() once, then
  /// prepare() on ranges of the bodies, best by the thread that has just
  /// stepped them against the level (their lines are still in its core's
  /// cache; read by one thread, every other core's bodies crossed over to
  /// it: 183 ns a body against 149 prepared, 1,024 bodies on 2 threads);
  /// then buildPrepared() into each pushing thread's own grid (pushes read
  /// the grid all over: a grid built on one core had every other pull its
  /// lines across, 490 against 437 ns a body on oa_dm4). Gives the grid
  /// build() gives, bit for bit.
  /// startPreparing: makes room for `bodies` bodies' inputs in this grid.
  /// Not thread-safe.
  void startPreparing(std::size_t bodies);
  /// Takes what build() reads of bodies [first, last) of `bodies` (the
  /// whole crowd, after their move against the level) into this grid's
  /// inputs. Precondition: startPreparing(bodies.size()) was called since
  /// the last buildPrepared from this grid, and last <= bodies.size().
  /// Thread safety: calls on disjoint ranges may run concurrently.
  void prepare(std::span<const Body> bodies, std::size_t first, std::size_t last);
  /// Builds this grid from `prepared`'s inputs, once prepare() has covered
  /// every body. Reads no body (other threads may be pushing theirs), and
  /// `prepared` only: several grids may be built from one at once, each on
  /// its own thread (`prepared` may be one of them: its inputs are not
  /// changed).
  void buildPrepared(const BodyGrid& prepared);

  /// Bodies in the last snapshot.
  std::size_t size() const { return entries_.size(); }

  /// How far along its move (0 to 1) the sweep of the last build stopped
  /// body `i`: 1 when it went the whole way. Precondition: i < size().
  float stopTime(std::size_t i) const { return stops_.empty() ? 1.0f : stops_[i].time; }

 private:
  friend void detail::pushRange(const World&, const BodyGrid&, std::span<Body>, std::size_t,
                                std::size_t, StepScratch&, std::span<StepReport>,
                                std::span<detail::BodyCache>);
  /// A body's cell: its packed coordinates, and the halves it lies in
  /// (Place::upperHalf).
  struct CellKey {
    std::uint64_t key;
    std::uint8_t upperHalf;
  };
  /// The cell of centre `p`, in cells 1 / inverseWidth wide and
  /// 1 / inverseHeight tall.
  static CellKey cellKeyOf(const Vec3& p, float inverseWidth, float inverseHeight);
  /// What build reads of a body, and the cell of its position in the cells
  /// of keyedInverseWidth_ and keyedInverseHeight_.
  struct Prepared {
    Vec3 position;
    Vec3 start;  ///< Body::lastStepStart
    EllipsoidRadii radii;
    float skin;  ///< MovementSettings::skin
    bool fast;   ///< movedFast
    CellKey cell;
  };
  /// build, given what it reads of each of `n` bodies (by index i < n:
  /// position(i), start(i), radii(i), skin(i), fast(i); scan(n), their cell
  /// size and whether any is fast; placeEntries(entries), each body's entry
  /// where it ends unless the sweep stops it; keyedFor(inverseWidth,
  /// inverseHeight), whether cellKey(i) is the cell of position(i) in cells
  /// of that size); it reads nothing else of them.
  template <typename Inputs>
  void buildFrom(std::size_t n, const Inputs& inputs);
  struct Entry {
    Vec3 position;
    EllipsoidRadii radii;
    std::uint32_t body;
  };
  struct Cell {
    std::uint64_t key;    ///< packed cell coordinates; kFree when unused
    std::uint32_t first;  ///< its entries: [first, first + count)
    std::uint32_t count;
  };
  /// Where one body is in the snapshot, by body index.
  struct Place {
    std::uint64_t key;       ///< its cell's key
    std::uint32_t entry;     ///< its entry in entries_
    std::uint32_t cellSlot;  ///< its cell's slot in cells_
    std::uint32_t bit;       ///< its cell's bit in occupied_ (when kept)
    /// Bit a set: along axis a (x, y, z) it lies in the upper half of its
    /// cell, so the neighbour that may hold an overlapping body is the one
    /// above, else the one below.
    std::uint8_t upperHalf;
  };
  /// Where the sweep stopped a body: the fraction of its move, and the unit
  /// normal of the contact (from the other body towards it).
  struct Stop {
    float time;
    Vec3 normal;
  };
  /// A body's move for the sweep, and the box of its swept path.
  struct Mover {
    Vec3 start, move, low, high;
    EllipsoidRadii radii;
    float skin;
    bool fast;
  };
  /// Sets stops_ (empty when no body is fast: `anyFast` false), from the
  /// `n` bodies' `inputs` (as buildFrom's).
  template <typename Inputs>
  void sweep(std::size_t n, const Inputs& inputs, bool anyFast);
  /// Fill sweepPairs_ (unsorted, maybe repeated) from movers_: through the
  /// grid cells fast paths cross, or, for kSortedSweepBodies bodies or
  /// fewer, by sorting the movers' boxes along x (or, with few fast ones,
  /// by testing theirs against every other).
  void sweepPairsByCells();
  void sweepPairsBySorting();
  /// The sorting's pairs, by testing each fast body's box against every
  /// other's: for kSortedSweepBodies bodies or fewer, of which at most
  /// kFewFastBodies are fast (with up to 16, the build cost 3 to 17% more
  /// at 40 m/s on fan, oa_dm4 and oa_dm5; with 4, 1 to 2% more there, and 5
  /// to 8% less at 6 m/s: the sorting's order, kept from sweep to sweep,
  /// grows stale while it is not used).
  void sweepPairsOfFewFast();
  static constexpr std::size_t kFewFastBodies = 4;
  /// The time (0 to 1) at which bodies a < b of movers_ first meet, moving
  /// until their current stop times, or above 1 if they never do; sets
  /// `normal` (from b towards a) when they do.
  double meetTime(std::uint32_t a, std::uint32_t b, Vec3& normal) const;

  /// For at most kSortedNeighbourBodies bodies whose entries_ are by body
  /// index: fills nearHead_ and nearLinks_ by sorting the centres along x
  /// (or from listedPairs_, while the bodies stayed near their listed
  /// places), or returns false when the grid must find the pairs instead (a coordinate
  /// or radius that is not finite, or a body with more than
  /// kMaxBodyCandidates others near enough to be in its cells). `width`,
  /// `height`: the cells' size, metres.
  bool findNeighboursBySorting(float width, float height);

  static constexpr std::uint64_t kFree = ~std::uint64_t(0);
  /// The table slot of `key` when a body is in that cell, else of a free slot.
  std::uint32_t find(std::uint64_t key) const;

  float inverseWidth_ = 1, inverseHeight_ = 1;  ///< 1 / cell size, horizontal and vertical
  int shift_ = 60;                              ///< 64 - log2(cells_.size()), for the hash
  std::vector<Cell> cells_;                     ///< open addressing, a power of 2 long
  /// By cell, body index order within a cell; by body index when
  /// sortedNeighbours_.
  std::vector<Entry> entries_;
  std::vector<Place> places_;       ///< by body index
  std::vector<Prepared> prepared_;  ///< by body index (prepare)
  /// Whether prepare() cuts the prepared bodies' cells, and the cell size
  /// (inverse, as inverseWidth_ and inverseHeight_) it cuts them with: the
  /// last build's.
  bool cutsCells_ = false;
  float keyedInverseWidth_ = 1, keyedInverseHeight_ = 1;
  /// When the box of the occupied cells, grown by one cell on every side, is
  /// small (a few hundred cells a body): a bit a cell of it, set where a
  /// body is, so that most empty neighbours cost a bit test, not a hash
  /// look-up. Empty when that box is too large.
  std::vector<std::uint64_t> occupied_;
  /// The bit offsets in occupied_ to a cell's 7 neighbours, by upperHalf (as
  /// the key offsets; modulo 2^32).
  std::array<std::array<std::uint32_t, 7>, 8> bitOffsets_{};
  /// The sweep: stops by body index (empty when no body was fast), and its
  /// working lists, kept to spare allocations.
  std::vector<Stop> stops_;
  std::vector<Mover> movers_;
  std::vector<std::pair<std::uint64_t, std::uint32_t>> sweepCells_;  ///< (cell key, fast body)
  std::vector<std::uint64_t> sweepPairs_;                            ///< a << 32 | b, a < b
  /// Low x's ordered bits << 32 | body, sorted; kept for the next sweep.
  std::vector<std::uint64_t> sweepOrder_;
  /// The sorted sweep's boxes in x order (detail::SortedBoxes): the six
  /// bounds' arrays, then the bodies' and their fast flags'.
  std::vector<float> sweepBounds_;
  std::vector<std::uint32_t> sweepBodies_;
  std::vector<std::uint32_t> oversize_;  ///< fast bodies of more than kMaxSweepPieces pieces
  /// The last build found the pairs by sorting (findNeighboursBySorting):
  /// entries_ are by body index, places_ and the cells unused.
  bool sortedNeighbours_ = false;
  /// Builds left before a crowd that findNeighboursBySorting turned back is
  /// sorted again (the grid's work meanwhile: the same pairs).
  int buildsUntilSortingAgain_ = 0;
  static constexpr int kBuildsBeforeSortingAgain = 30;
  /// The centres in x order (ties in the last order), then
  /// detail::kCentreRun at x +infinity; kept from the last build, whose
  /// order is nearly this build's.
  std::vector<detail::SortedCentre> xOrder_;
  /// The bodies the grid would examine for a body and that overlap it
  /// (pairOverlap > 0): a list a body, in nearLinks_ from nearHead_[body] on
  /// (the order does not matter: NearestPushers keeps the nearest whatever
  /// the order, and with no more candidates than the cap the grid examines
  /// all).
  struct NearLink {
    std::uint32_t body;
    std::uint32_t next;  ///< in nearLinks_; kNoNeighbour ends the list
    float distance;      ///< between the centres, as the push measures it
    float overlap;       ///< along the line between them, likewise
  };
  static constexpr std::uint32_t kNoNeighbour = ~std::uint32_t(0);
  std::vector<std::uint32_t> nearHead_;
  std::vector<NearLink> nearLinks_;
  /// The pairs findNeighboursBySorting last listed (a << 32 | b): those
  /// within reach plus twice listedSlack_ along x and z, and twice
  /// listedSlackY_ along y, of the entries then (listedEntries_, by body
  /// index), in cells of listedWidth_ by listedHeight_; listedSlack_ < 0
  /// when there is no list.
  std::vector<std::uint64_t> listedPairs_;
  /// Those of listedPairs_ that overlap in this build, and how far.
  struct OverlappingPair {
    std::uint64_t pair;
    float distance, overlap;  ///< as NearLink's
  };
  std::vector<OverlappingPair> overlappingPairs_;
  std::vector<Entry> listedEntries_;
  float listedSlack_ = -1, listedSlackY_ = -1, listedWidth_ = 0, listedHeight_ = 0;
  int listedBuilds_ = 0;  ///< builds the list has served since it was made
  /// Builds left before the pairs are listed again, after a list that served
  /// none, and how many the next such list will wait (doubled after each,
  /// back to the least after one that served a build).
  int buildsUntilListingAgain_ = 0;
  static constexpr int kLeastBuildsBeforeListingAgain = 16, kMostBuildsBeforeListingAgain = 256;
  int listingBackOff_ = kLeastBuildsBeforeListingAgain;
  /// A list's slack, as a share of the reach (half a cell, twice the
  /// widest body's xz radius): at most 1 (the cell-count bound,
  /// findNeighboursBySorting). Larger, a list lasts longer but holds more
  /// pairs, and the scan that lists them reads further along x. Once the
  /// listed pairs were measured four at a time, the whole reach (1, and 1
  /// along y) made the body phase's median frame 2.2% faster than 0.5 (and
  /// 0.75 along y) on oa_dm4, 1.4 to 5% on the other shared levels (walkers,
  /// 64 agents, 6 m/s; 0.75 and 1 along x with 0.75 along y: 0.5% and 0.7%).
  /// Before that, 0.25, 0.5 and 1 cost 135, 113 and 113 instructions a
  /// body-step (oa_dm4; 142 without a list).
  static constexpr float kListSlackShare = 1;
  /// The slack along y, as a share of the reach along y (half a cell's
  /// height). Its own, because falling bodies move along y: on fan, 255 of
  /// the 262 lists that ended in 600 frames ended on a move along y alone
  /// (walkers, 64 agents, 6 m/s, a share of 0.75). Free of the cell-count
  /// bound, which counts along x. The lists hold more pairs one above the
  /// other: on fan 1.5 was 1.7% faster than 1, on oa_dm4 1.4% slower.
  static constexpr float kListSlackShareY = 1;
};

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
  /// it over frames; stepBodies and stepBodiesAgainstLevel keep one per body.
  NearbyTriangles nearby;
  /// The body grid stepBodies builds each frame (the pool overload builds
  /// one in each thread's scratch).
  BodyGrid bodyGrid;

  /// How many triangles the last slide's narrow phase tested: the nearby
  /// triangles whose box overlaps the slide's local box (its swept box,
  /// grown a little). Diagnostics; valid until the scratch steps again.
  std::size_t lastSlideCandidates() const;
  /// How many candidates the last slide's scans went through, their boxes
  /// tested 4 or 8 at a time before anything else: a short list (at most
  /// 48) whole, of a longer one the 8 of each block of candidates whose box
  /// overlaps the local box. Diagnostics.
  std::size_t lastSlideScannedLanes() const;
  /// The narrow phases' working lists. Private to the runtime.
  detail::StepWorkspace& workspace();

 private:
  std::unique_ptr<detail::StepWorkspace> workspace_;
};

/// Advances one body by `dt` seconds against the level. `force` is the input
/// acceleration, m/s^2; only its x and z count (input acts in the xz plane).
/// Checks its inputs first, in every build: a body with a NaN or infinite
/// position, velocity or force, a bad dt, radii outside [kMinBodyRadius,
/// kMaxBodyRadius], settings out of range, or beyond kMaxBodyCoordinate is
/// not moved, and `report` says why (StepReport::invalidInput). From valid
/// inputs on a verified World the position and velocity stay finite.
/// Never leaves the body inside the level's offset surfaces if it started
/// outside them; a refused move leaves the position unchanged.
void stepBody(const World& world, Body& body, const Vec3& force, float dt, StepScratch& scratch,
              StepReport* report = nullptr);

/// What the step keeps of each body from frame to frame besides the Body
/// itself (its tree query and the candidates made from it), by body index,
/// for a job system's threads to share: with it a body keeps its query
/// whichever thread steps or pushes it (see the stepBodiesAgainstLevel and
/// pushBodiesApart overloads that take one). Results never depend on it;
/// only the cost does. Movable, not copyable; allocates only while growing.
class BodyCaches {
 public:
  BodyCaches();
  ~BodyCaches();
  BodyCaches(BodyCaches&&) noexcept;
  BodyCaches& operator=(BodyCaches&&) noexcept;
  /// Holds `bodies` bodies' caches: those of bodies [0, bodies) are kept,
  /// any beyond are dropped, new ones start empty. Not thread-safe: call it
  /// before a frame's jobs (when the crowd grows or shrinks).
  void resize(std::size_t bodies);
  std::size_t size() const;
  /// The tree queries made through these caches since construction
  /// (diagnostics: a body keeps its query while it stays inside it).
  std::uint64_t queries() const;

 private:
  friend void stepBodiesAgainstLevel(const World&, std::span<Body>, std::span<const Vec3>, float,
                                     std::size_t, std::size_t, StepScratch&, BodyCaches&,
                                     std::span<StepReport>);
  friend void pushBodiesApart(const World&, const BodyGrid&, std::span<Body>, std::size_t,
                              std::size_t, StepScratch&, BodyCaches&, std::span<StepReport>);
  std::vector<detail::BodyCache> caches_;
};

/// The level phase of stepBodies: advances each of `bodies` by `dt` against
/// the level only, as stepBody, without the body-against-body phase.
/// `forces` is parallel to `bodies`; `reports` is empty or parallel too (each
/// report is reset, then filled). To spread a frame over a job system, call
/// it on disjoint sub-spans of the bodies (with the matching sub-spans of
/// forces and reports), then build a BodyGrid from all the bodies, then call
/// pushBodiesApart on disjoint ranges: the same trajectories as stepBodies,
/// bit for bit, whatever the split.
/// Cost: `scratch` keeps each body's tree query and candidates between
/// frames by the body's place in the span it is given (here the sub-span;
/// in pushBodiesApart the whole crowd's). Trajectories never depend on
/// them, but a body whose place or scratch changes from one call to the
/// next (a job system handing ranges to whichever thread is free, or a
/// level phase on a sub-span that does not start at 0 followed by pushes
/// with the same scratch) queries the tree again (700 to 5,000 instructions
/// a query on a flat floor and on oa_dm4, against 2,600 for a whole step of
/// a walker there). The overloads with BodyCaches keep every body's cache
/// by its index, whichever thread steps it, as stepBodies with a ThreadPool
/// does.
/// Thread safety: as stepBody; calls on disjoint bodies may run concurrently,
/// each with its own scratch.
void stepBodiesAgainstLevel(const World& world, std::span<Body> bodies,
                            std::span<const Vec3> forces, float dt, StepScratch& scratch,
                            std::span<StepReport> reports = {});

/// The level phase for bodies [first, last) of a whole crowd `bodies`, each
/// body's cache kept in `caches` by its index in `bodies`: a job system may
/// hand any range to any thread, frame after frame, and every body keeps
/// its tree query. Otherwise as stepBodiesAgainstLevel on that sub-span
/// (the same trajectories, bit for bit).
/// Preconditions: `forces` (and `reports`, unless empty) parallel to
/// `bodies`; first <= last <= bodies.size() <= caches.size() (resize
/// `caches` first).
/// Thread safety: calls on disjoint ranges may run concurrently, each with
/// its own scratch, all with the same `caches`.
void stepBodiesAgainstLevel(const World& world, std::span<Body> bodies,
                            std::span<const Vec3> forces, float dt, std::size_t first,
                            std::size_t last, StepScratch& scratch, BodyCaches& caches,
                            std::span<StepReport> reports = {});

/// Advances every body by `dt`: each against the level (stepBodiesAgainstLevel),
/// then overlapping bodies are pushed apart (scratch.bodyGrid, then
/// pushBodiesApart: each body by half of each overlap, horizontally, summed
/// but no longer than the largest half, in one move against the level, so
/// it never ends inside a wall). The broad phase
/// is a hashed grid and the pushers per body are capped (kMaxBodyPushes,
/// kMaxBodyCandidates): the cost is linear in the number of bodies, even
/// when they pile up at one point.
/// `forces` is parallel to `bodies`; `reports` is empty or parallel too.
/// A body with invalid inputs (StepReport::invalidInput) is not moved and
/// is left out of the body phase: the others are pushed as if it were not
/// there (in a frame with such a body, the body phase runs on a copy of the
/// valid bodies, in their order, on the calling thread).
/// Thread safety: the World is only read; runs on the calling thread.
void stepBodies(const World& world, std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                StepScratch& scratch, std::span<StepReport> reports = {});

class ThreadPool;

/// stepBodies on every thread of `pool`: both phases are split into ranges of
/// bodies run in parallel. Gives the same trajectories and reports as the
/// single-threaded stepBodies, bit for bit, for any number of threads (with
/// a pool of one thread it is that stepBodies, on scratches[0]).
/// `scratches` holds one scratch per pool thread (scratches[t] for thread t;
/// each holds the frame's body grid, scratches[0] always, the others when
/// their thread pushed bodies); keep them across frames.
/// Preconditions: as stepBodies, and scratches.size() >= pool.threadCount().
/// Thread safety: uses the pool (one call at a time per pool) and the
/// scratches; the World is only read.
void stepBodies(const World& world, std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                ThreadPool& pool, std::span<StepScratch> scratches,
                std::span<StepReport> reports = {});

}  // namespace bspf
