// SPDX-License-Identifier: MIT
// The gather's test of a leaf entry's stored box (schema::Box, as the blob
// holds it) against a query box: on x86-64 with two SSE compares, elsewhere
// (or with BSPF_SCALAR_MASKS defined) a plain test. Both count touching
// boxes as overlapping; the tests compare them. Private to the runtime.
#pragma once

#include <bspf/geometry.h>
#include <bspf/world.h>

#include <cstring>
#include <limits>

#if (defined(__SSE2__) || defined(_M_X64) || defined(_M_AMD64)) && !defined(BSPF_SCALAR_MASKS)
#include <emmintrin.h>
#define BSPF_SSE_STORED_BOX 1
#endif

namespace bspf::detail {

/// The reference: whether `box` overlaps [low, high] (touching counts).
/// The world's check guarantees finite boxes.
inline bool storedBoxOverlapsScalar(const schema::Box& box, const Vec3& low, const Vec3& high) {
  return box.min().x() <= high.x() && low.x() <= box.max().x() && box.min().y() <= high.y() &&
         low.y() <= box.max().y() && box.min().z() <= high.z() && low.z() <= box.max().z();
}

/// The same test against one query box, set up once for many stored boxes.
class StoredBoxTest {
 public:
  StoredBoxTest(const Vec3& low, const Vec3& high) {
#ifdef BSPF_SSE_STORED_BOX
    // A stored box is 6 floats: min x y z, then max x y z. The first four
    // are compared at once as (min.x, min.y, min.z, -max.x) <= (high.x,
    // high.y, high.z, -low.x) (negating is exact), the last two as (max.y,
    // max.z) >= (low.y, low.z); the unused lanes always pass.
    firstFour_ = _mm_setr_ps(high.x(), high.y(), high.z(), -low.x());
    lastTwo_ = _mm_setr_ps(low.y(), low.z(), -kInfinity, -kInfinity);
    negateFourth_ = _mm_castsi128_ps(_mm_setr_epi32(0, 0, 0, int(0x80000000u)));
#else
    low_ = low;
    high_ = high;
#endif
  }

  bool overlaps(const schema::Box& box) const {
#ifdef BSPF_SSE_STORED_BOX
    static_assert(sizeof(schema::Box) == 6 * sizeof(float));
    const float* f = reinterpret_cast<const float*>(&box);
    const __m128 first = _mm_xor_ps(_mm_loadu_ps(f), negateFourth_);
    double lastBits;  // max.y and max.z, loaded as one 8-byte word
    std::memcpy(&lastBits, f + 4, sizeof lastBits);
    const __m128 last = _mm_castpd_ps(_mm_load_sd(&lastBits));
    const __m128 pass = _mm_and_ps(_mm_cmple_ps(first, firstFour_), _mm_cmpge_ps(last, lastTwo_));
    return _mm_movemask_ps(pass) == 0xF;
#else
    return storedBoxOverlapsScalar(box, low_, high_);
#endif
  }

 private:
#ifdef BSPF_SSE_STORED_BOX
  static constexpr float kInfinity = std::numeric_limits<float>::infinity();
  __m128 firstFour_, lastTwo_, negateFourth_;
#else
  Vec3 low_, high_;
#endif
};

}  // namespace bspf::detail
