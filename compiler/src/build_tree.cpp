// SPDX-License-Identifier: MIT
#include <bspc/build_tree.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
// The SSE2 paths below have portable twins that give the same trees (every
// CPU without SSE2 takes them). BSPC_PORTABLE_ONLY builds the twins on
// x86-64 too, so scripts/test.sh can check that both give the same blobs.
#if defined(__SSE2__) && !defined(BSPC_PORTABLE_ONLY)
#define BSPC_SSE2 1
#include <emmintrin.h>
#endif
#include <string>
#include <type_traits>
#include <utility>

#include "parallel.h"

namespace bspc {

namespace {

// A candidate split as the blob will store it: float, so the build classifies
// triangles against exactly the plane the runtime reads.
struct Split {
  Eigen::Vector3f normal;
  float distance;
};

// The axis-aligned box around a node's cell (conservative for oblique splits).
struct Box {
  Eigen::Vector3d low, high;

  // The boxes around the parts of this box in front of and behind a plane,
  // from one evaluation of the corners' signed distances (a distance from
  // the back is the front's negated, exactly).
  std::pair<Box, Box> clippedBoth(const Split& split) const {
    const Eigen::Vector3d n = split.normal.cast<double>();
    for (int axis = 0; axis < 3; ++axis)
      if (std::abs(n[axis]) == 1.0 && n[(axis + 1) % 3] == 0.0 && n[(axis + 2) % 3] == 0.0)
        return {clippedOnAxis(axis, n[axis], split.distance, 1.0),
                clippedOnAxis(axis, n[axis], split.distance, -1.0)};
    // Corner i: bit k set, the high end on axis k.
    double along[8];
    for (int i = 0; i < 8; ++i) {
      const Eigen::Vector3d corner(i & 1 ? high.x() : low.x(), i & 2 ? high.y() : low.y(),
                                   i & 4 ? high.z() : low.z());
      along[i] = n.dot(corner) - split.distance;
    }
    // Bit i: corner i is on that side (at distance 0, on both).
    unsigned sideCorners[2] = {0, 0};
    for (int i = 0; i < 8; ++i) {
      sideCorners[0] |= unsigned(along[i] >= 0) << i;
      sideCorners[1] |= unsigned(along[i] <= 0) << i;
    }
    // The corners on an axis's low face (the axis's bit clear).
    static constexpr unsigned kLowFace[3] = {0x55, 0x33, 0x0F};
    double lo[2][3], hi[2][3];
    for (int keep = 0; keep < 2; ++keep) {
      const unsigned kept = sideCorners[keep];
      if (!kept) continue;
      for (int axis = 0; axis < 3; ++axis) {
        // A side's corners, taken in order into a running min and max (the
        // first of equal values stays: the sign of a zero can tell them
        // apart), come to at most two values an axis, low's and high's.
        const bool atLow = kept & kLowFace[axis], atHigh = kept & ~kLowFace[axis];
        if (atLow && atHigh) {
          const bool highFirst = (unsigned(std::countr_zero(kept)) >> axis) & 1;
          const double first = highFirst ? high[axis] : low[axis],
                       second = highFirst ? low[axis] : high[axis];
          lo[keep][axis] = std::min(first, second);
          hi[keep][axis] = std::max(first, second);
        } else {
          lo[keep][axis] = hi[keep][axis] = atLow ? low[axis] : high[axis];
        }
      }
    }
    // A crossing moves only along its edge's axis, and its other
    // coordinates are those of its edge's corner on that side: only the
    // axis's bounds can change. An edge crossing the plane with a corner on
    // each side (the usual case) crosses it at the same point for both: the
    // back's -a / (-a - -b) is a / (a - b) to the bit, as IEEE negation and
    // subtraction are exact mirror images. An edge with a corner at
    // distance 0 crosses for one side only, which takes its own side's
    // arithmetic (its sign of zero). Each axis's edges in order of their
    // low corner, as the sides' running min and max took them.
    const auto addCrossing = [&](int keep, int axis, double at) {
      lo[keep][axis] = std::min(lo[keep][axis], at);
      hi[keep][axis] = std::max(hi[keep][axis], at);
    };
    for (int axis = 0; axis < 3; ++axis) {
      const int bit = 1 << axis;
      const unsigned frontCrossing = (sideCorners[0] ^ (sideCorners[0] >> bit)) & kLowFace[axis];
      const unsigned backCrossing = (sideCorners[1] ^ (sideCorners[1] >> bit)) & kLowFace[axis];
      const double span = high[axis] - low[axis];
      for (unsigned edges = frontCrossing | backCrossing; edges; edges &= edges - 1) {
        const int i = std::countr_zero(edges), j = i | bit;
        const unsigned edge = 1u << i;
        if (frontCrossing & backCrossing & edge) {
          const double at = low[axis] + along[i] / (along[i] - along[j]) * span;
          addCrossing(0, axis, at);
          addCrossing(1, axis, at);
        } else if (frontCrossing & edge) {
          addCrossing(0, axis, low[axis] + along[i] / (along[i] - along[j]) * span);
        } else {
          const double sideI = -along[i], sideJ = -along[j];
          addCrossing(1, axis, low[axis] + sideI / (sideI - sideJ) * span);
        }
      }
    }
    Box boxes[2];
    for (int keep = 0; keep < 2; ++keep) {
      if (sideCorners[keep])
        boxes[keep] = {Eigen::Vector3d(lo[keep][0], lo[keep][1], lo[keep][2]),
                       Eigen::Vector3d(hi[keep][0], hi[keep][1], hi[keep][2])};
      else
        boxes[keep] = {low, low};  // nothing on that side
    }
    return {boxes[0], boxes[1]};
  }

  // clippedBoth's box on one side (`sign` +1 front, -1 back) for a normal along `axis` (`direction`
  // +1 or -1): the general case's arithmetic on the one edge direction that can cross the plane, so
  // the same box to the bit. The corners' other coordinates are exact.
  Box clippedOnAxis(int axis, double direction, double distance, double sign) const {
    const double sideLow = sign * (direction * low[axis] - distance);
    const double sideHigh = sign * (direction * high[axis] - distance);
    const bool keepLow = sideLow >= 0, keepHigh = sideHigh >= 0;
    if (!keepLow && !keepHigh) return {low, low};
    if (keepLow && keepHigh) return {low, high};
    const double t = sideLow / (sideLow - sideHigh);
    const double crossing = low[axis] + t * (high[axis] - low[axis]);
    const double kept = keepLow ? low[axis] : high[axis];
    Box box{low, high};
    box.low[axis] = std::min(kept, crossing);
    box.high[axis] = std::max(kept, crossing);
    return box;
  }

  // How likely a query of the given reach overlaps the box, up to a constant:
  // the volume of the box grown by the reach on every side.
  double reachVolume(double reach) const {
    const Eigen::Vector3d size = (high - low).array() + 2 * reach;
    return size.x() * size.y() * size.z();
  }
};

enum Side : std::uint8_t { kFront = 1, kBack = 2, kBoth = kFront | kBack };

// How far, metres, a corner may sit off a plane and still count as on it.
// Grows with the plane's offset, as float rounding of the plane does.
double onPlaneTolerance(const Split& split) { return 1e-5 + 2e-7 * std::abs(split.distance); }

// Leaves its elements uninitialized on resize: partition sizes its lists
// and then writes every entry, so zeroing them first was wasted work.
template <class T>
struct UninitializedAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = UninitializedAllocator<U>;
  };
  UninitializedAllocator() = default;
  template <class U>
  UninitializedAllocator(const UninitializedAllocator<U>&) noexcept {}
  template <class U>
  void construct(U* at) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(at)) U;
  }
  template <class U, class... Args>
  void construct(U* at, Args&&... args) {
    ::new (static_cast<void*>(at)) U(std::forward<Args>(args)...);
  }
};

// Triangle indices.
using IndexList = std::vector<std::uint32_t, UninitializedAllocator<std::uint32_t>>;

// A node's triangles: in the order the node was given them, and, when axis
// candidates are wanted, sorted by centroid along each axis (sorted once, at
// the root; a child's lists are its parent's filtered, which keeps them
// sorted), so a quantile is a look-up.
struct Lists {
  IndexList order;
  IndexList byAxis[3];
  std::size_t size() const { return order.size(); }
};

// Small lists a subtree's nodes are done with, kept for the next nodes'
// lists: a node's partition made and freed up to eight, most of them small,
// and the allocator's calls were a twentieth of the tree's instructions.
// Bounded, so a large level's subtrees keep no more than they did.
class SpareLists {
 public:
  // An empty list, with room when one is kept.
  IndexList take() {
    if (kept_.empty()) return {};
    IndexList list = std::move(kept_.back());
    kept_.pop_back();
    return list;
  }
  // `list` kept if small and room remains; freed otherwise.
  void give(IndexList&& list) {
    if (list.capacity() == 0) return;
    if (list.capacity() > kLargest || kept_.size() >= kMostKept) {
      IndexList().swap(list);
      return;
    }
    list.clear();
    kept_.push_back(std::move(list));
  }

