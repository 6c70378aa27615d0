// SPDX-License-Identifier: MIT
// The narrow phases' working lists (StepScratch::workspace): each slide's
// candidates with what its tests need precomputed for the body's radii, so
// an iteration reads one short array and takes no square root per
// candidate. Private to the runtime.
#pragma once

#include <bspf/movement.h>
#include <bspf/query.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "narrow_phase.h"

// SSE2 is part of every x86-64 CPU's baseline, so the block tests use it
// without a run-time dispatch; elsewhere (or with BSPF_SCALAR_MASKS defined)
// they run their scalar references.
#if (defined(__SSE2__) || defined(_M_X64) || defined(_M_AMD64)) && !defined(BSPF_SCALAR_MASKS)
#include <emmintrin.h>
#define BSPF_SSE_MASKS 1
#endif

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
struct alignas(16) GrownTriangle {
  /// Plane k (edges 0, 2, 4; caps 1, 3, 5) as normal and offset: inside
  /// when dot(normal, p) >= offset for every k. Lanes 6 and 7 always hold
  /// (zero normal, offset -infinity), so the test takes two groups of 4.
  float normalX[8], normalY[8], normalZ[8], offset[8];
  /// The triangle's highest corner y (highestCornerY), for the rounded
  /// edge test: kept here, it costs one load where reading the triangle's
  /// corners from the level took three scattered ones (the test runs for
  /// most steep candidates a scan finds inside their planes).
  float highestY;

  void set(int k, const Vec3& normal, float planeOffset) {
    normalX[k] = normal.x(), normalY[k] = normal.y(), normalZ[k] = normal.z();
    offset[k] = planeOffset;
  }

  /// Precondition: grown (growPlanes). With SSE, 4 planes per instruction; the same
  /// float operations in the same order as insideOneByOne (the tests
  /// compare them).
  bool inside(const Vec3& p) const {
#ifdef BSPF_SSE_MASKS
    const __m128 x = _mm_set1_ps(p.x()), y = _mm_set1_ps(p.y()), z = _mm_set1_ps(p.z());
    int outside = 0;
    for (int first = 0; first < 8; first += 4) {
      const __m128 d = _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_load_ps(normalX + first), x),
                                             _mm_mul_ps(_mm_load_ps(normalY + first), y)),
                                  _mm_mul_ps(_mm_load_ps(normalZ + first), z));
      outside |= _mm_movemask_ps(_mm_cmplt_ps(d, _mm_load_ps(offset + first)));
    }
    return outside == 0;
#else
    return insideOneByOne(p);
#endif
  }

  /// inside(), a plane at a time: the reference.
  bool insideOneByOne(const Vec3& p) const {
    for (int k = 0; k < 6; ++k)
      if (normalX[k] * p.x() + normalY[k] * p.y() + normalZ[k] * p.z() < offset[k]) return false;
    return true;
  }
};

