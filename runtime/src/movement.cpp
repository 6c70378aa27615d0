// SPDX-License-Identifier: MIT
// The per-frame step: stepBody drives one body through the phases (future
// velocity, slide against the level, step-up, contact response); stepBodies
// steps every body, then runs the body-against-body phase.
#include <bspf/movement.h>
#include <bspf/thread_pool.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cassert>
#include <cmath>
#include <cstring>
#include <optional>
#include <vector>

#include "slide.h"
#include "velocity.h"

namespace bspf {

StepScratch::StepScratch() = default;
StepScratch::~StepScratch() = default;
StepScratch::StepScratch(StepScratch&&) noexcept = default;
StepScratch& StepScratch::operator=(StepScratch&&) noexcept = default;

detail::StepWorkspace& StepScratch::workspace() {
  // Made on first use, so a default-constructed or moved-from scratch works.
  if (!workspace_) workspace_ = std::make_unique<detail::StepWorkspace>();
  return *workspace_;
}

std::size_t StepScratch::lastSlideCandidates() const {
  if (!workspace_) return 0;
  // Counted here, not in the slide: a short list is scanned whole, its
  // lanes' boxes tested by the masks, and only the count needs them apart.
  std::size_t count = 0;
  for (const detail::CandidateBlock* const block : workspace_->lastBlocks)
    count += std::size_t(std::popcount(detail::boxMask(*block, workspace_->lastLocal)));
  return count;
}

std::size_t StepScratch::lastSlideScannedLanes() const {
  return workspace_ ? workspace_->lastScanned : 0;
}

SlideResult slideAgainstLevel(const World& world, const Vec3& start, const Vec3& desiredEnd,
                              EllipsoidRadii radii, const MovementSettings& settings,
                              float walkableNormalY, StepScratch& scratch,
                              std::span<const std::uint32_t> hints,
                              std::span<const std::uint32_t> wallHints) {
  return settings.method == CollisionMethod::ExactSweep
             ? slideExact(world, start, desiredEnd, radii, settings, walkableNormalY, scratch,
                          hints, wallHints)
             : slideWithPlanes(world, start, desiredEnd, radii, settings, walkableNormalY, scratch,
                               hints);
}

namespace {

// How far a slide got along the horizontal direction of `move`, metres.
float horizontalProgress(const Vec3& start, const Vec3& end, const Vec3& move) {
  const Vec3 along(move.x(), 0, move.z());
  const float length = along.norm();
  return length > 0 ? (end - start).dot(along) / length : 0;
}

bool anyWalkable(const SlideResult& r) {
  return std::any_of(r.contacts.begin(), r.contacts.begin() + r.contactCount,
                     [](const Contact& c) { return c.walkable; });
}

// Whether anything below held the body in this slide: a contact facing up,
// walkable or not (a wall's normal may tilt by float rounding: within about
// half a degree of level it is a wall). A steep contact facing up is one the
// move pushed into (a slope too steep to walk, or the rounded edge of a step
// the exact sweep is riding over): the body is not leaving the ground there,
// and pulling it down would drag it back off the edge.
bool heldFromBelow(const SlideResult& r) {
  return std::any_of(r.contacts.begin(), r.contacts.begin() + r.contactCount,
                     [](const Contact& c) { return c.walkable || c.normal.y() > 0.01f; });
}

// Ground snapping (MovementSettings::maxStepDown): a body that was grounded
// and whose move (`slide`, of `move`, from a velocity not moving it upward)
// left the ground is slid straight down from the move's end, with the
// narrow phase, so it never passes through anything; the slide down is kept
// when it ends on walkable ground at most maxStepDown below the move's end.
// Both narrow phases stop a body on walkable ground where they meet it (no
// creep downhill), so on a slope the snapped body keeps the move's
// horizontal progress.
// The first slide goes only as deep as the steepest walkable slope falls
// over the move (plus a frame of gravity): the common case, walking down a
// slope, then stays in the box of triangles the move itself queried; only
// when nothing is met does the next go on to maxStepDown (stairs, ledges).
// A rounded body (the exact sweep) going over a stair's edge meets the edge
// steep: the slide down slips along it and spends most of its length doing
// so, so the next goes on straight down from where it slipped to, with what
// is left of the drop. At most kSnapSlides slides in all.
void snapToGround(const World& world, const Body& body, const Vec3& move, float walkableY,
                  StepScratch& scratch, SlideResult& slide) {
  constexpr int kSnapSlides = 4;
  const MovementSettings& s = body.settings;
  const float lowest = slide.end.y() - s.maxStepDown;
  const float slopeTan = std::sqrt(std::max(0.0f, 1 - walkableY * walkableY)) / walkableY;
  const float slopeDrop = std::hypot(move.x(), move.z()) * slopeTan + std::max(0.0f, -move.y());
  SlideResult down;
  down.end = slide.end;
  int iterations = 0;
  for (int k = 0; k < kSnapSlides; ++k) {
    const float rest = down.end.y() - lowest;
    const bool all = k > 0 || slopeDrop + s.skin >= rest;
    if (rest <= s.skin) return;
    down = slideAgainstLevel(world, down.end, down.end - Vec3(0, all ? rest : slopeDrop, 0),
                             body.radii, s, walkableY, scratch);
    iterations += down.iterations;
    if (down.refused) return;
    if (anyWalkable(down)) break;
    // Nothing below within maxStepDown (a ledge higher than it, a gap): the
    // body falls.
    if (all && down.contactCount == 0) return;
  }
  if (!anyWalkable(down) || down.end.y() < lowest - s.skin) return;
  slide.end = down.end;
  slide.iterations += iterations;
  for (int i = 0; i < down.contactCount; ++i) {
    if (slide.contactCount < kMaxReportedContacts) {
      slide.contacts[slide.contactCount++] = down.contacts[i];
    } else if (down.contacts[i].walkable) {
      // A full list keeps the ground, which decides the ground state.
      slide.contacts[kMaxReportedContacts - 1] = down.contacts[i];
      break;
    }
  }
}

// Body::groundTriangles and wallTriangles after `slide`: the triangles of
// its walkable contacts, and (for the exact sweep, the one method that uses
// them) of its other contacts with a face, not an edge or a corner, each
// once, in the order met.
void rememberContacts(const SlideResult& slide, Body& body) {
  auto remember = [&slide](auto& list, auto kept) {
    std::fill(list.begin(), list.end(), kNoTriangle);
    std::size_t count = 0;
    for (int i = 0; i < slide.contactCount && count < list.size(); ++i) {
      const std::uint32_t t = slide.contacts[i].triangle;
      if (kept(slide.contacts[i]) &&
          std::find(list.begin(), list.begin() + count, t) == list.begin() + count)
        list[count++] = t;
    }
  };
  remember(body.groundTriangles, [](const Contact& c) { return c.walkable; });
  if (body.settings.method == CollisionMethod::ExactSweep)
    remember(body.wallTriangles, [](const Contact& c) { return !c.walkable && !c.edge; });
  else
    body.wallTriangles = kNoWallTriangles;
}

// Stairs: a grounded body whose horizontal move was blocked retries it lifted
// by maxStepHeight (up, across, then down onto the step), and keeps the retry
// when it lands on walkable ground further along than the plain slide. The
// slides are the narrow phase's own, so a step-up never enters a wall; a
// ceiling lower than the lift just lifts less.
void tryStepUp(const World& world, const Body& body, const Vec3& start, const Vec3& desiredEnd,
               float walkableY, StepScratch& scratch, SlideResult& slide) {
  const Vec3 move = desiredEnd - start;
  const Vec3 across(move.x(), 0, move.z());
  const float plainProgress = horizontalProgress(start, slide.end, move);
  // Only a move stopped short by something steep is retried.
  bool blocked = false;
  for (int i = 0; i < slide.contactCount; ++i) blocked = blocked || !slide.contacts[i].walkable;
  if (!blocked || across.norm() - plainProgress < 1e-4f) return;

  const MovementSettings& s = body.settings;
  const SlideResult up = slideAgainstLevel(world, start, start + Vec3(0, s.maxStepHeight, 0),
                                           body.radii, s, walkableY, scratch);
  const SlideResult over =
      slideAgainstLevel(world, up.end, up.end + across, body.radii, s, walkableY, scratch);
  // Down by the lift and by the move's own fall.
  const float drop = (up.end.y() - start.y()) + std::max(0.0f, -move.y());
  const SlideResult down = slideAgainstLevel(world, over.end, over.end - Vec3(0, drop, 0),
                                             body.radii, s, walkableY, scratch);
  // A rounded body (the exact sweep) comes down on the step's edge before
  // its centre is over the step: an edge contact facing up, higher than the
  // start, is standing on a step. (A steep slope's face still refuses.)
  const bool onStepEdge =
      !anyWalkable(down) && down.end.y() > start.y() + 1e-3f &&
      std::any_of(down.contacts.begin(), down.contacts.begin() + down.contactCount,
                  [](const Contact& c) { return c.edge && c.normal.y() > 0; });
  if (!anyWalkable(down) && !onStepEdge) return;
  // Never higher than the step height: a walkable response on the way down
  // (the planes method lifts a body onto a surface it reaches) could
  // otherwise carry it onto a ledge above the lift.
  if (up.refused || over.refused || down.refused ||
      down.end.y() > start.y() + s.maxStepHeight + s.skin ||
      horizontalProgress(start, down.end, move) <= plainProgress + 1e-4f)
    return;
  SlideResult stepped = down;
  stepped.iterations = up.iterations + over.iterations + down.iterations;
  stepped.contactCount = 0;
  for (const SlideResult* part : {&over, &down})
    for (int i = 0; i < part->contactCount && stepped.contactCount < kMaxReportedContacts; ++i)
      if (part != &down || !onStepEdge)
        stepped.contacts[stepped.contactCount++] = part->contacts[i];
  // Standing on the step's edge counts as standing on the step (the edge's
  // triangle and point, ground's normal).
  if (onStepEdge && stepped.contactCount < kMaxReportedContacts) {
    Contact standing = *std::find_if(down.contacts.begin(), down.contacts.end(),
                                     [](const Contact& c) { return c.edge && c.normal.y() > 0; });
    standing.normal = Vec3::UnitY();
    standing.walkable = true;
    stepped.contacts[stepped.contactCount++] = standing;
  }
  slide = stepped;
}

// Every range movement.h gives, written so that NaN fails each test.
bool settingsInRange(const Body& body) {
  const MovementSettings& s = body.settings;
  const bool finite = std::isfinite(s.gravity) && std::isfinite(s.groundFriction) &&
                      std::isfinite(s.airFriction) && std::isfinite(s.maxHorizontalSpeed);
  const bool knownMethod =
      s.method == CollisionMethod::Planes || s.method == CollisionMethod::ExactSweep;
  return finite && knownMethod && s.gravity >= 0 && s.groundFriction >= 0 && s.airFriction >= 0 &&
         s.maxHorizontalSpeed > 0 && s.walkableSlopeDegrees >= 0 && s.walkableSlopeDegrees <= 89 &&
         s.maxIterations >= 1 && s.maxIterations <= 32 && s.restitution >= 0 &&
         s.restitution <= 1 && s.skin > 0 && s.skin < std::min(body.radii.xz, body.radii.y) &&
         s.maxStepHeight >= 0 && s.maxStepHeight <= 2 * body.radii.y && s.maxStepDown >= 0 &&
         s.maxStepDown <= kMaxBodyRadius;
}

// settingsInRange, remembering per thread the last settings (and radii)
// found in range: most bodies share them, and their bytes compare in a few
// instructions where the ranges take a hundred. Settings equal byte for byte
// to ones in range are in range, so nothing is ever accepted that the full
// check would refuse.
bool settingsInRangeRemembered(const Body& body) {
  // No padding (its bytes are its fields): 4-byte fields only.
  static_assert(sizeof(MovementSettings) == 11 * 4 && sizeof(CollisionMethod) == 4,
                "MovementSettings changed: check it has no padding, then this count");
  thread_local MovementSettings lastSettings;
  thread_local EllipsoidRadii lastRadii{0, 0};
  if (std::memcmp(&body.settings, &lastSettings, sizeof lastSettings) == 0 &&
      body.radii.xz == lastRadii.xz && body.radii.y == lastRadii.y)
    return true;
  if (!settingsInRange(body)) return false;
  lastSettings = body.settings;
  lastRadii = body.radii;
  return true;
}

}  // namespace

const char* toString(InvalidInput invalid) {
  switch (invalid) {
    case InvalidInput::None: return "none";
    case InvalidInput::Position: return "position";
    case InvalidInput::Velocity: return "velocity";
    case InvalidInput::Force: return "force";
    case InvalidInput::TimeStep: return "time step";
    case InvalidInput::Radii: return "radii";
    case InvalidInput::Settings: return "settings";
    case InvalidInput::OutOfReach: return "out of reach";
    case InvalidInput::DeferredPush: return "deferred push";
  }
  return "unknown";
}

namespace {

// The step's entry check (stepBody; stepBodies uses it to leave bodies out
// of the body phase). It runs twice per body per frame, so it takes no
// square root: friction only slows the horizontal velocity and the cap only
// limits it, so the desired end is within (|v| + (|force| + gravity) dt) dt
// of the position (plus the deferred push), bounded here with sums of
// absolute components (never less than the lengths). In float: a sum that
// overflows is infinite, and fails the bound as it should.
InvalidInput checkStepInputs(const Body& body, const Vec3& force, float dt) {
  // One product by zero catches every NaN or infinity at once (it makes a
  // NaN); the checks one by one run only to name the culprit.
  const float probe =
      (body.position.sum() + body.velocity.sum() + force.sum() + body.deferredPush.sum() + dt) *
      0.0f;
  if (probe != 0.0f || !(dt > 0)) {
    if (!body.position.allFinite()) return InvalidInput::Position;
    if (!body.velocity.allFinite()) return InvalidInput::Velocity;
    if (!force.allFinite()) return InvalidInput::Force;
    if (!(dt > 0) || !std::isfinite(dt)) return InvalidInput::TimeStep;
    if (!body.deferredPush.allFinite()) return InvalidInput::DeferredPush;
  }
  for (const float r : {body.radii.xz, body.radii.y})
    if (!(r >= kMinBodyRadius && r <= kMaxBodyRadius)) return InvalidInput::Radii;
  if (!settingsInRangeRemembered(body)) return InvalidInput::Settings;
  const float speed =
      body.velocity.cwiseAbs().sum() + (force.cwiseAbs().sum() + body.settings.gravity) * dt;
  const float reach =
      body.position.cwiseAbs().maxCoeff() + speed * dt + body.deferredPush.cwiseAbs().sum();
  if (!(reach <= kMaxBodyCoordinate)) return InvalidInput::OutOfReach;
  return InvalidInput::None;
}

// Gives `report` StepReport{}'s values, field by field: assigning a
// StepReport{} built it on the stack first, in 4-byte stores that the copy
// then read back 16 bytes at a time (failed store forwards: 40% of
// stepOne's samples in perf), and constructing it in place zeroed it with a
// slower `rep stos`. The contacts' normals and points StepReport{} leaves
// unset are left as they are.
void clearReport(StepReport& report) {
  static_assert(sizeof(StepReport) == 12 + kMaxReportedContacts * 32 + 8,
                "StepReport changed: reset its new fields here");
  report.iterations = 0;
  report.refused = false;
  report.grounded = false;
  report.contactCount = 0;
  report.contactTriangles.fill(0);
  report.contactSurfaces.fill(0);
  report.bodyContacts = 0;
  report.belowLevel = false;
  report.stoppedByBody = false;
  report.invalidInput = InvalidInput::None;
}

}  // namespace

namespace detail {

InvalidInput stepOne(const World& world, Body& body, const Vec3& force, float dt,
                     StepScratch& scratch, StepReport* report) {
  if (report) clearReport(*report);
  // Where the body phase's sweep starts this body's move from.
  body.lastStepStart = body.position;
  body.lastStepPush = Vec3::Zero();
  if (const InvalidInput invalid = checkStepInputs(body, force, dt);
      invalid != InvalidInput::None) {
    if (report) report->invalidInput = invalid;
    return invalid;
  }

  detail::futureVelocity(body, force, dt);
  const Vec3 start = body.position;
  // The push the body phase carried over moves with the body's own move.
  const Vec3 move = body.velocity * dt + body.deferredPush;
  body.lastStepPush = body.deferredPush;
  body.deferredPush = Vec3::Zero();
  const float walkableY = walkableNormalY(body.settings);
  SlideResult slide =
      slideAgainstLevel(world, start, start + move, body.radii, body.settings, walkableY, scratch,
                        body.groundTriangles, body.wallTriangles);
  // A rounded body resting on a step's edge (not walkable ground, but
  // support) may step on as well.
  auto onEdge = [&slide] {
    return std::any_of(slide.contacts.begin(), slide.contacts.begin() + slide.contactCount,
                       [](const Contact& c) { return c.edge && c.normal.y() > 0; });
  };
  if (body.settings.maxStepHeight > 0 && (body.grounded || onEdge()))
    tryStepUp(world, body, start, start + move, walkableY, scratch, slide);
  // Ground snapping, when the move left the ground: nothing below held it.
  // Moving upward means a vertical velocity above 0 after this step's
  // gravity: a jump or a bounce (walking never leaves one; see
  // MovementSettings::maxStepDown). A refused move stays where it was.
  if (body.settings.maxStepDown > 0 && body.grounded && body.velocity.y() <= 0 && !slide.refused &&
      !heldFromBelow(slide))
    snapToGround(world, body, move, walkableY, scratch, slide);
  body.position = slide.end;
  detail::respondToContacts(body, slide, dt);
  body.grounded = anyWalkable(slide);
  rememberContacts(slide, body);
  if (report) {
    recordSlide(world, report, slide, true);
    report->grounded = body.grounded;
    report->belowLevel = body.position.y() + body.radii.y < world.boundsMin().y();
  }
  return InvalidInput::None;
}

}  // namespace detail

void stepBody(const World& world, Body& body, const Vec3& force, float dt, StepScratch& scratch,
              StepReport* report) {
  detail::stepOne(world, body, force, dt, scratch, report);
}

void stepBodiesAgainstLevel(const World& world, std::span<Body> bodies,
                            std::span<const Vec3> forces, float dt, StepScratch& scratch,
                            std::span<StepReport> reports) {
  assert(forces.size() == bodies.size());
  assert(reports.empty() || reports.size() == bodies.size());
  std::vector<detail::BodyCache>& caches = scratch.workspace().bodies;
  if (caches.size() < bodies.size()) caches.resize(bodies.size());
  detail::stepRangeAgainstLevel(world, bodies, forces, dt, scratch, reports, caches);
}

BodyCaches::BodyCaches() = default;
BodyCaches::~BodyCaches() = default;
BodyCaches::BodyCaches(BodyCaches&&) noexcept = default;
BodyCaches& BodyCaches::operator=(BodyCaches&&) noexcept = default;
void BodyCaches::resize(std::size_t bodies) { caches_.resize(bodies); }
std::size_t BodyCaches::size() const { return caches_.size(); }
std::uint64_t BodyCaches::queries() const {
  std::uint64_t total = 0;
  for (const detail::BodyCache& cache : caches_) total += cache.nearby.queries();
  return total;
}

void stepBodiesAgainstLevel(const World& world, std::span<Body> bodies,
                            std::span<const Vec3> forces, float dt, std::size_t first,
                            std::size_t last, StepScratch& scratch, BodyCaches& caches,
                            std::span<StepReport> reports) {
  assert(forces.size() == bodies.size());
  assert(reports.empty() || reports.size() == bodies.size());
  assert(first <= last && last <= bodies.size() && bodies.size() <= caches.size());
  const std::size_t count = last - first;
  detail::stepRangeAgainstLevel(world, bodies.subspan(first, count), forces.subspan(first, count),
                                dt, scratch,
                                reports.empty() ? reports : reports.subspan(first, count),
                                std::span(caches.caches_).subspan(first, count));
}

namespace {

// stepBodiesAgainstLevel, saying how many bodies were not moved for
// invalid input.
std::size_t stepAllAgainstLevel(const World& world, std::span<Body> bodies,
                                std::span<const Vec3> forces, float dt, StepScratch& scratch,
                                std::span<StepReport> reports) {
  std::vector<detail::BodyCache>& caches = scratch.workspace().bodies;
  if (caches.size() < bodies.size()) caches.resize(bodies.size());
  return detail::stepRangeAgainstLevel(world, bodies, forces, dt, scratch, reports, caches);
}

}  // namespace

namespace detail {

std::size_t stepRangeAgainstLevel(const World& world, std::span<Body> bodies,
                                  std::span<const Vec3> forces, float dt, StepScratch& scratch,
                                  std::span<StepReport> reports, std::span<BodyCache> caches) {
  // Each body keeps its own nearby triangles from frame to frame (swapped in,
  // no copy). A list reordered by the caller only costs re-queries: a cache
  // answers only boxes inside the one it queried, whoever asks, and the
  // narrow phases test their candidates in triangle order, so results do
  // not depend on what a cache held (the exact sweep's only in the last bits
  // of a slide: its candidates keep their last face distance while their
  // query lasts, so when a body queries again can round a slide
  // differently; the same inputs still give the same trajectories).
  std::size_t invalid = 0;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    swapBodyCache(scratch, caches[i]);
    invalid += stepOne(world, bodies[i], forces[i], dt, scratch,
                       reports.empty() ? nullptr : &reports[i]) != InvalidInput::None;
    swapBodyCache(scratch, caches[i]);
  }
  return invalid;
}

}  // namespace detail

