// SPDX-License-Identifier: MIT
// The box test and the pre-checks of the narrow phases, a CandidateBlock at a
// time (workspace.h): on x86-64, 4 lanes per SSE instruction (SSE2 is part of
// the baseline every x86-64 CPU has, so no run-time dispatch is needed);
// elsewhere, or with BSPF_SCALAR_MASKS defined, a plain loop that computes
// the same bits with the same float operations in the same order. The tests
// run both and compare them (tests/runtime/candidate_blocks_test.cpp).
#include "workspace.h"  // defines BSPF_SSE_MASKS where SSE2 is used

namespace bspf::detail {

namespace {

enum class Check { Box, Planes, Exact };

// The reference: one lane at a time.
template <Check check>
std::uint32_t scalarMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                         const Vec3& end, LaneSides* sides) {
  // (No early exit on the block's box: the reference checks every lane.)
  std::uint32_t bits = 0;
  for (int i = 0; i < kBlockLanes; ++i) {
    bool keep = laneBoxOverlaps(block, i, box);
    if constexpr (check != Check::Box) {
      // The side values: signed distances of the start and end centres to
      // the face plane, metres.
      const float startSide = laneSide(block, i, start), endSide = laneSide(block, i, end);
      if constexpr (check == Check::Planes) {
        keep = keep && endSide < block.reach[i] && startSide >= 0;
        sides->start[i] = startSide, sides->end[i] = endSide;
      } else
        keep = keep && startSide >= -1e-5f &&
               (startSide <= block.reach[i] || endSide <= block.reach[i]);
    }
    bits |= std::uint32_t(keep) << i;
  }
  return bits;
}

#ifdef BSPF_SSE_MASKS
// The same, 4 lanes at a time: each comparison gives a lane mask of all ones
// or zeros; movemask packs the lanes' sign bits into the result.
template <Check check>
std::uint32_t sseMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                      const Vec3& end, LaneSides* sides) {
  if (!boxesOverlap(block.low, block.high, box.low, box.high)) return 0;
  const __m128 lx = _mm_set1_ps(box.low.x()), ly = _mm_set1_ps(box.low.y()),
               lz = _mm_set1_ps(box.low.z());
  const __m128 hx = _mm_set1_ps(box.high.x()), hy = _mm_set1_ps(box.high.y()),
               hz = _mm_set1_ps(box.high.z());
  std::uint32_t bits = 0;
  for (int first = 0; first < kBlockLanes; first += 4) {
    __m128 keep = _mm_and_ps(_mm_cmple_ps(_mm_load_ps(block.lowX + first), hx),
                             _mm_cmple_ps(lx, _mm_load_ps(block.highX + first)));
    keep = _mm_and_ps(keep, _mm_and_ps(_mm_cmple_ps(_mm_load_ps(block.lowY + first), hy),
                                       _mm_cmple_ps(ly, _mm_load_ps(block.highY + first))));
    keep = _mm_and_ps(keep, _mm_and_ps(_mm_cmple_ps(_mm_load_ps(block.lowZ + first), hz),
                                       _mm_cmple_ps(lz, _mm_load_ps(block.highZ + first))));
    if constexpr (check != Check::Box) {
      const __m128 nx = _mm_load_ps(block.normalX + first), ny = _mm_load_ps(block.normalY + first),
                   nz = _mm_load_ps(block.normalZ + first);
      const __m128 distance = _mm_load_ps(block.distance + first);
      const __m128 reach = _mm_load_ps(block.reach + first);
      auto side = [&](const Vec3& p) {
        const __m128 sum = _mm_add_ps(
            _mm_add_ps(_mm_mul_ps(nx, _mm_set1_ps(p.x())), _mm_mul_ps(ny, _mm_set1_ps(p.y()))),
            _mm_mul_ps(nz, _mm_set1_ps(p.z())));
        return _mm_sub_ps(sum, distance);
      };
      const __m128 startSide = side(start), endSide = side(end);
      if constexpr (check == Check::Planes) {
        keep = _mm_and_ps(keep, _mm_and_ps(_mm_cmplt_ps(endSide, reach),
                                           _mm_cmpge_ps(startSide, _mm_setzero_ps())));
        _mm_store_ps(sides->start + first, startSide);
        _mm_store_ps(sides->end + first, endSide);
      } else {
        const __m128 inReach =
            _mm_or_ps(_mm_cmple_ps(startSide, reach), _mm_cmple_ps(endSide, reach));
        keep = _mm_and_ps(keep, _mm_and_ps(_mm_cmpge_ps(startSide, _mm_set1_ps(-1e-5f)), inReach));
      }
    }
    bits |= std::uint32_t(_mm_movemask_ps(keep)) << first;
  }
  return bits;
}
#endif

template <Check check>
std::uint32_t mask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                   const Vec3& end, LaneSides* sides = nullptr) {
#ifdef BSPF_SSE_MASKS
  return sseMask<check>(block, box, start, end, sides);
#else
  return scalarMask<check>(block, box, start, end, sides);
#endif
}

}  // namespace

std::uint32_t boxMask(const CandidateBlock& block, const Bounds& box) {
  return mask<Check::Box>(block, box, Vec3::Zero(), Vec3::Zero());
}

std::uint32_t planesMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                         const Vec3& end, LaneSides& sides) {
  return mask<Check::Planes>(block, box, start, end, &sides);
}

std::uint32_t exactMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                        const Vec3& end) {
  return mask<Check::Exact>(block, box, start, end);
}

std::uint32_t scalarBoxMask(const CandidateBlock& block, const Bounds& box) {
  return scalarMask<Check::Box>(block, box, Vec3::Zero(), Vec3::Zero(), nullptr);
}

std::uint32_t scalarPlanesMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                               const Vec3& end, LaneSides& sides) {
  return scalarMask<Check::Planes>(block, box, start, end, &sides);
}

std::uint32_t scalarExactMask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                              const Vec3& end) {
  return scalarMask<Check::Exact>(block, box, start, end, nullptr);
}

}  // namespace bspf::detail