/// sweptBounds(from, to, radii) for the narrow phases' iterations. With SSE,
/// its operations lane by lane in registers: Eigen's 4-float version went
/// through the stack, and reloading 16 bytes just stored as 12 stalled on
/// failed store forwarding (a quarter of the planes slide's own cycles in
/// perf at 40 m/s). The same values: min, max, abs and the padding's
/// arithmetic in the same order, and no NaN (the step checks its inputs).
inline Bounds slideSweptBounds(const Vec3& from, const Vec3& to, EllipsoidRadii radii) {
#ifdef BSPF_SSE_MASKS
  // A Vec3 is 3 packed floats, loaded one float at a time (the fourth lane
  // zero): the slide has just written `to` a float at a time, and one 8-byte
  // load of x and y spanning two such stores cannot be forwarded from them
  // (it waited for them to reach the cache: 14% of the planes slide's own
  // samples at 6 m/s, perf annotate on walkers, oa_dm5). Stored as x and y
  // in one 8-byte store through memcpy (a Vec3 is only 4-byte aligned, and a
  // double access there is undefined), then z: each later float load is
  // inside one store, which forwards.
  auto load = [](const Vec3& v) { return _mm_setr_ps(v.x(), v.y(), v.z(), 0.0f); };
  auto store = [](__m128 lanes, Vec3& v) {
    const double xy = _mm_cvtsd_f64(_mm_castps_pd(lanes));
    std::memcpy(v.data(), &xy, sizeof xy);
    _mm_store_ss(v.data() + 2, _mm_movehl_ps(lanes, lanes));
  };
  const __m128 f = load(from), t = load(to);
  const __m128 extent = _mm_setr_ps(radii.xz, radii.y, radii.xz, 0.0f);
  __m128 low = _mm_sub_ps(_mm_min_ps(f, t), extent);
  __m128 high = _mm_add_ps(_mm_max_ps(f, t), extent);
  const __m128 signBit = _mm_set1_ps(-0.0f);
  const __m128 largest = _mm_max_ps(_mm_andnot_ps(signBit, low), _mm_andnot_ps(signBit, high));
  const __m128 pad =
      _mm_add_ps(_mm_set1_ps(kSweepMarginMetres), _mm_mul_ps(_mm_set1_ps(4e-7f), largest));
  Bounds bounds;
  store(_mm_sub_ps(low, pad), bounds.low);
  store(_mm_add_ps(high, pad), bounds.high);
  return bounds;
#else
  return sweptBounds(from, to, radii);
#endif
}

/// Fills `grown` for triangle `triangle` and `radii`.
void growPlanes(const World& world, std::uint32_t triangle, EllipsoidRadii radii,
                GrownTriangle& grown);

/// How many candidates a CandidateBlock holds.
inline constexpr int kBlockLanes = 8;

/// What every scan of a slide reads of its candidates, for kBlockLanes of
/// them at once: their boxes and face planes, one array per coordinate.
/// A scan reads these few cache lines and tests a whole block with a few
/// SSE instructions (planesMask and the like); the rest of a candidate
/// (Cold in MadeCandidates) is read only for the few that pass. Unused lanes have an empty box
/// (low +infinity, high -infinity), which no box overlaps.
struct alignas(32) CandidateBlock {
  float lowX[kBlockLanes], lowY[kBlockLanes], lowZ[kBlockLanes];
  float highX[kBlockLanes], highY[kBlockLanes], highZ[kBlockLanes];
  float normalX[kBlockLanes], normalY[kBlockLanes], normalZ[kBlockLanes];
  float distance[kBlockLanes], reach[kBlockLanes];
  /// Index of the candidate in MadeCandidates::cold.
  std::uint32_t slot[kBlockLanes];
  /// The box around every used lane's box (sealBlock): a scan skips a
  /// block whose box misses its own (BlockBoxTest).
  Vec3 low, high;
  /// Read with `high` by BlockBoxTest's four-lane loads, its lane ignored:
  /// set, so that no load reads uninitialised bytes.
  float afterHigh = 0;
};

/// sweptBounds(from, to, radii) grown by `margin` (metres) on every side,
/// the same floats: the box a push's clearance test reads candidates in.
/// With SSE2 in four lanes (x, y, z, z again), the same operations lane by
/// lane (Eigen's took 70 instructions a call; a call a push).
inline Bounds pushBounds(const Vec3& from, const Vec3& to, EllipsoidRadii radii, float margin) {
#ifdef BSPF_SSE_MASKS
  const __m128 a = _mm_setr_ps(from.x(), from.y(), from.z(), from.z()),
               b = _mm_setr_ps(to.x(), to.y(), to.z(), to.z()),
               extent = _mm_setr_ps(radii.xz, radii.y, radii.xz, radii.xz);
  const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
  // min and max may pick the other of two equal values (-0 for +0): minus
  // or plus a radius, the same float.
  __m128 low = _mm_sub_ps(_mm_min_ps(a, b), extent), high = _mm_add_ps(_mm_max_ps(a, b), extent);
  // padBounds' pad: kSweepMarginMetres plus 4e-7 of the larger magnitude.
  const __m128 pad =
      _mm_add_ps(_mm_set1_ps(kSweepMarginMetres),
                 _mm_mul_ps(_mm_set1_ps(4e-7f),
                            _mm_max_ps(_mm_and_ps(low, magnitude), _mm_and_ps(high, magnitude))));
  low = _mm_sub_ps(_mm_sub_ps(low, pad), _mm_set1_ps(margin));
  high = _mm_add_ps(_mm_add_ps(high, pad), _mm_set1_ps(margin));
  alignas(16) float l[4], h[4];
  _mm_store_ps(l, low);
  _mm_store_ps(h, high);
  return {Vec3(l[0], l[1], l[2]), Vec3(h[0], h[1], h[2])};
#else
  Bounds box = sweptBounds(from, to, radii);
  box.low.array() -= margin;
  box.high.array() += margin;
  return box;
#endif
}

