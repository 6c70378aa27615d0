// SPDX-License-Identifier: MIT
// The box test and the pre-checks of the narrow phases, a CandidateBlock at a
// time (workspace.h): on x86-64, 4 lanes per SSE instruction (SSE2 is part of
// the baseline every x86-64 CPU has), or all 8 per AVX instruction where the
// CPU has AVX (chosen once, at run time: the build stays for the baseline
// CPU); elsewhere, or with BSPF_SCALAR_MASKS defined, a plain loop. Every
// path computes the same bits with the same float operations in the same
// order (AVX without FMA: no product is fused into a sum), and the tests run
// each path the CPU has against the plain loop
// (tests/runtime/candidate_blocks_test.cpp).
#include "workspace.h"  // defines BSPF_SSE_MASKS where SSE2 is used

#if defined(BSPF_SSE_MASKS) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(BSPF_NO_AVX_MASKS)
#include <immintrin.h>
#define BSPF_AVX_MASKS 1
#endif

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

#ifdef BSPF_AVX_MASKS
// sseMask, 8 lanes at a time. Compiled for AVX alone (not FMA, so products
// and sums round as in the other paths); called only where the CPU has it.
template <Check check>
__attribute__((target("avx"))) std::uint32_t avxMask(const CandidateBlock& block, const Bounds& box,
                                                     const Vec3& start, const Vec3& end,
                                                     LaneSides* sides) {
  static_assert(kBlockLanes == 8 && alignof(CandidateBlock) >= 32 && alignof(LaneSides) >= 32);
  // (No lambdas: they would not be compiled for AVX.)
  __m256 keep = _mm256_and_ps(
      _mm256_cmp_ps(_mm256_load_ps(block.lowX), _mm256_set1_ps(box.high.x()), _CMP_LE_OQ),
      _mm256_cmp_ps(_mm256_set1_ps(box.low.x()), _mm256_load_ps(block.highX), _CMP_LE_OQ));
  keep = _mm256_and_ps(
      keep,
      _mm256_and_ps(
          _mm256_cmp_ps(_mm256_load_ps(block.lowY), _mm256_set1_ps(box.high.y()), _CMP_LE_OQ),
          _mm256_cmp_ps(_mm256_set1_ps(box.low.y()), _mm256_load_ps(block.highY), _CMP_LE_OQ)));
  keep = _mm256_and_ps(
      keep,
      _mm256_and_ps(
          _mm256_cmp_ps(_mm256_load_ps(block.lowZ), _mm256_set1_ps(box.high.z()), _CMP_LE_OQ),
          _mm256_cmp_ps(_mm256_set1_ps(box.low.z()), _mm256_load_ps(block.highZ), _CMP_LE_OQ)));
  if constexpr (check != Check::Box) {
    const __m256 nx = _mm256_load_ps(block.normalX), ny = _mm256_load_ps(block.normalY),
                 nz = _mm256_load_ps(block.normalZ);
    const __m256 distance = _mm256_load_ps(block.distance), reach = _mm256_load_ps(block.reach);
    const __m256 startSide =
        _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, _mm256_set1_ps(start.x())),
                                                  _mm256_mul_ps(ny, _mm256_set1_ps(start.y()))),
                                    _mm256_mul_ps(nz, _mm256_set1_ps(start.z()))),
                      distance);
    const __m256 endSide =
        _mm256_sub_ps(_mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(nx, _mm256_set1_ps(end.x())),
                                                  _mm256_mul_ps(ny, _mm256_set1_ps(end.y()))),
                                    _mm256_mul_ps(nz, _mm256_set1_ps(end.z()))),
                      distance);
    if constexpr (check == Check::Planes) {
      keep = _mm256_and_ps(
          keep, _mm256_and_ps(_mm256_cmp_ps(endSide, reach, _CMP_LT_OQ),
                              _mm256_cmp_ps(startSide, _mm256_setzero_ps(), _CMP_GE_OQ)));
      _mm256_store_ps(sides->start, startSide);
      _mm256_store_ps(sides->end, endSide);
    } else {
      const __m256 inReach = _mm256_or_ps(_mm256_cmp_ps(startSide, reach, _CMP_LE_OQ),
                                          _mm256_cmp_ps(endSide, reach, _CMP_LE_OQ));
      keep = _mm256_and_ps(
          keep,
          _mm256_and_ps(_mm256_cmp_ps(startSide, _mm256_set1_ps(-1e-5f), _CMP_GE_OQ), inReach));
    }
  }
  return std::uint32_t(_mm256_movemask_ps(keep));
}