 private:
  static constexpr std::size_t kLargest = 4096, kMostKept = 64;
  std::vector<IndexList> kept_;
};

// A node's per-triangle passes (gathering its columns, classifying and
// sharing out its lists) run on a pool's threads above this many triangles,
// in ranges of kParallelRange (a multiple of four): below it, waking the
// threads costs more than they save.
constexpr std::size_t kParallelAbove = 4096;
constexpr std::size_t kParallelRange = 1024;

// A face normal rounded to float, padded to four floats: the columns take
// it with one load, not a conversion at every node.
using FloatNormal = std::array<float, 4>;

// The node's triangles as columns of floats, for the split search: the
// corners (relative to `origin`, near the node, so that float keeps them to
// a small fraction of the on-plane tolerance), the face normal, and each
// axis's lowest and highest corner. A candidate is then counted in one pass
// over contiguous memory, four triangles at a time. The counts only guide
// the choice of a split; partition classifies from them only the triangles
// whose float distances are further from every threshold than float's
// error can reach (so exactly as in double), and the others in double,
// from the mesh. A split that leaves every triangle on one side is refused
// (buildNode). Float halves the memory the counting reads and doubles the
// triangles an SSE instruction takes.
struct Columns {
  std::vector<float> corner[3][3];  // [corner][axis]
  std::vector<float> normal[3];
  std::vector<float> low[3], high[3];
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  std::size_t size = 0;
  // size rounded up to four: the lanes past the triangles hold NaN, which
  // every comparison of the tally finds false, so a padded lane counts on
  // no side and four at a time needs no one-by-one tail.
  std::size_t padded = 0;

  // With a pool, a large node's columns are filled on all its threads, in
  // ranges of whole fours: each triangle's floats are the same either way.
  void gather(const IndexList& triangles, const Mesh& mesh,
              const std::vector<FloatNormal>& faceNormals, const Eigen::Vector3d& near,
              bspf::ThreadPool* pool = nullptr) {
    size = triangles.size();
    padded = (size + 3) & ~std::size_t(3);
    origin = near;
    // Only grown: a node smaller than an earlier one reuses the columns as they are.
    if (normal[0].size() < padded) {
      for (auto& c : corner)
        for (auto& axis : c) axis.resize(padded);
      for (int axis = 0; axis < 3; ++axis) {
        normal[axis].resize(padded);
        low[axis].resize(padded);
        high[axis].resize(padded);
      }
    }
    if (pool && size > kParallelAbove)
      runParallel(pool, size, kParallelRange, [&](int, std::size_t first, std::size_t last) {
        fill(triangles, mesh, faceNormals, first, last);
      });
    else
      fill(triangles, mesh, faceNormals, 0, size);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (int axis = 0; axis < 3; ++axis) {
      for (std::size_t i = size; i < padded; ++i) {
        for (int k = 0; k < 3; ++k) corner[k][axis][i] = nan;
        normal[axis][i] = nan;
        low[axis][i] = nan;
        high[axis][i] = nan;
      }
    }
  }

 private:
  // Columns [first, last) from triangles[first, last); `first` a multiple of four.
  void fill(const IndexList& triangles, const Mesh& mesh,
            const std::vector<FloatNormal>& faceNormals, std::size_t first, std::size_t last) {
    float* cornerOut[3][3];
    float *normalOut[3], *lowOut[3], *highOut[3];
    for (int axis = 0; axis < 3; ++axis) {
      for (int k = 0; k < 3; ++k) cornerOut[k][axis] = corner[k][axis].data();
      normalOut[axis] = normal[axis].data();
      lowOut[axis] = low[axis].data();
      highOut[axis] = high[axis].data();
    }
    const double originAt[3] = {origin.x(), origin.y(), origin.z()};
    std::size_t i = first;
#ifdef BSPC_SSE2
    // Four triangles at a time: each point (x, y, z) converted as one
    // vector, four of them turned into columns by a transpose. The same
    // floats: the same double subtraction and rounding, and
    // _mm_min_ps(b, a) is std::min(a, b) to the bit (so is max).
    const __m128d originXy = _mm_loadu_pd(originAt), originZ = _mm_load_sd(originAt + 2);
    const auto point = [&](const double* at) {
      return _mm_movelh_ps(_mm_cvtpd_ps(_mm_sub_pd(_mm_loadu_pd(at), originXy)),
                           _mm_cvtpd_ps(_mm_sub_sd(_mm_load_sd(at + 2), originZ)));
    };
    // One column each of x, y and z for four points (x, y, z) of four
    // triangles; ((x, y, z, 0) rows turned into columns, the fourth dropped).
    const auto columnsOf = [&](const double* p0, const double* p1, const double* p2,
                               const double* p3, __m128 out[3]) {
      __m128 r0 = point(p0), r1 = point(p1), r2 = point(p2), r3 = point(p3);
      _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
      out[0] = r0;
      out[1] = r1;
      out[2] = r2;
    };
    for (; i + 4 <= last; i += 4) {
      const std::uint32_t t0 = triangles[i], t1 = triangles[i + 1], t2 = triangles[i + 2],
                          t3 = triangles[i + 3];
      const std::array<std::uint32_t, 3>&c0 = mesh.triangles[t0], &c1 = mesh.triangles[t1],
                                      &c2 = mesh.triangles[t2], &c3 = mesh.triangles[t3];
      __m128 a[3], b[3], c[3], facing[3];
      const auto vertex = [&](std::uint32_t v) { return mesh.vertices[v].data(); };
      columnsOf(vertex(c0[0]), vertex(c1[0]), vertex(c2[0]), vertex(c3[0]), a);
      columnsOf(vertex(c0[1]), vertex(c1[1]), vertex(c2[1]), vertex(c3[1]), b);
      columnsOf(vertex(c0[2]), vertex(c1[2]), vertex(c2[2]), vertex(c3[2]), c);
      __m128 n0 = _mm_loadu_ps(faceNormals[t0].data()), n1 = _mm_loadu_ps(faceNormals[t1].data()),
             n2 = _mm_loadu_ps(faceNormals[t2].data()), n3 = _mm_loadu_ps(faceNormals[t3].data());
      _MM_TRANSPOSE4_PS(n0, n1, n2, n3);
      facing[0] = n0;
      facing[1] = n1;
      facing[2] = n2;
      for (int axis = 0; axis < 3; ++axis) {
        _mm_storeu_ps(cornerOut[0][axis] + i, a[axis]);
        _mm_storeu_ps(cornerOut[1][axis] + i, b[axis]);
        _mm_storeu_ps(cornerOut[2][axis] + i, c[axis]);
        _mm_storeu_ps(normalOut[axis] + i, facing[axis]);
        _mm_storeu_ps(lowOut[axis] + i, _mm_min_ps(c[axis], _mm_min_ps(b[axis], a[axis])));
        _mm_storeu_ps(highOut[axis] + i, _mm_max_ps(c[axis], _mm_max_ps(b[axis], a[axis])));
      }
    }
#endif
    for (; i < last; ++i) {
      const std::uint32_t t = triangles[i];
      const std::array<std::uint32_t, 3>& corners = mesh.triangles[t];
      const double* at[3] = {mesh.vertices[corners[0]].data(), mesh.vertices[corners[1]].data(),
                             mesh.vertices[corners[2]].data()};
      const float* facing = faceNormals[t].data();
      const auto fillAxis = [&](int axis) {
        const auto a = static_cast<float>(at[0][axis] - originAt[axis]);
        const auto b = static_cast<float>(at[1][axis] - originAt[axis]);
        const auto c = static_cast<float>(at[2][axis] - originAt[axis]);
        cornerOut[0][axis][i] = a;
        cornerOut[1][axis][i] = b;
        cornerOut[2][axis][i] = c;
        normalOut[axis][i] = facing[axis];
        lowOut[axis][i] = std::min(std::min(a, b), c);
        highOut[axis][i] = std::max(std::max(a, b), c);
      };
      fillAxis(0);
      fillAxis(1);
      fillAxis(2);
    }
  }
};

// The triangles a split sends to the front only, the back only and both.
struct Counts {
  std::size_t front = 0, back = 0, both = 0;
  // Tallies partition's rule from a triangle's lowest and highest signed
  // distance and, for one lying in the plane, the side its normal faces.
  void add(float lowest, float highest, float facing, float tolerance) {
    const bool inPlane = highest <= tolerance && lowest >= -tolerance;
    const bool reachesFront = inPlane ? facing >= 0 : highest > -tolerance;
    const bool reachesBack = inPlane ? facing < 0 : lowest < tolerance;
    front += reachesFront & !reachesBack;
    back += reachesBack & !reachesFront;
    both += reachesFront & reachesBack;
  }
  Counts operator+(const Counts& other) const {
    return {front + other.front, back + other.back, both + other.both};
  }
};