namespace {

// The bodies with valid inputs, by index, when some are invalid; nothing
// when all are valid (the common case: nothing is allocated).
std::optional<std::vector<std::uint32_t>> validBodiesIfAnyInvalid(std::span<const Body> bodies,
                                                                  std::span<const Vec3> forces,
                                                                  float dt) {
  auto ok = [&](std::size_t i) {
    return checkStepInputs(bodies[i], forces[i], dt) == InvalidInput::None;
  };
  std::size_t i = 0;
  while (i < bodies.size() && ok(i)) ++i;
  if (i == bodies.size()) return std::nullopt;
  std::vector<std::uint32_t> valid;
  valid.reserve(bodies.size());
  for (std::uint32_t j = 0; j < i; ++j) valid.push_back(j);
  for (++i; i < bodies.size(); ++i)
    if (ok(i)) valid.push_back(std::uint32_t(i));
  return valid;
}

// The body phase over the valid bodies only, on a copy of them (the body
// grid would take an invalid body's NaN or huge radius into its cells).
void pushValidBodiesApart(const World& world, std::span<Body> bodies,
                          std::span<const std::uint32_t> valid, StepScratch& scratch,
                          std::span<StepReport> reports) {
  std::vector<Body> kept(valid.size());
  std::vector<StepReport> keptReports(reports.empty() ? 0 : valid.size());
  for (std::size_t j = 0; j < valid.size(); ++j) {
    kept[j] = bodies[valid[j]];
    if (!reports.empty()) keptReports[j] = reports[valid[j]];
  }
  scratch.bodyGrid.build(kept);
  pushBodiesApart(world, scratch.bodyGrid, kept, 0, kept.size(), scratch, keptReports);
  for (std::size_t j = 0; j < valid.size(); ++j) {
    bodies[valid[j]] = kept[j];
    if (!reports.empty()) reports[valid[j]] = keptReports[j];
  }
}

}  // namespace