/// The test a scan makes of each block before its mask: whether the
/// block's box overlaps `box` (touching counts), as boxesOverlap. With SSE,
/// each box in one four-lane load (a block's low and high are adjacent) and
/// the query's box prepared once a scan: a third of the instructions of six
/// scalar comparisons and their branches, which ran in every mask call
/// (walkers at 40 m/s on oa_dm5: 382,000 mask calls, 39% of them for
/// blocks whose box misses).
class BlockBoxTest {
 public:
  explicit BlockBoxTest(const Bounds& box)
#ifdef BSPF_SSE_MASKS
      : low_(_mm_setr_ps(box.low.x(), box.low.y(), box.low.z(), 0)),
        high_(_mm_setr_ps(box.high.x(), box.high.y(), box.high.z(), 0))
#else
      : box_(box)
#endif
  {
  }
  bool meets(const CandidateBlock& block) const {
#ifdef BSPF_SSE_MASKS
    static_assert(offsetof(CandidateBlock, high) == offsetof(CandidateBlock, low) + 12 &&
                  offsetof(CandidateBlock, afterHigh) == offsetof(CandidateBlock, high) + 12);
    const __m128 low = _mm_loadu_ps(block.low.data()), high = _mm_loadu_ps(block.high.data());
    const __m128 overlap = _mm_and_ps(_mm_cmple_ps(low, high_), _mm_cmple_ps(low_, high));
    return (_mm_movemask_ps(overlap) & 7) == 7;
#else
    return boxesOverlap(block.low, block.high, box_.low, box_.high);
#endif
  }

 private:
#ifdef BSPF_SSE_MASKS
  __m128 low_, high_;
#else
  Bounds box_;
#endif
};

/// Sets `block`'s box from its used lanes. Call once its lanes are written;
/// precondition: each lane is either set (setLane) or cleared
/// (clearLanes), whose empty box (+infinity low, -infinity high) changes no
/// minimum or maximum, so every lane is taken without a test (the loops
/// vectorise; at 40 m/s this ran once per 8 candidates of every query).
inline void sealBlock(CandidateBlock& block) {
#ifdef BSPF_SSE_MASKS
  // The 8 lanes as two groups of 4, folded: 7 instructions an array, where
  // the compiler's vectorisation of the loops below took about 18. The same
  // least and greatest values (no lane is NaN; a zero's sign may differ,
  // which no box comparison sees).
  auto least = [](const float(&lanes)[kBlockLanes]) {
    __m128 m = _mm_min_ps(_mm_load_ps(lanes), _mm_load_ps(lanes + 4));
    m = _mm_min_ps(m, _mm_movehl_ps(m, m));
    return _mm_cvtss_f32(_mm_min_ss(m, _mm_shuffle_ps(m, m, 1)));
  };
  auto most = [](const float(&lanes)[kBlockLanes]) {
    __m128 m = _mm_max_ps(_mm_load_ps(lanes), _mm_load_ps(lanes + 4));
    m = _mm_max_ps(m, _mm_movehl_ps(m, m));
    return _mm_cvtss_f32(_mm_max_ss(m, _mm_shuffle_ps(m, m, 1)));
  };
#else
  auto least = [](const float(&lanes)[kBlockLanes]) {
    float m = lanes[0];
    for (int lane = 1; lane < kBlockLanes; ++lane) m = std::min(m, lanes[lane]);
    return m;
  };
  auto most = [](const float(&lanes)[kBlockLanes]) {
    float m = lanes[0];
    for (int lane = 1; lane < kBlockLanes; ++lane) m = std::max(m, lanes[lane]);
    return m;
  };
#endif
  block.low = Vec3(least(block.lowX), least(block.lowY), least(block.lowZ));
  block.high = Vec3(most(block.highX), most(block.highY), most(block.highZ));
}