#ifdef BSPC_SSE2
// Counts::add on four triangles at once: the same decisions, lane by lane.
struct TallySse2 {
  __m128 above, below, zero = _mm_setzero_ps();
  // Minus the lanes reaching the front (16-bit lanes 0 to 3) and the back
  // (4 to 7): one accumulator, one addition a four. 16 bits hold the count
  // of a block (TreeBuilder::kBlock, a few hundred triangles), the most
  // that one tally is given.
  __m128i negatedReached = _mm_setzero_si128();
  explicit TallySse2(float tolerance)
      : above(_mm_set1_ps(tolerance)), below(_mm_set1_ps(-tolerance)) {}
  // A four's lanes that reach each side, as masks.
  struct Reach {
    __m128 inPlane, front, back;
  };
  // `facing()` gives the lanes' facings; it is called only when a lane
  // lies in the plane, which few do (for most four, the side follows from
  // the distances alone).
  template <class Facing>
  void add(__m128 lowest, __m128 highest, const Facing& facing) {
    Reach reach = byDistance(lowest, highest);
    if (_mm_movemask_ps(reach.inPlane)) byFacing(reach, facing());
    count(reach);
  }
  // add() on two fours, with one test for a lane in the plane; `facing(k)`
  // gives four k's facings.
  template <class Facing>
  void addTwo(__m128 lowest0, __m128 highest0, __m128 lowest1, __m128 highest1,
              const Facing& facing) {
    Reach first = byDistance(lowest0, highest0), second = byDistance(lowest1, highest1);
    if (_mm_movemask_ps(_mm_or_ps(first.inPlane, second.inPlane))) {
      byFacing(first, facing(0));
      byFacing(second, facing(1));
    }
    count(first);
    count(second);
  }

 private:
  Reach byDistance(__m128 lowest, __m128 highest) const {
    return {_mm_and_ps(_mm_cmple_ps(highest, above), _mm_cmpge_ps(lowest, below)),
            _mm_cmpgt_ps(highest, below), _mm_cmplt_ps(lowest, above)};
  }
  // The lanes in the plane reach the side they face (none in it: unchanged).
  void byFacing(Reach& reach, __m128 facing) const {
    const __m128 facesFront = _mm_cmpge_ps(facing, zero);
    reach.front =
        _mm_or_ps(_mm_and_ps(reach.inPlane, facesFront), _mm_andnot_ps(reach.inPlane, reach.front));
    reach.back = _mm_or_ps(_mm_andnot_ps(facesFront, reach.inPlane),
                           _mm_andnot_ps(reach.inPlane, reach.back));
  }
  void count(const Reach& reach) {
    // A mask lane is all ones, -1 as an integer (packed, still -1): adding
    // counts it, negated. All that reach each side are counted; counts()
    // finds those reaching both from them.
    negatedReached = _mm_add_epi16(negatedReached, _mm_packs_epi32(_mm_castps_si128(reach.front),
                                                                   _mm_castps_si128(reach.back)));
  }

 public:
  // `triangles`: the lanes added that hold a triangle (not padding). Each
  // reaches a side: out of the plane its highest distance is above the
  // tolerance (so above minus it) or its lowest below minus the tolerance,
  // and in it its facing, a finite number, is >= 0 or not. (A NaN
  // coordinate would break this and skew the counts, which only guide the
  // choice: partition decides the lists.) So the triangles reaching both
  // sides are those counted twice.
  Counts counts(std::size_t triangles) const {
    // Both sides' sums at once: adjacent lanes added into 32 bits, (f0 +
    // f1, f2 + f3, b0 + b1, b2 + b3), then each side's two.
    const __m128i pairs = _mm_madd_epi16(negatedReached, _mm_set1_epi16(-1));
    const __m128i totals = _mm_add_epi32(pairs, _mm_shuffle_epi32(pairs, _MM_SHUFFLE(2, 3, 0, 1)));
    const std::size_t reachFront = static_cast<std::uint32_t>(_mm_cvtsi128_si32(totals));
    const std::size_t reachBack =
        static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_shuffle_epi32(totals, 2)));
    const std::size_t inBoth = reachFront + reachBack - triangles;
    return {reachFront - inBoth, reachBack - inBoth, inBoth};
  }
};
#endif

// partition's rule, counted, for triangles [begin, end) of `c` against an
// axis-aligned split (normal the axis, or its opposite when `flipped`;
// `distance` from the columns' origin): the normal's dot product with a
// corner is the corner's coordinate (negated), so the lowest signed distance
// is the lowest coordinate (the highest, negated) less the distance.
Counts countAxisSplit(const Columns& c, std::size_t begin, std::size_t end, int axis, bool flipped,
                      float distance, float tolerance) {
  const float *low = c.low[axis].data(), *high = c.high[axis].data(),
              *normal = c.normal[axis].data();
  if (flipped) std::swap(low, high);
  const float sign = flipped ? -1.0f : 1.0f;
  std::size_t i = begin;
  Counts counts;
#ifdef BSPC_SSE2
  TallySse2 lanes(tolerance);
  const __m128 vd = _mm_set1_ps(distance);
  if (flipped) {
    // Negation flips the sign bit, exactly.
    const __m128 flip = _mm_set1_ps(-0.0f);
    for (; i + 4 <= end; i += 4)
      lanes.add(_mm_sub_ps(_mm_xor_ps(_mm_loadu_ps(low + i), flip), vd),
                _mm_sub_ps(_mm_xor_ps(_mm_loadu_ps(high + i), flip), vd),
                [&] { return _mm_xor_ps(_mm_loadu_ps(normal + i), flip); });
  } else {
    // The axis quantiles: most of the axis candidates.
    // Eight a step: half the loop's own instructions and tests for a lane
    // in the plane.
    for (; i + 8 <= end; i += 8)
      lanes.addTwo(_mm_sub_ps(_mm_loadu_ps(low + i), vd), _mm_sub_ps(_mm_loadu_ps(high + i), vd),
                   _mm_sub_ps(_mm_loadu_ps(low + i + 4), vd),
                   _mm_sub_ps(_mm_loadu_ps(high + i + 4), vd),
                   [&](int four) { return _mm_loadu_ps(normal + i + 4 * std::size_t(four)); });
    for (; i + 4 <= end; i += 4)
      lanes.add(_mm_sub_ps(_mm_loadu_ps(low + i), vd), _mm_sub_ps(_mm_loadu_ps(high + i), vd),
                [&] { return _mm_loadu_ps(normal + i); });
  }
  counts = lanes.counts(std::min(i, c.size) - std::min(begin, c.size));
#endif
  Counts tail;
  for (; i < end; ++i)
    tail.add(sign * low[i] - distance, sign * high[i] - distance, sign * normal[i], tolerance);
  return counts + tail;
}

// partition's rule, counted, for triangles [begin, end) of `c` against any
// split (`distance` from the columns' origin). Four at a time with SSE2
// where there is SSE2.
Counts countSplit(const Columns& c, std::size_t begin, std::size_t end, const Eigen::Vector3f& n,
                  float distance, float tolerance) {
  const float nx = n.x(), ny = n.y(), nz = n.z();
  std::size_t i = begin;
  Counts counts;
#ifdef BSPC_SSE2
  const __m128 vx = _mm_set1_ps(nx), vy = _mm_set1_ps(ny), vz = _mm_set1_ps(nz),
               vd = _mm_set1_ps(distance);
  TallySse2 lanes(tolerance);
  const auto along = [&](int k, std::size_t j) {
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(vx, _mm_loadu_ps(&c.corner[k][0][j])),
                                 _mm_mul_ps(vy, _mm_loadu_ps(&c.corner[k][1][j]))),
                      _mm_mul_ps(vz, _mm_loadu_ps(&c.corner[k][2][j])));
  };
  const auto facing = [&](std::size_t j) {
    return _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(&c.normal[0][j]), vx),
                                 _mm_mul_ps(_mm_loadu_ps(&c.normal[1][j]), vy)),
                      _mm_mul_ps(_mm_loadu_ps(&c.normal[2][j]), vz));
  };
  // The offset subtracted after the lowest and highest are found: float
  // subtraction is monotonic, so they are those of the differences. (Eight
  // a step, as in countAxisSplit, saved next to nothing here.)
  for (; i + 4 <= end; i += 4) {
    const __m128 s0 = along(0, i), s1 = along(1, i), s2 = along(2, i);
    lanes.add(_mm_sub_ps(_mm_min_ps(_mm_min_ps(s0, s1), s2), vd),
              _mm_sub_ps(_mm_max_ps(_mm_max_ps(s0, s1), s2), vd), [&] { return facing(i); });
  }
  counts = lanes.counts(std::min(i, c.size) - std::min(begin, c.size));
#endif
  Counts tail;
  for (; i < end; ++i) {
    float lowest = std::numeric_limits<float>::infinity();
    float highest = -lowest;
    for (int k = 0; k < 3; ++k) {
      const float s =
          (nx * c.corner[k][0][i] + ny * c.corner[k][1][i]) + nz * c.corner[k][2][i] - distance;
      lowest = std::min(lowest, s);
      highest = std::max(highest, s);
    }
    const float facing = (c.normal[0][i] * nx + c.normal[1][i] * ny) + c.normal[2][i] * nz;
    tail.add(lowest, highest, facing, tolerance);
  }
  return counts + tail;
}

