// The narrow phases' working lists (StepScratch::workspace): each slide's
// candidates with what its tests need precomputed for the body's radii, so
// an iteration reads one short array and takes no square root per
// candidate. Private to the runtime.
#pragma once

#include <bspf/movement.h>

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "narrow_phase.h"

namespace bspf::detail {

/// The face plane and its pre-check values for one body.
struct FaceTest {
  Vec3 normal;
  float distance;
  /// The body's extent along the normal (effectiveRadius).
  float reach;
};

/// A triangle's six perpendicular planes (edges and caps) pushed out by a
/// body's extent along each: the region the body's centre must enter to
/// touch the triangle grown by the body (a superset of where it touches).
/// Made only for the few candidates that pass the box test and the
/// pre-check (growPlanes).
struct GrownTriangle {
  bool ready = false;
  /// (normal, offset): inside when dot(normal, p) >= offset for all six.
  std::array<Eigen::Vector4f, 6> planes;

  /// Precondition: ready.
  bool inside(const Vec3& p) const {
    for (const Eigen::Vector4f& plane : planes)
      if (plane.head<3>().dot(p) < plane.w()) return false;
    return true;
  }
};

/// Fills `grown` for triangle `triangle` and `radii` (sets ready).
void growPlanes(const World& world, std::uint32_t triangle, EllipsoidRadii radii,
                GrownTriangle& grown);

/// A triangle as the planes method tests it for one body.
struct PlanesCandidate {
  Vec3 low, high;  ///< the triangle's box
  std::uint32_t triangle;
  FaceTest face;
  GrownTriangle grown;
};

/// A triangle as the exact sweep tests it for one body: in sphere space.
struct ExactCandidate {
  Vec3 low, high;  ///< the triangle's box, world space
  std::uint32_t triangle;
  FaceTest face;
  Triangle sphere;
};

/// A body's nearby triangles made into one narrow phase's candidates.
template <typename Candidate>
struct MadeCandidates {
  std::vector<Candidate> list;  ///< in triangle order
  /// NearbyTriangles::queryId() of the query they were made from; 0: none.
  std::uint64_t query = 0;
  EllipsoidRadii radii{0, 0};  ///< they were made for
};

/// What one body keeps from frame to frame: its tree query and the
/// candidates made from it.
struct BodyCache {
  NearbyTriangles nearby;
  MadeCandidates<PlanesCandidate> planes;
  MadeCandidates<ExactCandidate> exact;
};

struct StepWorkspace {
  /// The candidates of the body being stepped, made from StepScratch::nearby.
  MadeCandidates<PlanesCandidate> planes;
  MadeCandidates<ExactCandidate> exact;
  /// The current slide's candidates, as indices into planes or exact.
  std::vector<std::uint32_t> listed;
  std::size_t lastCount = 0;
  /// Each body's cache, by index in the bodies stepBodies (or
  /// stepBodiesAgainstLevel) steps: swapped in for the body's step, so each
  /// body reuses its own query and candidates over frames.
  std::vector<BodyCache> bodies;
};

/// Swaps `cache` with the body cache in use in `scratch` (its nearby
/// triangles and the candidates made from them): call once to step the
/// body with its own cache, again to put it back.
inline void swapBodyCache(StepScratch& scratch, BodyCache& cache) {
  StepWorkspace& workspace = scratch.workspace();
  std::swap(scratch.nearby, cache.nearby);
  std::swap(workspace.planes, cache.planes);
  std::swap(workspace.exact, cache.exact);
}

/// pushBodiesApart with caches[i] as body i's cache. Precondition: caches
/// is as long as bodies.
void pushRange(const World& world, const BodyGrid& grid, std::span<Body> bodies, std::size_t first,
               std::size_t last, StepScratch& scratch, std::span<StepReport> reports,
               std::span<BodyCache> caches);

/// Steps bodies[i] against the level with caches[i] as its cache (see
/// stepBodiesAgainstLevel). Precondition: caches is at least
/// as long as bodies.
void stepRangeAgainstLevel(const World& world, std::span<Body> bodies, std::span<const Vec3> forces,
                           float dt, StepScratch& scratch, std::span<StepReport> reports,
                           std::span<BodyCache> caches);

PlanesCandidate makePlanesCandidate(const World& world, const CandidateTriangle& c,
                                    EllipsoidRadii radii);
/// `toSphere`: (1/radii.xz, 1/radii.y, 1/radii.xz).
ExactCandidate makeExactCandidate(const World& world, const CandidateTriangle& c,
                                  EllipsoidRadii radii, const Vec3& toSphere);

}  // namespace bspf::detail