/// Writes candidate `slot` (its box and face test) into lane `lane`.
inline void setLane(CandidateBlock& block, int lane, const Vec3& low, const Vec3& high,
                    const FaceTest& face, std::uint32_t slot) {
  block.lowX[lane] = low.x(), block.lowY[lane] = low.y(), block.lowZ[lane] = low.z();
  block.highX[lane] = high.x(), block.highY[lane] = high.y(), block.highZ[lane] = high.z();
  block.normalX[lane] = face.normal.x(), block.normalY[lane] = face.normal.y();
  block.normalZ[lane] = face.normal.z();
  block.distance[lane] = face.distance, block.reach[lane] = face.reach;
  block.slot[lane] = slot;
}

/// Empties lanes [from, kBlockLanes) of `block`.
inline void clearLanes(CandidateBlock& block, int from) {
  for (int lane = from; lane < kBlockLanes; ++lane) {
    // Infinitely inverted: low > high alone is not enough, as [1, -1]
    // would still pass the overlap test against a box holding [-1, 1].
    constexpr float kInfinity = std::numeric_limits<float>::infinity();
    block.lowX[lane] = block.lowY[lane] = block.lowZ[lane] = kInfinity;
    block.highX[lane] = block.highY[lane] = block.highZ[lane] = -kInfinity;
    block.normalX[lane] = block.normalY[lane] = block.normalZ[lane] = 0;
    block.distance[lane] = block.reach[lane] = 0;
    block.slot[lane] = 0;
  }
}

/// The blocks a slide's scans go through, in order, by address (in a
/// MadeCandidates' blocks): valid until those are made again.
using BlockList = std::span<const CandidateBlock* const>;

/// Empties the lanes after the first `count` candidates of `blocks` (laid
/// out in order, kBlockLanes a block) and seals every block (sealBlock).
inline void finishBlocks(std::span<CandidateBlock> blocks, std::size_t count) {
  if (count % kBlockLanes != 0) clearLanes(blocks.back(), int(count % kBlockLanes));
  for (CandidateBlock& block : blocks) sealBlock(block);
}

/// Whether lane `lane`'s box overlaps `box` (touching counts): one lane of
/// boxMask, in the reference's operations.
inline bool laneBoxOverlaps(const CandidateBlock& block, int lane, const Bounds& box) {
  return block.lowX[lane] <= box.high.x() && box.low.x() <= block.highX[lane] &&
         block.lowY[lane] <= box.high.y() && box.low.y() <= block.highY[lane] &&
         block.lowZ[lane] <= box.high.z() && box.low.z() <= block.highZ[lane];
}

/// Lane `lane`'s signed distance, metres, of point `p` to its face plane.
inline float laneSide(const CandidateBlock& block, int lane, const Vec3& p) {
  return block.normalX[lane] * p.x() + block.normalY[lane] * p.y() + block.normalZ[lane] * p.z() -
         block.distance[lane];
}