// Appends the subtree `part` (its own numbering, root `root`) to `tree`;
// returns the root's reference in `tree`. Appended right after its parent's
// earlier subtrees, it lands where a build on one thread puts it.
std::int32_t appendSubtree(BspTree& tree, const BspTree& part, std::int32_t root) {
  const auto nodeOffset = static_cast<std::int32_t>(tree.nodes.size());
  const auto leafOffset = static_cast<std::int32_t>(tree.leaves.size());
  const auto entryOffset = static_cast<std::uint32_t>(tree.leafTriangles.size());
  const auto moved = [&](std::int32_t child) {
    return child >= 0 ? child + nodeOffset : child - leafOffset;
  };
  for (const bspf::schema::Node& node : part.nodes)
    tree.nodes.emplace_back(node.split(), moved(node.front()), moved(node.back()));
  for (const bspf::schema::Leaf& leaf : part.leaves)
    tree.leaves.emplace_back(leaf.first() + entryOffset, leaf.count());
  tree.leafTriangles.insert(tree.leafTriangles.end(), part.leafTriangles.begin(),
                            part.leafTriangles.end());
  tree.depth = std::max(tree.depth, part.depth);
  return moved(root);
}

class TreeBuilder {
 public:
  TreeBuilder(const Mesh& mesh, const TreeSettings& settings,
              const std::function<void(int)>& progress, bspf::ThreadPool* pool)
      : mesh_(mesh), settings_(settings), progress_(progress), pool_(pool) {
    faceNormals_.reserve(mesh.triangles.size());
    floatNormals_.reserve(mesh.triangles.size());
    centroids_.reserve(mesh.triangles.size());
    for (const auto& t : mesh.triangles) {
      const Eigen::Vector3d &a = mesh.vertices[t[0]], &b = mesh.vertices[t[1]],
                            &c = mesh.vertices[t[2]];
      faceNormals_.push_back((b - a).cross(c - a).normalized());
      const Eigen::Vector3d& normal = faceNormals_.back();
      floatNormals_.push_back({static_cast<float>(normal.x()), static_cast<float>(normal.y()),
                               static_cast<float>(normal.z()), 0.0f});
      centroids_.push_back((a + b + c) / 3.0);
    }
    if (settings.candidates != SplitCandidates::Axis) {
      trianglePlanes_.reserve(mesh.triangles.size());
      for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t)
        trianglePlanes_.push_back(trianglePlane(t));
    }
  }

  // The top of the tree is split here (expand: level by level, on every
  // thread), down to subtrees small enough to share out (several per
  // thread); the subtrees are then built on all threads at once,
  // each on one, and put together in the order one thread would have made
  // them. Which thread builds what never changes a split, so the tree is the
  // same for any thread count.
  BspTree build() {
    Lists all;
    all.order.resize(mesh_.triangles.size());
    for (std::uint32_t i = 0; i < all.size(); ++i) all.order[i] = i;
    // The three axes sorted at once, one a thread: a total order (ties by
    // index), so the same lists on any thread.
    if (settings_.candidates != SplitCandidates::Triangle)
      runParallel(pool_, 3, 1, [&](int, std::size_t first, std::size_t last) {
        for (std::size_t axis = first; axis < last; ++axis) {
          sortByCoordinate(int(axis), all.byAxis[axis]);
        }
      });
    Box bounds{mesh_.vertices.front(), mesh_.vertices.front()};
    for (const Eigen::Vector3d& v : mesh_.vertices) {
      bounds.low = bounds.low.cwiseMin(v);
      bounds.high = bounds.high.cwiseMax(v);
    }
    const int threads = pool_ ? pool_->threadCount() : 1;
    scratch_.resize(std::size_t(threads));
    // One thread: the whole tree is one subtree.
    shareSize_ = threads == 1 ? all.size() : all.size() / (8 * std::size_t(threads));
    const std::int32_t top = expand(std::move(all), bounds);

    std::vector<std::size_t> order(subtrees_.size());
    for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
    // Largest first, so no thread is left with a big one at the end.
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
      return subtrees_[a].lists.size() > subtrees_[b].lists.size();
    });
    runParallel(pool_, order.size(), 1, [&](int thread, std::size_t first, std::size_t last) {
      for (std::size_t i = first; i < last; ++i) {
        Subtree& s = subtrees_[order[i]];
        s.root = buildNode(s.lists, s.cell, s.depth, s.share, s.tree, scratch_[thread]);
      }
    });
    // Sized once: grown append by append, the arrays were copied and their
    // pages faulted in again at each doubling (putting oacmpctf3's 16
    // subtrees together took 2.3 ms at 2 threads, its one subtree 0.8 ms).
    std::size_t nodes = top_.size(), leaves = 0, entries = 0;
    for (const Subtree& s : subtrees_) {
      nodes += s.tree.nodes.size();
      leaves += s.tree.leaves.size();
      entries += s.tree.leafTriangles.size();
    }
    BspTree tree;
    tree.nodes.reserve(nodes);
    tree.leaves.reserve(leaves);
    tree.leafTriangles.reserve(entries);
    tree.root = assemble(top, tree);
    return tree;
  }

 private:
  // The mesh's triangles in order of their centroids' coordinate on `axis`,
  // ties in order of index: the order of sorted (coordinate, index) pairs,
  // by a stable radix sort of the coordinates' bits made to order as the
  // numbers do (sign bit set on the positive, all bits flipped on the
  // negative; -0 first made +0, which it equals). Six passes of 11 bits
  // (few buckets to clear for a small mesh), a pass skipped where every
  // key has the same digit.
  void sortByCoordinate(int axis, IndexList& out) const {
    const std::size_t n = centroids_.size();
    std::vector<std::uint64_t> keys(n), keysTo(n);
    IndexList order(n), orderTo(n);
    for (std::size_t i = 0; i < n; ++i) {
      const double value = centroids_[i][axis] + 0.0;
      std::uint64_t bits;
      std::memcpy(&bits, &value, sizeof bits);
      keys[i] = bits >> 63 ? ~bits : bits | (std::uint64_t(1) << 63);
      order[i] = static_cast<std::uint32_t>(i);
    }
    constexpr int kDigitBits = 11;
    constexpr std::uint64_t kDigit = (std::uint64_t(1) << kDigitBits) - 1;
    std::vector<std::size_t> start(std::size_t(1) << kDigitBits);
    for (int shift = 0; shift < 64; shift += kDigitBits) {
      std::fill(start.begin(), start.end(), 0);
      for (const std::uint64_t key : keys) ++start[(key >> shift) & kDigit];
      if (n && start[(keys[0] >> shift) & kDigit] == n) continue;
      std::size_t sum = 0;
      for (std::size_t& s : start) sum += std::exchange(s, sum);
      for (std::size_t i = 0; i < n; ++i) {
        const std::size_t to = start[(keys[i] >> shift) & kDigit]++;
        keysTo[to] = keys[i];
        orderTo[to] = order[i];
      }
      keys.swap(keysTo);
      order.swap(orderTo);
    }
    out = std::move(order);
  }

  // A part of the tree built on one thread, into its own arrays.
  struct Subtree {
    Lists lists;
    Box cell;
    std::uint32_t depth;
    double share;  // of the mesh's triangles, for the progress line
    BspTree tree;
    std::int32_t root = -1;
  };
  // A node split before the subtrees are shared out. Children: >= 0 another
  // top node, < 0 subtree -(child + 1).
  struct TopNode {
    Split split;
    std::int32_t front = 0, back = 0;
  };

  // A node of the top waiting to be split or shared out, and where its
  // reference goes: the front or back child of top node `parent` (-1: the
  // root).
  struct Pending {
    Lists lists;
    Box cell;
    std::uint32_t depth;
    double share;
    std::int32_t parent;
    bool front;
  };

  // Splits the top of the tree level by level, down to nodes of at most
  // shareSize_ triangles (or that no split pays for), which become the
  // subtrees; returns the root's reference. A level's nodes are split at
  // once, one a thread, when none holds more than half of the level's
  // triangles; otherwise one after another, each on all threads. Each node
  // is split as it would be alone, so the tree is the same either way.
  std::int32_t expand(Lists all, const Box& bounds) {
    std::int32_t root = 0;
    std::vector<Pending> level;
    level.push_back({std::move(all), bounds, 0, 1.0, -1, false});
    while (!level.empty()) {
      const std::size_t count = level.size();
      std::vector<std::optional<Chosen>> splits(count);
      std::vector<Lists> fronts(count), backs(count);
      std::vector<std::uint8_t> divided(count, 0);
      const auto divide = [&](std::size_t i, Scratch& scratch, bspf::ThreadPool* pool) {
        Pending& node = level[i];
        if (node.lists.size() > shareSize_ && node.lists.size() > settings_.maxLeafTriangles &&
            node.depth < settings_.maxDepth)
          splits[i] = chooseSplit(node.lists, node.cell, scratch, pool);
        divided[i] =
            splits[i] && partition(node.lists, splits[i]->split, scratch.columns, node.depth + 1,
                                   fronts[i], backs[i], scratch.side, pool);
      };
      std::size_t total = 0, largest = 0;
      for (const Pending& node : level) {
        total += node.lists.size();
        largest = std::max(largest, node.lists.size());
      }
      if (count > 1 && 2 * largest <= total)
        runParallel(pool_, count, 1, [&](int thread, std::size_t first, std::size_t last) {
          for (std::size_t i = first; i < last; ++i)
            divide(i, scratch_[std::size_t(thread)], nullptr);
        });
      else
        for (std::size_t i = 0; i < count; ++i) divide(i, scratch_.front(), pool_);

      std::vector<Pending> next;
      for (std::size_t i = 0; i < count; ++i) {
        Pending& node = level[i];
        std::int32_t reference;
        if (!divided[i]) {
          subtrees_.push_back({std::move(node.lists), node.cell, node.depth, node.share, {}, -1});
          reference = -static_cast<std::int32_t>(subtrees_.size());
        } else {
          reference = static_cast<std::int32_t>(top_.size());
          top_.push_back({splits[i]->split});
          const double whole = double(fronts[i].size() + backs[i].size());
          const double frontShare = node.share * double(fronts[i].size()) / whole;
          const double backShare = node.share * double(backs[i].size()) / whole;
          const auto& [frontCell, backCell] = splits[i]->cells;
          next.push_back(
              {std::move(fronts[i]), frontCell, node.depth + 1, frontShare, reference, true});
          next.push_back(
              {std::move(backs[i]), backCell, node.depth + 1, backShare, reference, false});
        }
        if (node.parent < 0)
          root = reference;
        else if (node.front)
          top_[std::size_t(node.parent)].front = reference;
        else
          top_[std::size_t(node.parent)].back = reference;
      }
      level = std::move(next);
    }
    return root;
  }

  // The top node or subtree `child` and everything below it, appended to
  // `tree` in the order buildNode makes them; its reference there.
  std::int32_t assemble(std::int32_t child, BspTree& tree) {
    if (child < 0) {
      const Subtree& s = subtrees_[std::size_t(-child - 1)];
      return appendSubtree(tree, s.tree, s.root);
    }
    const TopNode& node = top_[std::size_t(child)];
    const auto index = static_cast<std::int32_t>(tree.nodes.size());
    tree.nodes.emplace_back();
    const std::int32_t frontChild = assemble(node.front, tree);
    const std::int32_t backChild = assemble(node.back, tree);
    tree.nodes[std::size_t(index)] = bspf::schema::Node(toPlane(node.split), frontChild, backChild);
    return index;
  }

  static bspf::schema::Plane toPlane(const Split& split) {
    return bspf::schema::Plane(
        bspf::schema::Vec3(split.normal.x(), split.normal.y(), split.normal.z()), split.distance);
  }

  // Splits `triangles` (emptied) into the two sides' lists, in their order;
  // `side` is working memory, one entry a mesh triangle. A triangle lying in
  // the plane goes to the side its normal faces; a corner within the
  // tolerance of a side counts as reaching it. In double, from the mesh, or
  // equivalently from `columns` (the node's triangles in the order of
  // `triangles`, gathered by chooseSplit) where float is provably
  // decisive: a cell's lists are complete whatever float made of the
  // counts. False, with `triangles` left as they were, when every triangle
  // would reach one side: the split makes no progress (the float counts
  // said it did, which only a triangle at the tolerance's edge can make
  // them say). `childDepth`: the children's depth, which with their sizes
  // tells whether they will be split (and need their axis orders).
  // (`columns`: read by the SSE2 path only.)
  // With `pool`, a large node is classified and its lists written on all
  // the pool's threads: each triangle's side and each list's order are the
  // same either way.
  bool partition(Lists& triangles, const Split& split, [[maybe_unused]] const Columns& columns,
                 std::uint32_t childDepth, Lists& front, Lists& back,
                 std::vector<std::uint8_t>& side, bspf::ThreadPool* pool,
                 SpareLists* spare = nullptr) const {
    side.resize(mesh_.triangles.size());
    const double nx = split.normal.x(), ny = split.normal.y(), nz = split.normal.z();
    const double distance = split.distance, tolerance = onPlaneTolerance(split);
    const auto classifyInDouble = [&](std::uint32_t t) {
      double lowest = std::numeric_limits<double>::infinity();
      double highest = -lowest;
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d& v = mesh_.vertices[mesh_.triangles[t][k]];
        const double s = (nx * v.x() + ny * v.y()) + nz * v.z() - distance;
        lowest = std::min(lowest, s);
        highest = std::max(highest, s);
      }
      const Eigen::Vector3d& normal = faceNormals_[t];
      const double facing = (normal.x() * nx + normal.y() * ny) + normal.z() * nz;
      const bool inPlane = highest <= tolerance && lowest >= -tolerance;
      const bool reachesFront = inPlane ? facing >= 0 : highest > -tolerance;
      const bool reachesBack = inPlane ? facing < 0 : lowest < tolerance;
      return std::uint8_t((reachesFront ? kFront : 0) | (reachesBack ? kBack : 0));
    };
    // The triangles [first, last) classified, `first` a multiple of four,
    // and listed in order from `frontOut` and `backOut` (as many slots as
    // triangles each: a triangle's unconditional write lands at most at its
    // own index); how many reach each side. The order lists are written
    // here, where each triangle's side is at hand, not by a second pass.
    std::function<std::pair<std::size_t, std::size_t>(std::size_t, std::size_t, std::uint32_t*,
                                                      std::uint32_t*)>
        classify;
    // Written unconditionally, kept by the side's bit: no branch to mispredict.
    const auto keep = [&](std::uint32_t t, std::uint8_t sides, std::uint32_t*& frontOut,
                          std::uint32_t*& backOut) {
      side[t] = sides;
      *frontOut = t;
      *backOut = t;
      frontOut += sides & kFront;
      backOut += sides >> 1;
    };