void stepBodies(const World& world, std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                StepScratch& scratch, std::span<StepReport> reports) {
  assert(forces.size() == bodies.size());
  assert(reports.empty() || reports.size() == bodies.size());
  // The level phase checks every body; only when it refused one are the
  // bodies checked again (after their moves, which keep a valid body valid)
  // to leave the refused ones out of the body phase.
  if (stepAllAgainstLevel(world, bodies, forces, dt, scratch, reports) > 0) {
    if (const auto valid = validBodiesIfAnyInvalid(bodies, forces, dt)) {
      pushValidBodiesApart(world, bodies, *valid, scratch, reports);
      return;
    }
  }
  scratch.bodyGrid.build(bodies);
  pushBodiesApart(world, scratch.bodyGrid, bodies, 0, bodies.size(), scratch, reports);
}

void stepBodies(const World& world, std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                ThreadPool& pool, std::span<StepScratch> scratches, std::span<StepReport> reports) {
  assert(forces.size() == bodies.size());
  assert(reports.empty() || reports.size() == bodies.size());
  assert(scratches.size() >= std::size_t(pool.threadCount()));
  // On one thread the body phase reads every body from the core that just
  // stepped it: preparing what its build reads would only copy it (43
  // instructions a body-step, 1.5% of a walker's step at 6 m/s on oa_dm5,
  // callgrind).
  if (pool.threadCount() == 1) {
    stepBodies(world, bodies, forces, dt, scratches[0], reports);
    return;
  }
  // Small ranges balance the threads (a body against a wall costs several
  // times one in the open); each range still holds enough work to hide the
  // hand-out.
  constexpr std::size_t kBodiesPerRange = 16;
  // The bodies' caches live in the first scratch, by body index, whichever
  // thread steps a body (each entry is touched by one thread at a time).
  std::vector<detail::BodyCache>& caches = scratches[0].workspace().bodies;
  if (caches.size() < bodies.size()) caches.resize(bodies.size());
  // Each range also takes what the grid's build reads of its bodies, while
  // they are in its core's cache: built from the bodies themselves, the
  // build (on one thread) read every other thread's bodies from that core,
  // and those threads took the lines back in their next step. Where cores
  // pass a cache line slowly (about 250 ns each way on the 2-core machine
  // measured), a walking crowd of 1,024 on a flat floor took 183 ns a body
  // on 2 threads, and 149 with the bodies prepared in place.
  BodyGrid& prepared = scratches[0].bodyGrid;  // holds the prepared inputs
  prepared.startPreparing(bodies.size());
  std::atomic<std::size_t> invalid{0};
  pool.parallelFor(
      bodies.size(), kBodiesPerRange, [&](int thread, std::size_t first, std::size_t last) {
        const std::size_t count = last - first;
        const std::size_t refused = detail::stepRangeAgainstLevel(
            world, bodies.subspan(first, count), forces.subspan(first, count), dt,
            scratches[thread], reports.empty() ? reports : reports.subspan(first, count),
            std::span(caches).subspan(first, count));
        // Only when there is something to add (nearly never): the counter's
        // line is shared by every thread, and an add at every range would
        // pass it from core to core.
        if (refused > 0) invalid += refused;
        prepared.prepare(bodies, first, last);
      });
  if (invalid > 0) {
    if (const auto valid = validBodiesIfAnyInvalid(bodies, forces, dt)) {
      pushValidBodiesApart(world, bodies, *valid, scratches[0], reports);
      return;
    }
  }
  // Every thread that pushes builds its own copy of the grid, from the
  // prepared inputs, before its first range: the pushes read the grid all
  // over, and a grid built by one core had each other core pull its lines
  // across, one slow transfer at a time (1,024 walkers on oa_dm4, 2 threads:
  // planes 490 -> 437 ns a body, exact 662 -> 613). The copies are built
  // side by side from the same inputs, so they are equal, and the wall time
  // of the build is one build's, as before. The caller's copy is built even
  // when other threads took all its ranges: scratches[0] holds the frame's grid.
  for (int thread = 0; thread < pool.threadCount(); ++thread)
    scratches[std::size_t(thread)].workspace().gridBuilt = false;
  auto buildOnce = [&](int thread) -> const BodyGrid& {
    StepScratch& scratch = scratches[std::size_t(thread)];
    if (!scratch.workspace().gridBuilt) {
      scratch.bodyGrid.buildPrepared(prepared);
      scratch.workspace().gridBuilt = true;
    }
    return scratch.bodyGrid;
  };
  pool.parallelFor(bodies.size(), kBodiesPerRange,
                   [&](int thread, std::size_t first, std::size_t last) {
                     detail::pushRange(world, buildOnce(thread), bodies, first, last,
                                       scratches[thread], reports, caches);
                   });
  buildOnce(0);
}

}  // namespace bspf