/// Bit i set when lane i's box overlaps `box` (touching counts). This mask
/// and the two below test every lane, whatever the block's own box: a scan
/// passes over the blocks whose box misses with BlockBoxTest first (in the
/// masks, that test ran again for every block that passed it).
std::uint32_t boxMask(const CandidateBlock& block, const Bounds& box);
/// The side values planesMask computed: lane i's signed distances, metres,
/// of the move's start and end to its face plane. Valid for the lanes whose
/// bit it set (the slide reads them rather than computing them again).
struct alignas(32) LaneSides {
  float start[kBlockLanes], end[kBlockLanes];
};
/// Bit i set when lane i's box overlaps `box` and it passes the planes
/// method's pre-check (passesPreCheck) for the move start -> end; `sides`
/// receives the side values.
std::uint32_t planesMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                         const Vec3& end, LaneSides& sides);
/// Bit i set when lane i's box overlaps `box` and it passes the exact
/// sweep's pre-check for the move start -> end: the path comes within reach
/// of the plane, and starts at most 1e-5 m behind it.
std::uint32_t exactMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                        const Vec3& end);
/// boxMask, planesMask and exactMask as the function they run on this CPU:
/// a scan asks once and calls it for each of its blocks (one call a block,
/// not two: the masks test the CPU, then call the widest path; boxMask's
/// test and switch were half of its 49 instructions a call in the pushes'
/// clearance test).
using BoxMaskFunction = std::uint32_t (*)(const CandidateBlock&, const Bounds&);
using PlanesMaskFunction = std::uint32_t (*)(const CandidateBlock&, const Bounds&, const Vec3&,
                                             const Vec3&, LaneSides&);
using ExactMaskFunction = std::uint32_t (*)(const CandidateBlock&, const Bounds&, const Vec3&,
                                            const Vec3&);
BoxMaskFunction boxMaskFunction();
PlanesMaskFunction planesMaskFunction();
ExactMaskFunction exactMaskFunction();
/// How the three masks above run: a lane at a time, 4 lanes per SSE
/// instruction, or 8 per AVX instruction (where the CPU has AVX: chosen
/// once at run time, so a build for the baseline x86-64 CPU uses it too).
enum class MaskPath { Scalar, Sse, Avx };
/// The paths this build and CPU can run, Scalar first; the masks above use
/// the last.
std::vector<MaskPath> availableMaskPaths();
/// The masks on a given path, for the tests that hold every path to the
/// scalar one. Precondition: `path` is in availableMaskPaths().
std::uint32_t boxMaskOn(MaskPath path, const CandidateBlock& block, const Bounds& box);
std::uint32_t planesMaskOn(MaskPath path, const CandidateBlock& block, const Bounds& box,
                           const Vec3& start, const Vec3& end, LaneSides& sides);
std::uint32_t exactMaskOn(MaskPath path, const CandidateBlock& block, const Bounds& box,
                          const Vec3& start, const Vec3& end);
/// The same three, a lane at a time: what the SSE and AVX versions must
/// match bit for bit (the tests compare them), and what runs on CPUs
/// without SSE.
std::uint32_t scalarBoxMask(const CandidateBlock& block, const Bounds& box);
std::uint32_t scalarPlanesMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                               const Vec3& end, LaneSides& sides);
std::uint32_t scalarExactMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                              const Vec3& end);

/// std::allocator, except that a vector growing by resize() default-initialises
/// its new elements instead of value-initialising them: plain numbers and
/// CandidateBlocks are left unwritten rather than zeroed. For the lists a
/// remake writes in full after resizing them: zeroing them first (memset of
/// every new block and 160-byte PlanesCold) took 2% of a 40 m/s step.
template <typename T>
struct UnzeroedAllocator : std::allocator<T> {
  template <typename U>
  struct rebind {
    using other = UnzeroedAllocator<U>;
  };
  UnzeroedAllocator() = default;
  template <typename U>
  UnzeroedAllocator(const UnzeroedAllocator<U>&) noexcept {}
  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
  }
};
/// A vector whose resize() leaves new elements default-initialised
/// (UnzeroedAllocator).
template <typename T>
using UnzeroedVector = std::vector<T, UnzeroedAllocator<T>>;

/// Makes `list` `count` long for a caller that rewrites (or treats as
/// stale) every element: when it must grow past its capacity, the old
/// elements are dropped rather than moved to the new storage (a body's
/// candidates, 160 to 264 bytes each, were copied over only to be
/// overwritten).
template <typename T>
void resizeForRewrite(UnzeroedVector<T>& list, std::size_t count) {
  if (count > list.capacity()) {
    list.clear();
    list.reserve(std::max(count, 2 * list.capacity()));
  }
  list.resize(count);
}