#ifdef BSPC_SSE2
    // A float signed distance differs from partition's double one by less
    // than `error`: the corners' and the offset's rounding to float (half
    // an ulp each), float's four operations on them, and double's rounding
    // of the distance and of its own evaluation, all bounded generously.
    // Where the lowest and highest distances are each further than that
    // from the four thresholds (+-tolerance), every comparison comes out
    // as in double; and a triangle in the plane whose float facing is
    // further from 0 than the normal's rounding can move it faces the same
    // side. Any other triangle is classified in double.
    const double offset = distance - split.normal.cast<double>().dot(columns.origin);
    const auto offsetFloat = static_cast<float>(offset);
    const double unit = std::ldexp(1.0, -24);
    // The largest distance of a corner from the origin along each axis.
    double extent[3];
    for (int axis = 0; axis < 3; ++axis) {
      __m128 lowest = _mm_setzero_ps(), highest = _mm_setzero_ps();
      for (std::size_t j = 0; j + 4 <= columns.size; j += 4) {
        lowest = _mm_min_ps(lowest, _mm_loadu_ps(&columns.low[axis][j]));
        highest = _mm_max_ps(highest, _mm_loadu_ps(&columns.high[axis][j]));
      }
      float lanes[8];
      _mm_storeu_ps(lanes, lowest);
      _mm_storeu_ps(lanes + 4, highest);
      extent[axis] = 0;
      for (const float lane : lanes) extent[axis] = std::max(extent[axis], double(std::abs(lane)));
    }
    const double spread =
        std::abs(nx) * extent[0] + std::abs(ny) * extent[1] + std::abs(nz) * extent[2];
    const double far = std::abs(nx * columns.origin.x()) + std::abs(ny * columns.origin.y()) +
                       std::abs(nz * columns.origin.z()) + std::abs(distance) + spread;
    const double error =
        8 * unit * (spread + std::abs(offset)) + std::ldexp(far, -46) + 4 * unit * tolerance;
    // Bands around the thresholds, widened for their own rounding to float.
    const double widened = error * (1 + 8 * unit) + 1e-30;
    const auto bandLow = [&](double threshold) {
      return _mm_set1_ps(static_cast<float>(threshold - widened - 4 * unit * std::abs(threshold)));
    };
    const auto bandHigh = [&](double threshold) {
      return _mm_set1_ps(static_cast<float>(threshold + widened + 4 * unit * std::abs(threshold)));
    };
    const __m128 aboveLow = bandLow(tolerance), aboveHigh = bandHigh(tolerance);
    const __m128 belowLow = bandLow(-tolerance), belowHigh = bandHigh(-tolerance);
    const __m128 above = _mm_set1_ps(static_cast<float>(tolerance)),
                 below = _mm_set1_ps(static_cast<float>(-tolerance));
    const __m128 facingBand = _mm_set1_ps(1e-5f);
    const __m128 vx = _mm_set1_ps(split.normal.x()), vy = _mm_set1_ps(split.normal.y()),
                 vz = _mm_set1_ps(split.normal.z()), vd = _mm_set1_ps(offsetFloat);
    const __m128 zero = _mm_setzero_ps();
    const __m128 signBit = _mm_set1_ps(-0.0f);
    const auto within = [](__m128 value, __m128 lowEdge, __m128 highEdge) {
      return _mm_and_ps(_mm_cmpge_ps(value, lowEdge), _mm_cmple_ps(value, highEdge));
    };
    const std::uint32_t* order = triangles.order.data();
    const __m128i frontCode = _mm_set1_epi32(kFront), backCode = _mm_set1_epi32(kBack);
    classify = [&](std::size_t first, std::size_t last, std::uint32_t* frontOut,
                   std::uint32_t* backOut) {
      std::uint32_t *const frontFirst = frontOut, *const backFirst = backOut;
      std::size_t i = first;
      for (; i + 4 <= last; i += 4) {
        const auto along = [&](int k) {
          return _mm_sub_ps(
              _mm_add_ps(_mm_add_ps(_mm_mul_ps(vx, _mm_loadu_ps(&columns.corner[k][0][i])),
                                    _mm_mul_ps(vy, _mm_loadu_ps(&columns.corner[k][1][i]))),
                         _mm_mul_ps(vz, _mm_loadu_ps(&columns.corner[k][2][i]))),
              vd);
        };
        const __m128 s0 = along(0), s1 = along(1), s2 = along(2);
        const __m128 lowest = _mm_min_ps(_mm_min_ps(s0, s1), s2);
        const __m128 highest = _mm_max_ps(_mm_max_ps(s0, s1), s2);
        const __m128 facing =
            _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_loadu_ps(&columns.normal[0][i]), vx),
                                  _mm_mul_ps(_mm_loadu_ps(&columns.normal[1][i]), vy)),
                       _mm_mul_ps(_mm_loadu_ps(&columns.normal[2][i]), vz));
        const __m128 inPlane =
            _mm_and_ps(_mm_cmple_ps(highest, above), _mm_cmpge_ps(lowest, below));
        const __m128 unsure = _mm_or_ps(
            _mm_or_ps(
                _mm_or_ps(within(lowest, aboveLow, aboveHigh), within(lowest, belowLow, belowHigh)),
                _mm_or_ps(within(highest, aboveLow, aboveHigh),
                          within(highest, belowLow, belowHigh))),
            _mm_and_ps(inPlane, _mm_cmple_ps(_mm_andnot_ps(signBit, facing), facingBand)));
        const __m128 facesFront = _mm_cmpge_ps(facing, zero);
        const __m128 reachesFront = _mm_or_ps(_mm_and_ps(inPlane, facesFront),
                                              _mm_andnot_ps(inPlane, _mm_cmpgt_ps(highest, below)));
        const __m128 reachesBack = _mm_or_ps(_mm_andnot_ps(facesFront, inPlane),
                                             _mm_andnot_ps(inPlane, _mm_cmplt_ps(lowest, above)));
        // The four lanes' sides as the four bytes of one integer.
        const __m128i sideLanes =
            _mm_or_si128(_mm_and_si128(_mm_castps_si128(reachesFront), frontCode),
                         _mm_and_si128(_mm_castps_si128(reachesBack), backCode));
        const auto sideBytes = static_cast<std::uint32_t>(
            _mm_cvtsi128_si32(_mm_packus_epi16(_mm_packs_epi32(sideLanes, sideLanes), sideLanes)));
        const int unsureBits = _mm_movemask_ps(unsure);
        if (!unsureBits) {
          // Most fours: spelled out, no lane's test.
          keep(order[i], std::uint8_t(sideBytes), frontOut, backOut);
          keep(order[i + 1], std::uint8_t(sideBytes >> 8), frontOut, backOut);
          keep(order[i + 2], std::uint8_t(sideBytes >> 16), frontOut, backOut);
          keep(order[i + 3], std::uint8_t(sideBytes >> 24), frontOut, backOut);
          continue;
        }
        for (int lane = 0; lane < 4; ++lane) {
          const std::uint32_t t = order[i + std::size_t(lane)];
          const std::uint8_t sides = (unsureBits >> lane) & 1
                                         ? classifyInDouble(t)
                                         : std::uint8_t(sideBytes >> (8 * lane));
          keep(t, sides, frontOut, backOut);
        }
      }
      for (; i < last; ++i) {
        const std::uint32_t t = order[i];
        keep(t, classifyInDouble(t), frontOut, backOut);
      }
      return std::pair(std::size_t(frontOut - frontFirst), std::size_t(backOut - backFirst));
    };
