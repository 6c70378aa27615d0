// SPDX-License-Identifier: MIT
// bspf/debug_draw.h: what a query or a step looked at, for a game to draw in
// its own renderer.
//
// A separate entry point, not a hook inside the step: stepBody and the
// queries never call it and pay nothing for it. These functions re-run the
// broad phase of a query (the same tree walk and the same triangle filter as
// collectCandidateTriangles) and hand every BSP cell it reached and every
// candidate triangle it listed to the callbacks of a DebugDraw; the contacts
// of a step come from its StepReport. Call them for the bodies a developer
// is looking at, in a debug view: each call costs about one tree query plus,
// per leaf reached, a walk up the tree (O(depth)), and allocates.
//
// Units: metres, Y up, as everywhere. Thread safety: reads the World only;
// the callbacks run on the calling thread, in order, before the call
// returns.
#pragma once

#include <bspf/geometry.h>
#include <bspf/movement.h>
#include <bspf/world.h>

#include <cstdint>
#include <functional>
#include <span>

namespace bspf {

/// One side of a BSP split: the points p with dot(normal, p) <= distance
/// (normal of unit length, pointing out of the cell).
struct DebugHalfSpace {
  Vec3 normal;
  float distance;
};

/// A leaf's cell of the BSP tree, as a query reached it.
struct DebugCell {
  /// The leaf's number (World::leaves()).
  std::uint32_t leaf;
  /// Its depth in the tree (0 when the tree is a single leaf).
  std::uint32_t depth;
  /// The cell exactly: the level's bounds (World::blob().bounds_min/max)
  /// cut by these half-spaces, one per split from the root down to the
  /// leaf. Valid during the callback only.
  std::span<const DebugHalfSpace> halfSpaces;
  /// An axis-aligned box holding the cell: the level's bounds cut by the
  /// axis-aligned splits among halfSpaces (the cell itself when every split
  /// on the way is axis-aligned; larger when some are slanted).
  Vec3 low, high;
};

/// A triangle a query listed as a candidate.
struct DebugTriangle {
  /// Its index (World::triangles()).
  std::uint32_t triangle;
  /// Its corners, as stored in the level.
  Vec3 a, b, c;
  /// Its face normal (unit length, pointing out of the solid).
  Vec3 normal;
};

/// A surface a step slid against.
struct DebugContact {
  /// Where the body, at the end of the step, touches a plane with this
  /// normal: the ellipsoid's surface point furthest along -normal. The step
  /// keeps no contact points, so for a contact of an earlier slide of the
  /// step this is where the body would touch that plane now.
  Vec3 point;
  /// The contact's unit normal, pointing away from the surface
  /// (StepReport::contactNormals).
  Vec3 normal;
};

/// The callbacks; any may be empty, and is then skipped.
struct DebugDraw {
  std::function<void(const DebugCell&)> cell;
  std::function<void(const DebugTriangle&)> triangle;
  std::function<void(const DebugContact&)> contact;
};

/// Replays the broad phase of the ellipsoid with `radii` swept from centre
/// `from` to centre `to`: calls draw.cell for each leaf collectSweptLeaves
/// returns (in its order, near side first), then draw.triangle for each
/// triangle collectCandidateTriangles returns (the same triangles, in the
/// same order). Preconditions: finite points, radii > 0.
void debugQuery(const World& world, const Vec3& from, const Vec3& to, EllipsoidRadii radii,
                const DebugDraw& draw);

/// Calls draw.contact for each contact normal `report` kept (at most
/// kMaxReportedContacts: level contacts first, then pushes from other
/// bodies), with the point where `body` (after the step) touches it. For a
/// game that steps with stepBodies: call it per body, after the step, with
/// that body's report. Nothing for a report with invalid input.
void debugContacts(const Body& body, const StepReport& report, const DebugDraw& draw);

/// stepBody with a view of its work: steps `body` exactly as stepBody does
/// (the same position, velocity and report, bit for bit), then calls
/// debugQuery for the sweep from the body's start to the end its velocity
/// aimed at (the first slide's query: later slides look at triangles near
/// their own, shorter moves) and debugContacts for the step's contacts.
/// Returns the step's report. A body with invalid input (see stepBody) is
/// not moved and nothing is drawn.
StepReport debugStep(const World& world, Body& body, const Vec3& force, float dt,
                     StepScratch& scratch, const DebugDraw& draw);

}  // namespace bspf