/// A triangle as the planes method tests it for one body, beyond its
/// CandidateBlock lane: the triangle and its planes, grown on first use in
/// MadeCandidates::generation `grownIn` and stale in any other. Making the
/// candidates writes none of these entries (160 bytes apart, most never
/// grown): resetting each then was 4% of the planes slide's samples at
/// 40 m/s in perf.
struct PlanesCold {
  /// The planes method takes, of the candidates that block, the one facing
  /// the move most, ties to the lower triangle: the order it tests them in
  /// changes nothing, so they stay in the query's order (sorting them took
  /// 4% of a 40 m/s step).
  static constexpr bool kInTriangleOrder = false;
  std::uint32_t triangle;
  /// 0, the generation no candidates are made in, until first grown: a
  /// new entry (UnzeroedVector default-initialises it) is stale.
  std::uint64_t grownIn = 0;
  GrownTriangle grown;
};

/// A triangle as the exact sweep tests it for one body, beyond its
/// CandidateBlock lane: in sphere space (in double: its float corners and
/// normal exactly), made on first use.
struct ExactCold {
  /// Made on first use in a making (MadeCandidates::generation), like
  /// PlanesCold: most of a list's entries (264 bytes apart) are never used.
  static constexpr bool kInTriangleOrder = true;
  std::uint32_t triangle;
  /// The generation `sphere` and `measured` belong to; 0 (no making's) until
  /// first made, so a new entry (default-initialised) is stale.
  std::uint64_t madeIn = 0;
  TriangleD sphere;
  /// The face stage's last distance from the body to it (kept over frames,
  /// while the candidates last).
  MeasuredDistance measured;
};

/// A body's nearby triangles made into one narrow phase's candidates: in
/// triangle order, lane by lane through `blocks`, and `cold[slot]`.
template <typename Cold>
struct MadeCandidates {
  UnzeroedVector<CandidateBlock> blocks;
  UnzeroedVector<Cold> cold;
  /// cold[i].triangle, packed: searched for a triangle without touching
  /// the larger cold entries.
  UnzeroedVector<std::uint32_t> triangles;
  /// The slots found for the last triangles looked up (LocalCandidates::
  /// laneOf), by triangle % 4: a body asks for the same few (its touched
  /// triangles) every step. kNotListed: not a candidate. Cleared when made.
  static constexpr std::uint32_t kNotListed = ~std::uint32_t(0);
  std::array<std::pair<std::uint32_t, std::uint32_t>, 4> lookups{{{kNotListed, kNotListed},
                                                                  {kNotListed, kNotListed},
                                                                  {kNotListed, kNotListed},
                                                                  {kNotListed, kNotListed}}};
  /// NearbyTriangles::queryId() of the query they were made from; 0: none.
  std::uint64_t query = 0;
  /// How many times they were made (from 1 on): a Cold entry not reset
  /// when made (PlanesCold) names the making it belongs to.
  std::uint64_t generation = 0;
  EllipsoidRadii radii{0, 0};  ///< they were made for

  /// Whether they are `nearby`'s current list, made for `bodyRadii`.
  bool madeFrom(const NearbyTriangles& nearby, EllipsoidRadii bodyRadii) const {
    return query == nearby.queryId() && radii.xz == bodyRadii.xz && radii.y == bodyRadii.y;
  }
};

/// What one body keeps from frame to frame: its tree query and the
/// candidates made from it.
struct BodyCache {
  NearbyTriangles nearby;
  MadeCandidates<PlanesCold> planes;
  MadeCandidates<ExactCold> exact;
};