#else
    classify = [&](std::size_t first, std::size_t last, std::uint32_t* frontOut,
                   std::uint32_t* backOut) {
      std::uint32_t *const frontFirst = frontOut, *const backFirst = backOut;
      for (std::size_t i = first; i < last; ++i) {
        const std::uint32_t t = triangles.order[i];
        keep(t, classifyInDouble(t), frontOut, backOut);
      }
      return std::pair(std::size_t(frontOut - frontFirst), std::size_t(backOut - backFirst));
    };
#endif
    const bool parallel = pool && triangles.size() > kParallelAbove;
    const std::size_t n = triangles.size();
    const auto fresh = [&](IndexList& list) {
      if (spare && list.capacity() == 0) list = spare->take();
    };
    // A list done with: kept for the next node's, or freed.
    const auto release = [&](IndexList& list) {
      if (spare)
        spare->give(std::move(list));
      else
        IndexList().swap(list);
    };
    fresh(front.order);
    fresh(back.order);
    front.order.resize(n);
    back.order.resize(n);
    std::size_t toFront = 0, toBack = 0;
    if (parallel) {
      // Each range listed in its own stretch of the lists, then the
      // stretches closed up in order.
      const std::size_t ranges = (n + kParallelRange - 1) / kParallelRange;
      std::vector<std::pair<std::size_t, std::size_t>> reached(ranges);
      runParallel(pool, ranges, 1, [&](int, std::size_t first, std::size_t last) {
        for (std::size_t r = first; r < last; ++r)
          reached[r] = classify(r * kParallelRange, std::min(n, (r + 1) * kParallelRange),
                                front.order.data() + r * kParallelRange,
                                back.order.data() + r * kParallelRange);
      });
      for (std::size_t r = 0; r < ranges; ++r) {
        std::memmove(front.order.data() + toFront, front.order.data() + r * kParallelRange,
                     reached[r].first * sizeof(std::uint32_t));
        std::memmove(back.order.data() + toBack, back.order.data() + r * kParallelRange,
                     reached[r].second * sizeof(std::uint32_t));
        toFront += reached[r].first;
        toBack += reached[r].second;
      }
    } else {
      std::tie(toFront, toBack) = classify(0, n, front.order.data(), back.order.data());
    }
    if (toFront == n || toBack == n) return false;
    front.order.resize(toFront);
    back.order.resize(toBack);
    release(triangles.order);
    // A side's list is written when wanted: a child that will be a leaf
    // (few triangles, or at the depth limit) never reads its axis orders.
    const auto share = [&](IndexList& from, IndexList& toFrontList, IndexList& toBackList,
                           bool wantFront, bool wantBack) {
      if (from.empty()) return;
      // One spare slot each: the write past a side's last kept entry.
      if (wantFront) fresh(toFrontList), toFrontList.resize(toFront + 1);
      if (wantBack) fresh(toBackList), toBackList.resize(toBack + 1);
      std::uint32_t *frontOut = toFrontList.data(), *backOut = toBackList.data();
      // Written unconditionally, kept by the side's bit: no branch to mispredict.
      if (wantFront && wantBack)
        for (const std::uint32_t t : from) {
          *frontOut = t;
          *backOut = t;
          frontOut += side[t] & kFront;
          backOut += (side[t] & kBack) >> 1;
        }
      else if (wantFront)
        for (const std::uint32_t t : from) {
          *frontOut = t;
          frontOut += side[t] & kFront;
        }
      else if (wantBack)
        for (const std::uint32_t t : from) {
          *backOut = t;
          backOut += (side[t] & kBack) >> 1;
        }
      if (wantFront) toFrontList.pop_back();
      if (wantBack) toBackList.pop_back();
      release(from);
    };
    const auto splitFurther = [&](std::size_t count) {
      return count > settings_.maxLeafTriangles && childDepth < settings_.maxDepth;
    };
    // The axes' lists apart, one a task.
    runParallel(parallel ? pool : nullptr, 3, 1, [&](int, std::size_t first, std::size_t last) {
      for (std::size_t axis = first; axis < last; ++axis)
        share(triangles.byAxis[axis], front.byAxis[axis], back.byAxis[axis], splitFurther(toFront),
              splitFurther(toBack));
    });
    return true;
  }

  // A candidate split and how to count it: against the column of `axis`
  // (negated when `flipped`) when its normal is that axis, by the full dot
  // product when `axis` is -1.
  struct Candidate {
    Split split;
    int axis;
    bool flipped;
  };

  // The candidates, in order, each plane once: a later copy of a plane
  // (many triangles of a wall sample the same one) has the same counts and
  // cells as the first, so it loses every tie to it and is never chosen.
  // The axis planes need no look-up: an axis's quantiles come in order (an
  // equal one is the one before), and the axes' normals differ. A triangle
  // plane can equal one only when its normal is that axis (flipped, it
  // faces the other way): those few are compared with their axis's planes.
  // `slots` is working memory for a hash set of the triangle planes so far
  // (a scan of them all was a tenth of the build); small nodes, most of
  // the tree's, were spending more on the set than on counting.
  void candidates(const Lists& lists, std::vector<Candidate>& out,
                  std::vector<std::int32_t>& slots) const {
    const auto n = lists.size();
    const IndexList& triangles = lists.order;
    const bool axisPlanes = settings_.candidates != SplitCandidates::Triangle,
               trianglePlanes = settings_.candidates != SplitCandidates::Axis;
    const std::uint32_t quantiles = settings_.axisCandidatesPerAxis;
    const std::size_t step = std::max<std::size_t>(1, n / settings_.triangleCandidates);
    const std::size_t sampled = trianglePlanes ? (n + step - 1) / step : 0;
    // Room for every plane tried, written by index: push_back, not inlined,
    // was a third of this.
    const std::size_t most = (axisPlanes ? 3 * std::size_t(quantiles) : 0) + sampled;
    if (out.size() < most) out.resize(most);
    std::size_t kept = 0;
    std::array<std::size_t, 3> axisFirst{}, axisEnd{};
    if (axisPlanes) {
      // Quantile q at q * n / (quantiles + 1): the quotient and remainder
      // of q * n grow by those of n, one division a node, not one a plane.
      const std::size_t parts = std::size_t(quantiles) + 1, whole = n / parts, rest = n % parts;
      for (int axis = 0; axis < 3; ++axis) {
        axisFirst[axis] = kept;
        float previous = std::numeric_limits<float>::quiet_NaN();
        std::size_t at = 0, remainder = 0;
        for (std::uint32_t q = 1; q <= quantiles; ++q) {
          at += whole;
          remainder += rest;
          if (remainder >= parts) ++at, remainder -= parts;
          const std::uint32_t t = lists.byAxis[axis][at];
          const float value = static_cast<float>(centroids_[t][axis]);
          if (value == previous) continue;
          previous = value;
          out[kept++] = {{Eigen::Vector3f::Unit(axis), value}, axis, false};
        }
        axisEnd[axis] = kept;
      }
    }
    if (trianglePlanes) {
      // At most half full.
      std::size_t tableSize = 16;
      while (tableSize < 2 * sampled) tableSize *= 2;
      slots.assign(tableSize, -1);
      for (std::size_t i = 0; i < n; i += step) {
        const TrianglePlane& plane = trianglePlanes_[triangles[i]];
        const Candidate& candidate = plane.candidate;
        const Split& split = candidate.split;
        if (candidate.axis >= 0 && !candidate.flipped) {
          const std::size_t axis = std::size_t(candidate.axis);
          std::size_t k = axisFirst[axis];
          while (k < axisEnd[axis] && !(out[k].split.distance == split.distance)) ++k;
          if (k < axisEnd[axis]) continue;
        }
        for (std::size_t slot = std::size_t(plane.hash >> 40) & (tableSize - 1);;
             slot = (slot + 1) & (tableSize - 1)) {
          if (slots[slot] < 0) {
            slots[slot] = static_cast<std::int32_t>(kept);
            out[kept++] = candidate;
            break;
          }
          const Split& c = out[std::size_t(slots[slot])].split;
          if (c.distance == split.distance && c.normal == split.normal) break;
        }
      }
    }
    out.resize(kept);
  }

  // The split chooseSplit picks, with the boxes around its two cells (front,
  // back), which select clipped to judge it.
  struct Chosen {
    Split split;
    std::pair<Box, Box> cells;
  };

  // Picks the first slot candidates() tries for a plane. Two words, two
  // multiplications: the hash never decides which candidates are kept or
  // their order.
  static std::uint64_t planeHash(const Split& split) {
    // + 0.0f: -0 and +0, equal to ==, hash alike.
    const float key[4] = {split.normal.x() + 0.0f, split.normal.y() + 0.0f, split.normal.z() + 0.0f,
                          split.distance + 0.0f};
    std::uint64_t words[2];
    std::memcpy(words, key, sizeof words);
    return ((words[0] * 0x9E3779B97F4A7C15ull) ^ words[1]) * 0xC2B2AE3D27D4EB4Full;
  }

  // A triangle's own plane as a candidate, with its hash: the same at every
  // node that samples the triangle, so found once.
  struct TrianglePlane {
    Candidate candidate;
    std::uint64_t hash;
  };
  TrianglePlane trianglePlane(std::uint32_t t) const {
    const Eigen::Vector3f normal = faceNormals_[t].cast<float>();
    const auto distance =
        static_cast<float>(normal.cast<double>().dot(mesh_.vertices[mesh_.triangles[t][0]]));
    int axis = -1;
    for (int a = 0; a < 3; ++a)
      if (std::abs(normal[a]) == 1.0f && normal[(a + 1) % 3] == 0.0f && normal[(a + 2) % 3] == 0.0f)
        axis = a;
    const Split split{normal, distance};
    return {{split, axis, axis >= 0 && normal[axis] < 0}, planeHash(split)};
  }

  // Per-thread working memory of the split search.
  struct Scratch {
    SpareLists spare;
    Columns columns, sampleColumns;
    IndexList sample;
    std::vector<std::uint8_t> side;
    std::vector<std::int32_t> slots;
    std::vector<Candidate> candidates, shortlist;
    std::vector<std::pair<double, std::size_t>> estimates, ranked;  // score, candidate
    struct Counted {
      Split split;
      double frontTotal, backTotal, score;
      std::optional<std::pair<Box, Box>> cells;  // front, back
    };
    std::vector<Counts> blockCounts, counts;
    std::vector<Counted> counted;
  };

  // partition's counts of each of `candidates` over the triangles of
  // `columns`, into `out`. Block by block, every candidate counted on a
  // block while it is in the cache; with a pool, blocks shared between the
  // threads, each block's counts kept apart and summed in order.
  static void countAll(const std::vector<Candidate>& candidates, const Columns& columns,
                       Scratch& scratch, bspf::ThreadPool* pool, std::vector<Counts>& out) {
    // The padded size: a block's end is a multiple of four.
    const std::size_t n = columns.padded, m = candidates.size();
    const std::size_t blocks = (n + kBlock - 1) / kBlock;
    // Only grown: every entry read below is written first.
    if (scratch.blockCounts.size() < blocks * m) scratch.blockCounts.resize(blocks * m);
    runParallel(pool, blocks, 1, [&](int, std::size_t first, std::size_t last) {
      for (std::size_t b = first; b < last; ++b) {
        const std::size_t begin = b * kBlock, end = std::min(n, begin + kBlock);
        for (std::size_t i = 0; i < m; ++i) {
          const auto& [split, axis, flipped] = candidates[i];
          const auto tolerance = static_cast<float>(onPlaneTolerance(split));
          const auto distance = static_cast<float>(double(split.distance) -
                                                   split.normal.cast<double>().dot(columns.origin));
          scratch.blockCounts[b * m + i] =
              axis >= 0 ? countAxisSplit(columns, begin, end, axis, flipped, distance, tolerance)
                        : countSplit(columns, begin, end, split.normal, distance, tolerance);
        }
      }
    });
    out.assign(m, Counts{});
    for (std::size_t b = 0; b < blocks; ++b)
      for (std::size_t i = 0; i < m; ++i) {
        out[i] = out[i] + scratch.blockCounts[b * m + i];
      }
  }

  double score(const Counts& c, double count) const {
    return settings_.balanceWeight * std::abs(double(c.front) - double(c.back)) / count +
           settings_.splitWeight * double(c.both) / count;
  }

  // The best-scoring split among those that make progress on both sides and
  // pay for themselves: its expected query cost (one node test plus the triangles of each
  // child, weighted by how likely a query reaches the child's cell) is below
  // the leaf's (all its triangles). When none pays at the query reach and
  // the node has more than kDenseNodeTriangles, the same at a reach of at
  // most a quarter of its cell's longest side: a cell much smaller than the
  // query reach is seen whole by every query that reaches it, so at that
  // reach no split of a dense cluster of tiny triangles pays (its
  // straddlers outweigh the gain), and such leaves grew to thousands of
  // triangles. At the cell's own scale a split pays unless it lists most
  // triangles on both sides.
  //
  // A node of more than kSampledAbove triangles first counts its candidates
  // on an even sample of kSample of them, and only the kShortlist best
  // estimates on all: the exact count of every candidate was most of the
  // build, and the estimates put the best candidate among the shortlisted
  // almost always (the trees' query figures: docs/measurements.md). When
  // no shortlisted candidate pays, all are counted; with
  // TreeSettings::exhaustiveSplitSearch, always. With a pool, the exact
  // counts run on all its threads.
  std::optional<Chosen> chooseSplit(const Lists& lists, const Box& cell, Scratch& scratch,
                                    bspf::ThreadPool* pool) const {
    const std::size_t n = lists.size();
    // A small node's counts take less time than waking the pool's threads.
    if (n <= kParallelAbove) pool = nullptr;
    candidates(lists, scratch.candidates, scratch.slots);
    const Eigen::Vector3d middle = (cell.low + cell.high) / 2;
    scratch.columns.gather(lists.order, mesh_, floatNormals_, middle, pool);
    if (!settings_.exhaustiveSplitSearch && n > kSampledAbove &&
        scratch.candidates.size() > kShortlist) {
      scratch.sample.resize(kSample);
      for (std::size_t i = 0; i < kSample; ++i) scratch.sample[i] = lists.order[i * n / kSample];
      scratch.sampleColumns.gather(scratch.sample, mesh_, floatNormals_, middle);
      countAll(scratch.candidates, scratch.sampleColumns, scratch, nullptr, scratch.counts);
      scratch.estimates.resize(scratch.candidates.size());
      for (std::size_t i = 0; i < scratch.candidates.size(); ++i)
        scratch.estimates[i] = {score(scratch.counts[i], double(kSample)), i};
      // Stable: of equal estimates, the earlier candidate.
      std::nth_element(scratch.estimates.begin(), scratch.estimates.begin() + kShortlist,
                       scratch.estimates.end());
      std::sort(scratch.estimates.begin(), scratch.estimates.begin() + kShortlist,
                [](const auto& a, const auto& b) { return a.second < b.second; });
      scratch.shortlist.clear();
      for (std::size_t i = 0; i < kShortlist; ++i)
        scratch.shortlist.push_back(scratch.candidates[scratch.estimates[i].second]);
      countAll(scratch.shortlist, scratch.columns, scratch, pool, scratch.counts);
      if (std::optional<Chosen> chosen = select(scratch.shortlist, n, cell, scratch)) return chosen;
    }
    countAll(scratch.candidates, scratch.columns, scratch, pool, scratch.counts);
    return select(scratch.candidates, n, cell, scratch);
  }

  // The choice among `candidates`, whose counts over the node's `n`
  // triangles are in scratch.counts.
  std::optional<Chosen> select(const std::vector<Candidate>& candidates, std::size_t n,
                               const Box& cell, Scratch& scratch) const {
    // Written by index, as in candidates().
    if (scratch.counted.size() < candidates.size()) scratch.counted.resize(candidates.size());
    std::size_t kept = 0;
    const double count = static_cast<double>(n);
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      const Counts& c = scratch.counts[i];
      if (c.front + c.both == n || c.back + c.both == n) continue;
      const double frontTotal = double(c.front + c.both), backTotal = double(c.back + c.both);
      scratch.counted[kept++] = {candidates[i].split, frontTotal, backTotal, score(c, count),
                                 std::nullopt};
    }
    // The lowest score that pays, the earliest candidate of equal scores:
    // candidates in that order, the first that pays. Its cells are clipped
    // only when asked, as most candidates never are.
    // Ranks sorted, not the candidates, whose cells make them large to move.
    scratch.ranked.resize(kept);
    for (std::size_t i = 0; i < kept; ++i) scratch.ranked[i] = {scratch.counted[i].score, i};
    bool sorted = false;
    auto best = [&](double reach) -> std::optional<Chosen> {
      const double whole = cell.reachVolume(reach);
      auto pays = [&](std::size_t i) {
        auto& c = scratch.counted[i];
        if (!c.cells) c.cells = cell.clippedBoth(c.split);
        const double cost = 1.0 + (c.cells->first.reachVolume(reach) * c.frontTotal +
                                   c.cells->second.reachVolume(reach) * c.backTotal) /
                                      whole;
        return cost < count;
      };
      if (scratch.ranked.empty()) return std::nullopt;
      // The first in rank most often pays: found in one pass, it spares the
      // sort (a small node's sort cost more than its counting).
      const std::size_t first =
          std::min_element(scratch.ranked.begin(), scratch.ranked.end())->second;
      if (pays(first)) return Chosen{scratch.counted[first].split, *scratch.counted[first].cells};
      if (!sorted) std::sort(scratch.ranked.begin(), scratch.ranked.end());
      sorted = true;
      for (std::size_t k = 1; k < scratch.ranked.size(); ++k) {
        const std::size_t i = scratch.ranked[k].second;
        if (pays(i)) return Chosen{scratch.counted[i].split, *scratch.counted[i].cells};
      }
      return std::nullopt;
    };
    std::optional<Chosen> chosen = best(settings_.queryReach);
    if (!chosen && n > kDenseNodeTriangles)
      chosen = best(std::min(settings_.queryReach, 0.25 * (cell.high - cell.low).maxCoeff()));
    return chosen;
  }

  std::int32_t makeLeaf(Lists& lists, std::uint32_t depth, double share, BspTree& tree) {
    IndexList& triangles = lists.order;
    std::sort(triangles.begin(), triangles.end());
    const auto first = static_cast<std::uint32_t>(tree.leafTriangles.size());
    tree.leafTriangles.insert(tree.leafTriangles.end(), triangles.begin(), triangles.end());
    tree.leaves.emplace_back(first, static_cast<std::uint32_t>(triangles.size()));
    tree.depth = std::max(tree.depth, depth);
    if (progress_) report(share);
    return -static_cast<std::int32_t>(tree.leaves.size());
  }

  // Adds a finished leaf's share of the mesh to the progress line, which
  // changes when the whole percentage does.
  void report(double share) {
    const auto units = static_cast<std::uint64_t>(share * kProgressUnits);
    const std::uint64_t done = done_.fetch_add(units) + units;
    const int percent = static_cast<int>(std::min<std::uint64_t>(99, done * 100 / kProgressUnits));
    int shown = shown_.load();
    while (percent > shown)
      if (shown_.compare_exchange_weak(shown, percent)) {
        std::lock_guard lock(progressMutex_);
        progress_(percent);
        break;
      }
  }

  std::int32_t buildNode(Lists& triangles, const Box& cell, std::uint32_t depth, double share,
                         BspTree& tree, Scratch& scratch) {
    if (triangles.size() <= settings_.maxLeafTriangles || depth >= settings_.maxDepth)
      return makeLeaf(triangles, depth, share, tree);
    const std::optional<Chosen> chosen = chooseSplit(triangles, cell, scratch, nullptr);
    Lists front, back;
    if (!chosen || !partition(triangles, chosen->split, scratch.columns, depth + 1, front, back,
                              scratch.side, nullptr, &scratch.spare))
      return makeLeaf(triangles, depth, share, tree);
    const double whole = double(front.size() + back.size());
    const double frontShare = share * double(front.size()) / whole;
    const double backShare = share * double(back.size()) / whole;

    const auto index = static_cast<std::int32_t>(tree.nodes.size());
    tree.nodes.emplace_back();
    const auto& [frontCell, backCell] = chosen->cells;
    const std::int32_t frontChild =
        buildNode(front, frontCell, depth + 1, frontShare, tree, scratch);
    const std::int32_t backChild = buildNode(back, backCell, depth + 1, backShare, tree, scratch);
    tree.nodes[std::size_t(index)] =
        bspf::schema::Node(toPlane(chosen->split), frontChild, backChild);
    for (Lists* lists : {&front, &back}) {
      scratch.spare.give(std::move(lists->order));
      for (IndexList& list : lists->byAxis) scratch.spare.give(std::move(list));
    }
    return index;
  }

  static constexpr double kProgressUnits = 1e9;
  // Triangles counted against all candidates at a time: their columns
  // (21 floats each) stay in the first-level cache.
  static constexpr std::size_t kBlock = 256;