// Whether this CPU (and its operating system, which must save the wider
// registers) runs AVX: asked once.
bool cpuHasAvx() {
  static const bool has = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx") != 0;
  }();
  return has;
}
#endif

template <Check check>
std::uint32_t maskOn(MaskPath path, const CandidateBlock& block, const Bounds& box,
                     const Vec3& start, const Vec3& end, LaneSides* sides) {
  switch (path) {
#ifdef BSPF_AVX_MASKS
    case MaskPath::Avx: return avxMask<check>(block, box, start, end, sides);
#endif
#ifdef BSPF_SSE_MASKS
    case MaskPath::Sse: return sseMask<check>(block, box, start, end, sides);
#endif
    default: return scalarMask<check>(block, box, start, end, sides);
  }
}

// The widest path this build and CPU run (availableMaskPaths' last), asked
// once.
MaskPath widestPath() {
  static const MaskPath path = availableMaskPaths().back();
  return path;
}

template <Check check>
std::uint32_t mask(const CandidateBlock& block, const Bounds& box, const Vec3& start,
                   const Vec3& end, LaneSides* sides = nullptr) {
  return maskOn<check>(widestPath(), block, box, start, end, sides);
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

namespace {

// The widest paths with the masks' own signatures, so a scan calls the
// chosen one directly, without planesMask's test of the CPU on every block.
#ifdef BSPF_AVX_MASKS
__attribute__((target("avx"))) std::uint32_t avxBoxMask(const CandidateBlock& block,
                                                        const Bounds& box) {
  return avxMask<Check::Box>(block, box, Vec3::Zero(), Vec3::Zero(), nullptr);
}
__attribute__((target("avx"))) std::uint32_t avxPlanesMask(const CandidateBlock& block,
                                                           const Bounds& box, const Vec3& start,
                                                           const Vec3& end, LaneSides& sides) {
  return avxMask<Check::Planes>(block, box, start, end, &sides);
}
__attribute__((target("avx"))) std::uint32_t avxExactMask(const CandidateBlock& block,
                                                          const Bounds& box, const Vec3& start,
                                                          const Vec3& end) {
  return avxMask<Check::Exact>(block, box, start, end, nullptr);
}
#endif

}  // namespace

BoxMaskFunction boxMaskFunction() {
#ifdef BSPF_AVX_MASKS
  if (widestPath() == MaskPath::Avx) return avxBoxMask;
#endif
  return boxMask;
}

PlanesMaskFunction planesMaskFunction() {
#ifdef BSPF_AVX_MASKS
  if (widestPath() == MaskPath::Avx) return avxPlanesMask;
#endif
  return planesMask;
}

ExactMaskFunction exactMaskFunction() {
#ifdef BSPF_AVX_MASKS
  if (widestPath() == MaskPath::Avx) return avxExactMask;
#endif
  return exactMask;
}

std::vector<MaskPath> availableMaskPaths() {
  std::vector<MaskPath> paths{MaskPath::Scalar};
#ifdef BSPF_SSE_MASKS
  paths.push_back(MaskPath::Sse);
#endif
#ifdef BSPF_AVX_MASKS
  if (cpuHasAvx()) paths.push_back(MaskPath::Avx);
#endif
  return paths;
}

std::uint32_t boxMaskOn(MaskPath path, const CandidateBlock& block, const Bounds& box) {
  return maskOn<Check::Box>(path, block, box, Vec3::Zero(), Vec3::Zero(), nullptr);
}

std::uint32_t planesMaskOn(MaskPath path, const CandidateBlock& block, const Bounds& box,
                           const Vec3& start, const Vec3& end, LaneSides& sides) {
  return maskOn<Check::Planes>(path, block, box, start, end, &sides);
}

std::uint32_t exactMaskOn(MaskPath path, const CandidateBlock& block, const Bounds& box,
                          const Vec3& start, const Vec3& end) {
  return maskOn<Check::Exact>(path, block, box, start, end, nullptr);
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