struct StepWorkspace {
  /// The candidates of a body stepped with the scratch's own cache (no
  /// BodyCache in use), made from StepScratch::nearby.
  MadeCandidates<PlanesCold> planes;
  MadeCandidates<ExactCold> exact;
  /// The body cache in use (swapBodyCache), or null for the scratch's own.
  BodyCache* active = nullptr;
  /// The current slide's candidates: the blocks of planes or exact whose box
  /// overlaps the slide's local box, by address (copying the 416-byte blocks
  /// took 5% of a 40 m/s step).
  UnzeroedVector<const CandidateBlock*> listed;
  /// The nearby triangles sorted by triangle, while making candidates:
  /// triangle << 32 | the triangle's place in NearbyTriangles::list().
  UnzeroedVector<std::uint64_t> sorted;
  /// The exact sweep's candidates whose edges an iteration may still test:
  /// (the earliest time their face stage allows, slot).
  std::vector<std::pair<double, std::uint32_t>> open;
  /// The last slide's list (diagnostics: StepScratch::lastSlideCandidates):
  /// its blocks, valid until the next slide, their lanes in use, and the
  /// local box they were listed for.
  BlockList lastBlocks;
  std::size_t lastScanned = 0;
  Bounds lastLocal;
  /// Each body's cache, by index in the bodies stepBodies (or
  /// stepBodiesAgainstLevel) steps, so each body reuses its own query and
  /// candidates over frames.
  std::vector<BodyCache> bodies;
  /// Whether the scratch's bodyGrid holds the current frame's grid (the
  /// pool's stepBodies: set by the thread that builds it, cleared by the
  /// caller before the body phase).
  bool gridBuilt = false;
};

/// Makes `cache` the one the narrow phases use in `scratch` (its nearby
/// triangles and the candidates made from them), in place of the scratch's
/// own: call once to step a body with its own cache, again to go back. A
/// pointer, not a swap of the containers: it runs twice per body per phase.
inline void swapBodyCache(StepScratch& scratch, BodyCache& cache) {
  StepWorkspace& workspace = scratch.workspace();
  workspace.active = workspace.active == &cache ? nullptr : &cache;
}

/// The nearby triangles and the candidates the narrow phases use now.
inline NearbyTriangles& activeNearby(StepScratch& scratch) {
  StepWorkspace& workspace = scratch.workspace();
  return workspace.active ? workspace.active->nearby : scratch.nearby;
}
inline MadeCandidates<PlanesCold>& activePlanes(StepWorkspace& workspace) {
  return workspace.active ? workspace.active->planes : workspace.planes;
}
inline MadeCandidates<ExactCold>& activeExact(StepWorkspace& workspace) {
  return workspace.active ? workspace.active->exact : workspace.exact;
}

/// pushBodiesApart with caches[i] as body i's cache. Precondition: caches
/// is as long as bodies.
void pushRange(const World& world, const BodyGrid& grid, std::span<Body> bodies, std::size_t first,
               std::size_t last, StepScratch& scratch, std::span<StepReport> reports,
               std::span<BodyCache> caches);

/// Steps bodies[i] against the level with caches[i] as its cache (see
/// stepBodiesAgainstLevel); returns how many bodies it did not move for
/// invalid input. Precondition: caches is at least as long as bodies.
std::size_t stepRangeAgainstLevel(const World& world, std::span<Body> bodies,
                                  std::span<const Vec3> forces, float dt, StepScratch& scratch,
                                  std::span<StepReport> reports, std::span<BodyCache> caches);

/// stepBody, returning why the body was not moved (None: it was).
InvalidInput stepOne(const World& world, Body& body, const Vec3& force, float dt,
                     StepScratch& scratch, StepReport* report);

/// The planes method's pre-check values of triangle `triangle` for `radii`:
/// its face plane and the body's extent along it. Inline: a push's
/// clearance test runs it for every triangle near the push.
inline FaceTest planesFaceTest(const World& world, std::uint32_t triangle, EllipsoidRadii radii) {
  const schema::Plane& face = world.trianglePlanes()[triangle].face();
  const Vec3 normal = toVec3(face.normal());
  return {normal, face.distance(), effectiveRadius(normal, radii)};
}
/// The exact sweep's: its reach padded for float rounding.
FaceTest exactFaceTest(const World& world, std::uint32_t triangle, EllipsoidRadii radii);

}  // namespace bspf::detail