#ifdef BSPC_SSE2
  static_assert(kBlock / 4 <= 32767, "TallySse2 counts a lane's triangles in 16 bits");
#endif
  // The sampled split search (chooseSplit).
  // Measured on the shared levels (docs/measurements.md, "Issue 12
  // closed"): a sample of 64 and a shortlist of 4 above 128 triangles spare
  // a sixth of the tree's time (the exhaustive search, 129 ms against 108
  // on oacmpctf3, one thread); the walkers' steps cost the same as on the
  // exhaustive search's trees (leaves per query 10% fewer to 4% more,
  // candidates within 0.3%). Larger samples part from it as much, either
  // way: one split near the root moves oa_dm5's leaves per query by 10%.
  static constexpr std::size_t kSample = 64;
  static constexpr std::size_t kSampledAbove = 128;
  static constexpr std::size_t kShortlist = 4;

  const Mesh& mesh_;
  const TreeSettings& settings_;
  const std::function<void(int)>& progress_;
  bspf::ThreadPool* pool_;
  std::vector<Eigen::Vector3d> faceNormals_;
  std::vector<FloatNormal> floatNormals_;
  std::vector<Eigen::Vector3d> centroids_;
  std::vector<TrianglePlane> trianglePlanes_;  // empty when only axis candidates are tried
  std::vector<Scratch> scratch_;
  std::size_t shareSize_ = 0;
  std::vector<TopNode> top_;
  std::vector<Subtree> subtrees_;
  std::atomic<std::uint64_t> done_{0};
  std::atomic<int> shown_{-1};
  std::mutex progressMutex_;
};

}  // namespace

BspTree buildTree(const Mesh& mesh, const TreeSettings& settings,
                  const std::function<void(int)>& progress, bspf::ThreadPool* pool) {
  return TreeBuilder(mesh, settings, progress, pool).build();
}

}  // namespace bspc
