// SPDX-License-Identifier: MIT
// CollisionMethod::ExactSweep: exact continuous collision of a swept
// ellipsoid against triangles. Everything happens in "sphere space", the
// level scaled by (1/rxz, 1/ry, 1/rxz), where the body is the unit sphere and
// its path a segment; the earliest time of impact of a unit sphere against a
// triangle is the earliest of its face, its three edges and its three
// corners. Triangles are one-sided, as in the planes method: a centre behind
// a triangle's plane ignores it.
#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>

#include "narrow_phase.h"
#include "slide.h"  // (through workspace.h) defines BSPF_SSE_MASKS where SSE2 is used

// The stages' AVX paths where the masks have theirs (candidate_blocks.cpp).
#if defined(BSPF_SSE_MASKS) && (defined(__GNUC__) || defined(__clang__)) && \
    !defined(BSPF_NO_AVX_MASKS)
#include <immintrin.h>
#define BSPF_AVX_SWEEP 1
#endif

namespace bspf {

namespace {

// Smallest root in [0, 1] of a t^2 + b t + c = 0 with c >= 0 (outside at
// t = 0) and the distance shrinking; none when the path misses.
bool earliestRoot(double a, double b, double c, double& t) {
  if (a <= 1e-18 || b >= 0) return false;  // not approaching
  const double discriminant = b * b - 4 * a * c;
  if (discriminant < 0) return false;
  const double root = (-b - std::sqrt(discriminant)) / (2 * a);
  if (root < 0 || root > 1) return false;
  t = root;
  return true;
}

// A lower bound on the time (fraction of the move) after its plane's that
// the unit sphere takes to touch a triangle, from where it touched the
// plane: at a point `squaredGap` (squared) away, in the plane, from every
// point of the triangle, which rises at most `rise` off that plane towards
// the sphere. Every point of the triangle is then at least sqrt(1 +
// squaredGap) - rise from the centre, which must come within 1, moving
// `length` per unit of time; sqrt(1 + x) - 1 = x / (sqrt(1 + x) + 1) >=
// x / (2 + x / 2). That holds before the plane's time too, but a triangle
// rising off its plane can be touched before it, while the centre is less
// than `rise` further from the plane (`approach` per unit of time): then
// no bound (0) unless the gap is wider than what the sphere reaches of the
// plane then (sqrt(2 rise)) and slides meanwhile.
// The slacks: the float normal's length and rounding (1e-6, far above
// both), and the rounding of the edge stage's roots (its worst, a grazing
// path's, is about 1e-8), so an edge stage skipped for the bound would not
// have found an impact before it either. 0 when the gap gives nothing.
double clearanceTime(double squaredGap, double rise, double approach, double length) {
  constexpr double kSlack = 1e-6, kRootSlack = 1e-7;
  const double gap = squaredGap * (1 - kSlack);
  const double early = std::sqrt(2 * rise) + rise * length / approach + kSlack;
  if (!(gap > early * early)) return 0;
  return std::max(0.0, (gap / (2 + gap / 2) - rise - kSlack) / length - kRootSlack);
}

}  // namespace

namespace detail {

// The earliest impact of the unit sphere moving from p along v (t in [0, 1])
// with triangle `tri`, if it comes before `best`, in two stages: the face
// (faceImpact), then the edges and corners (edgeImpact), which only a
// triangle whose face stage leaves it open needs. In double precision, and
// relative to the start point: a body resting on an edge far from the
// triangle's corners loses the contact to cancellation in float.
void earliestImpact(const Triangle& tri, const Vec3& pf, const Vec3& vf, Impact& best,
                    bool& penetrating) {
  const SpherePath path(pf, vf);
  const TriangleD triangle(tri);
  if (faceImpact(triangle, path, best, penetrating) < best.time) edgeImpact(triangle, path, best);
}

bool sweepUsesAvx() {
#ifdef BSPF_AVX_SWEEP
  static const bool avx = availableMaskPaths().back() == MaskPath::Avx;
  return avx;
#else
  return false;
#endif
}

namespace {

#ifdef BSPF_AVX_SWEEP

// The AVX paths of the two stages: a triangle's three edges in lanes 0 to 2
// of one register (lane 3 repeats edge 0 and is never read). Each lane
// takes the reference's operations in the reference's order (sums left to
// right, no product fused into a sum: compiled for AVX alone, not FMA), so
// every value is the reference's bit for bit; only the choices that follow,
// made edge by edge in the reference's order, are scalar.

// The ends of every edge relative to the start p: lane k holds corner k - p
// and corner k + 1 - p, computed as the reference computes them.
struct AvxEdgeEnds {
  __m256d fromX, fromY, fromZ, toX, toY, toZ;
};

__attribute__((target("avx"))) inline AvxEdgeEnds edgeEndsAvx(const TriangleD& tri,
                                                              const Eigen::Vector3d& p) {
  const __m256d px = _mm256_set1_pd(p.x()), py = _mm256_set1_pd(p.y()), pz = _mm256_set1_pd(p.z());
  return {_mm256_sub_pd(_mm256_loadu_pd(tri.cornerX), px),
          _mm256_sub_pd(_mm256_loadu_pd(tri.cornerY), py),
          _mm256_sub_pd(_mm256_loadu_pd(tri.cornerZ), pz),
          _mm256_sub_pd(_mm256_loadu_pd(tri.cornerX + 1), px),
          _mm256_sub_pd(_mm256_loadu_pd(tri.cornerY + 1), py),
          _mm256_sub_pd(_mm256_loadu_pd(tri.cornerZ + 1), pz)};
}

// (x0 * y0 + x1 * y1) + x2 * y2, lane by lane.
__attribute__((target("avx"))) inline __m256d dotAvx(__m256d x0, __m256d x1, __m256d x2, __m256d y0,
                                                     __m256d y1, __m256d y2) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x0, y0), _mm256_mul_pd(x1, y1)),
                       _mm256_mul_pd(x2, y2));
}

// earliestRoot in each lane: the roots, and bit k of `found` set where lane
// k's would return true (its comparisons are ordered: false with a NaN, as
// the scalar ones are).
__attribute__((target("avx"))) inline __m256d earliestRootsAvx(__m256d a, __m256d b, __m256d c,
                                                               int& found) {
  const __m256d zero = _mm256_setzero_pd();
  __m256d missed = _mm256_or_pd(_mm256_cmp_pd(a, _mm256_set1_pd(1e-18), _CMP_LE_OQ),
                                _mm256_cmp_pd(b, zero, _CMP_GE_OQ));
  const __m256d discriminant =
      _mm256_sub_pd(_mm256_mul_pd(b, b), _mm256_mul_pd(_mm256_mul_pd(_mm256_set1_pd(4), a), c));
  missed = _mm256_or_pd(missed, _mm256_cmp_pd(discriminant, zero, _CMP_LT_OQ));
  const __m256d negativeB = _mm256_xor_pd(b, _mm256_set1_pd(-0.0));
  const __m256d root = _mm256_div_pd(_mm256_sub_pd(negativeB, _mm256_sqrt_pd(discriminant)),
                                     _mm256_mul_pd(_mm256_set1_pd(2), a));
  missed = _mm256_or_pd(missed, _mm256_or_pd(_mm256_cmp_pd(root, zero, _CMP_LT_OQ),
                                             _mm256_cmp_pd(root, _mm256_set1_pd(1), _CMP_GT_OQ)));
  found = ~_mm256_movemask_pd(missed) & 7;
  return root;
}

// The face stage's edge test for all three edges: bit k set when edge k's
// side value is not >= 0; `side` and `edgeSquared` receive every edge's.
__attribute__((target("avx"))) int outsideEdgesAvx(const TriangleD& tri, const Eigen::Vector3d& p,
                                                   const Eigen::Vector3d& touch, double (&side)[4],
                                                   double (&edgeSquared)[4]) {
  const AvxEdgeEnds ends = edgeEndsAvx(tri, p);
  const __m256d ex = _mm256_sub_pd(ends.toX, ends.fromX), ey = _mm256_sub_pd(ends.toY, ends.fromY),
                ez = _mm256_sub_pd(ends.toZ, ends.fromZ);
  const __m256d rx = _mm256_sub_pd(_mm256_set1_pd(touch.x()), ends.fromX),
                ry = _mm256_sub_pd(_mm256_set1_pd(touch.y()), ends.fromY),
                rz = _mm256_sub_pd(_mm256_set1_pd(touch.z()), ends.fromZ);
  const __m256d crossX = _mm256_sub_pd(_mm256_mul_pd(ey, rz), _mm256_mul_pd(ez, ry)),
                crossY = _mm256_sub_pd(_mm256_mul_pd(ez, rx), _mm256_mul_pd(ex, rz)),
                crossZ = _mm256_sub_pd(_mm256_mul_pd(ex, ry), _mm256_mul_pd(ey, rx));
  const __m256d sides = dotAvx(_mm256_set1_pd(tri.normal.x()), _mm256_set1_pd(tri.normal.y()),
                               _mm256_set1_pd(tri.normal.z()), crossX, crossY, crossZ);
  const int outside =
      _mm256_movemask_pd(_mm256_cmp_pd(sides, _mm256_setzero_pd(), _CMP_NGE_UQ)) & 7;
  if (outside) {
    _mm256_storeu_pd(side, sides);
    _mm256_storeu_pd(edgeSquared, dotAvx(ex, ey, ez, ex, ey, ez));
  }
  return outside;
}

__attribute__((target("avx"))) void edgeImpactAvx(const TriangleD& tri, const SpherePath& path,
                                                  Impact& best) {
  using V = Eigen::Vector3d;
  const V& v = path.move;
  const AvxEdgeEnds ends = edgeEndsAvx(tri, path.start);
  const __m256d vx = _mm256_set1_pd(v.x()), vy = _mm256_set1_pd(v.y()), vz = _mm256_set1_pd(v.z());
  const __m256d one = _mm256_set1_pd(1), signBit = _mm256_set1_pd(-0.0);
  // Edge k: the infinite cylinder of radius 1 around it.
  const __m256d dx = _mm256_sub_pd(ends.toX, ends.fromX), dy = _mm256_sub_pd(ends.toY, ends.fromY),
                dz = _mm256_sub_pd(ends.toZ, ends.fromZ);
  const __m256d dd = dotAvx(dx, dy, dz, dx, dy, dz);
  const __m256d startX = _mm256_xor_pd(ends.fromX, signBit),
                startY = _mm256_xor_pd(ends.fromY, signBit),
                startZ = _mm256_xor_pd(ends.fromZ, signBit);
  const __m256d alongStart = _mm256_div_pd(dotAvx(startX, startY, startZ, dx, dy, dz), dd);
  const __m256d wx = _mm256_sub_pd(startX, _mm256_mul_pd(alongStart, dx)),
                wy = _mm256_sub_pd(startY, _mm256_mul_pd(alongStart, dy)),
                wz = _mm256_sub_pd(startZ, _mm256_mul_pd(alongStart, dz));
  const __m256d alongMove = _mm256_div_pd(dotAvx(vx, vy, vz, dx, dy, dz), dd);
  const __m256d ux = _mm256_sub_pd(vx, _mm256_mul_pd(alongMove, dx)),
                uy = _mm256_sub_pd(vy, _mm256_mul_pd(alongMove, dy)),
                uz = _mm256_sub_pd(vz, _mm256_mul_pd(alongMove, dz));
  int edgeFound;
  const __m256d edgeRoots =
      earliestRootsAvx(dotAvx(ux, uy, uz, ux, uy, uz),
                       _mm256_mul_pd(_mm256_set1_pd(2), dotAvx(ux, uy, uz, wx, wy, wz)),
                       _mm256_sub_pd(dotAvx(wx, wy, wz, wx, wy, wz), one), edgeFound);
  // Corner k.
  int cornerFound;
  const __m256d cornerRoots = earliestRootsAvx(
      _mm256_set1_pd(path.squaredLength),
      _mm256_mul_pd(_mm256_set1_pd(-2), dotAvx(vx, vy, vz, ends.fromX, ends.fromY, ends.fromZ)),
      _mm256_sub_pd(dotAvx(ends.fromX, ends.fromY, ends.fromZ, ends.fromX, ends.fromY, ends.fromZ),
                    one),
      cornerFound);
  if ((edgeFound | cornerFound) == 0) return;  // the common case: nothing within the move
  alignas(32) double edgeT[4], cornerT[4], fromX[4], fromY[4], fromZ[4], edgeX[4], edgeY[4],
      edgeZ[4], squared[4];
  _mm256_store_pd(edgeT, edgeRoots);
  _mm256_store_pd(cornerT, cornerRoots);
  _mm256_store_pd(fromX, ends.fromX), _mm256_store_pd(fromY, ends.fromY);
  _mm256_store_pd(fromZ, ends.fromZ);
  _mm256_store_pd(edgeX, dx), _mm256_store_pd(edgeY, dy), _mm256_store_pd(edgeZ, dz);
  _mm256_store_pd(squared, dd);
  // The reference's choices, edge k then corner k, in its order.
  for (int k = 0; k < 3; ++k) {
    const V e0(fromX[k], fromY[k], fromZ[k]);
    if ((edgeFound >> k & 1) && edgeT[k] < best.time) {
      const double t = edgeT[k];
      const V d(edgeX[k], edgeY[k], edgeZ[k]);
      const V centre = t * v;
      const double along = (centre - e0).dot(d) / squared[k];
      if (along >= 0 && along <= 1)
        best = {float(t), (centre - (e0 + along * d)).normalized().cast<float>(), true};
    }
    if ((cornerFound >> k & 1) && cornerT[k] < best.time)
      best = {float(cornerT[k]), (cornerT[k] * v - e0).normalized().cast<float>(), true};
  }
}

#endif

// faceImpact, on the AVX path or not, inlined into the slide's scan, which
// runs it for every candidate the masks keep: the call, and the saving and
// restoring of registers around it, took about 15% of its instructions.
[[gnu::always_inline]] inline double faceStage([[maybe_unused]] bool avx, const TriangleD& tri,
                                               const SpherePath& path, Impact& best,
                                               bool& penetrating, MeasuredDistance* measured) {
  using V = Eigen::Vector3d;
  constexpr double kSettled = std::numeric_limits<double>::infinity();
  const V& p = path.start;
  const V& v = path.move;
  const V& n = tri.normal;
  const V a = tri.a - p;  // relative to the start
  const double startSide = -n.dot(a);
  if (startSide < 0) return kSettled;  // behind: one-sided
  if (startSide < 1) {
    // Out of reach of the triangle for the whole move, by the last distance
    // measured, whatever the rounding of this one (1e-9, thousands of times
    // the rounding of either): as settled as the measure would find it.
    if (measured && measured->distance >= 0) {
      const double spare = measured->distance - 1 - path.length - 1e-9;
      if (spare > 0 && (p - measured->from).squaredNorm() < spare * spare) return kSettled;
    }
    // Already within reach (recovery could not clear it all): never let the
    // move go deeper. Moving towards the closest point is an impact now.
    const V closest = closestPointOnTriangle<V>(V::Zero(), a, tri.b - p, tri.c - p);
    const double distance = closest.norm();
    if (measured) *measured = {p, distance};
    if (distance < 1) {
      penetrating = true;
      const V away = distance > 1e-9 ? V(-closest / distance) : n;
      if (away.dot(v) < 0 && 0 < best.time) best = {0.0f, away.cast<float>()};
      return kSettled;
    }
    // Within reach of the plane, not of the triangle: an edge or corner may
    // be touched, but not before the distance has fallen by the gap. The
    // distance to a triangle (a convex set) along a straight move is convex
    // in time, so it never falls faster than at the start, where it falls
    // at `closing` (the move along the line to the closest point) a unit of
    // t: no touch before gap / closing, none at all when it does not fall.
    // (Bounded by the move's whole length instead, a quarter to a third of
    // the candidates left open here started away from the triangle: walkers,
    // exact, oa_dm4, oa_dm5, oacmpctf3.) The 1e-7 given back, and the 1e-6
    // gap below which the bound by the length is kept, are far more than the
    // rounding of either this or the edge stage: it finds the same impacts.
    const double gap = distance - 1;
    if (gap > 1e-6) {
      const double closing = closest.dot(v) / distance;
      if (!(closing > 0)) return kSettled;
      const double earliest = (1 - 1e-7) * gap / closing;
      return earliest < 1 ? earliest : kSettled;
    }
    return gap < path.length ? gap / path.length : kSettled;
  }
  // Outside the plane's reach, the sphere touches no point of the triangle
  // before it touches the plane, at distance 1: if it never does within the
  // move, nothing is touched; if that point of the plane is inside the
  // triangle, it is the first touch.
  const double approach = n.dot(v);
  if (approach >= 0) return kSettled;
  const double t = (startSide - 1) / -approach;
  if (t > 1) return kSettled;
  if (t < best.time) {
    const V touch = t * v - n;
#ifdef BSPF_AVX_SWEEP
    if (avx) {
      double side[4], edgeSquared[4];
      if (const int outside = outsideEdgesAvx(tri, p, touch, side, edgeSquared)) {
        const int k = std::countr_zero(unsigned(outside));  // the reference's first
        return t +
               clearanceTime(side[k] * side[k] / edgeSquared[k], tri.rise, -approach, path.length);
      }
      best = {float(t), n.cast<float>()};
      return kSettled;
    }
#endif
    const V corners[3] = {a, tri.b - p, tri.c - p};
    for (int k = 0; k < 3; ++k) {
      // n . (edge x (touch - corner)), written out as edgeImpact's are.
      const V& from = corners[k];
      const V& to = corners[(k + 1) % 3];
      const double ex = to.x() - from.x(), ey = to.y() - from.y(), ez = to.z() - from.z();
      const double rx = touch.x() - from.x(), ry = touch.y() - from.y(), rz = touch.z() - from.z();
      const double side =
          n.x() * (ey * rz - ez * ry) + n.y() * (ez * rx - ex * rz) + n.z() * (ex * ry - ey * rx);
      // Outside edge k by side / |edge| at least (the edge's part along n
      // only lengthens it), so outside the triangle by that much.
      if (!(side >= 0))
        return t + clearanceTime(side * side / (ex * ex + ey * ey + ez * ez), tri.rise, -approach,
                                 path.length);
    }
    best = {float(t), n.cast<float>()};
    return kSettled;
  }
  return t;
}

}  // namespace

double faceImpact(const TriangleD& tri, const SpherePath& path, Impact& best, bool& penetrating,
                  MeasuredDistance* measured) {
  return faceStage(sweepUsesAvx(), tri, path, best, penetrating, measured);
}

double scalarFaceImpact(const TriangleD& tri, const SpherePath& path, Impact& best,
                        bool& penetrating, MeasuredDistance* measured) {
  return faceStage(false, tri, path, best, penetrating, measured);
}

void scalarEdgeImpact(const TriangleD& tri, const SpherePath& path, Impact& best) {
  using V = Eigen::Vector3d;
  const V& p = path.start;
  const V& v = path.move;
  const V corners[3] = {tri.a - p, tri.b - p, tri.c - p};  // relative to the start
  for (int k = 0; k < 3; ++k) {
    // Edge k: the infinite cylinder of radius 1 around it, then the segment.
    // Written out coordinate by coordinate, in the operations and order of
    // Eigen's (dot products summed x, y, then z), which here spent a third
    // more instructions moving values between packed and scalar registers.
    const V& e0 = corners[k];
    const V& e1 = corners[(k + 1) % 3];
    const double dx = e1.x() - e0.x(), dy = e1.y() - e0.y(), dz = e1.z() - e0.z();
    const double dd = dx * dx + dy * dy + dz * dz;
    // The start and the move, perpendicular to the edge.
    const double alongStart = (-e0.x() * dx + -e0.y() * dy + -e0.z() * dz) / dd;
    const double wx = -e0.x() - alongStart * dx, wy = -e0.y() - alongStart * dy,
                 wz = -e0.z() - alongStart * dz;
    const double alongMove = (v.x() * dx + v.y() * dy + v.z() * dz) / dd;
    const double ux = v.x() - alongMove * dx, uy = v.y() - alongMove * dy,
                 uz = v.z() - alongMove * dz;
    double t;
    if (earliestRoot(ux * ux + uy * uy + uz * uz, 2 * (ux * wx + uy * wy + uz * wz),
                     (wx * wx + wy * wy + wz * wz) - 1, t) &&
        t < best.time) {
      const V d(dx, dy, dz);
      const V centre = t * v;
      const double along = (centre - e0).dot(d) / dd;
      if (along >= 0 && along <= 1)
        best = {float(t), (centre - (e0 + along * d)).normalized().cast<float>(), true};
    }
    // Corner k.
    if (earliestRoot(path.squaredLength, -2 * (v.x() * e0.x() + v.y() * e0.y() + v.z() * e0.z()),
                     (e0.x() * e0.x() + e0.y() * e0.y() + e0.z() * e0.z()) - 1, t) &&
        t < best.time)
      best = {float(t), (t * v - e0).normalized().cast<float>(), true};
  }
}

namespace {

// edgeImpact, on the AVX path or not.
void edgeStage([[maybe_unused]] bool avx, const TriangleD& tri, const SpherePath& path,
               Impact& best) {
#ifdef BSPF_AVX_SWEEP
  if (avx) return edgeImpactAvx(tri, path, best);
#endif
  scalarEdgeImpact(tri, path, best);
}

}  // namespace

void edgeImpact(const TriangleD& tri, const SpherePath& path, Impact& best) {
  edgeStage(sweepUsesAvx(), tri, path, best);
}

Triangle sphereSpaceTriangle(const World& world, std::uint32_t t, const Vec3& toSphere) {
  const schema::Triangle& tri = world.triangles()[t];
  Triangle out;
  out.a = toVec3(world.vertices()[tri.v0()]).cwiseProduct(toSphere);
  out.b = toVec3(world.vertices()[tri.v1()]).cwiseProduct(toSphere);
  out.c = toVec3(world.vertices()[tri.v2()]).cwiseProduct(toSphere);
  out.normal = (out.b - out.a).cross(out.c - out.a).normalized();
  return out;
}

FaceTest exactFaceTest(const World& world, std::uint32_t triangle, EllipsoidRadii radii) {
  const schema::Plane& face = world.trianglePlanes()[triangle].face();
  const Vec3 normal = toVec3(face.normal());
  // The reach is padded so float rounding in the pre-check never drops a
  // triangle the sphere touches.
  return {normal, face.distance(), effectiveRadius(normal, radii) * 1.0001f + 1e-5f};
}

}  // namespace detail

namespace {

using detail::Impact;
using detail::sphereSpaceTriangle;
using detail::Triangle;

// The exact sweep's candidates: LocalCandidates with each triangle scaled
// into sphere space on first use (most candidates never pass the box test
// and the pre-check).
template <typename Make>
class ExactCandidates : public LocalCandidates<detail::ExactCold, Make> {
 public:
  ExactCandidates(const World& world, const Vec3& toSphere, detail::StepWorkspace& workspace,
                  Make make)
      : LocalCandidates<detail::ExactCold, Make>(detail::activeExact(workspace), workspace.listed,
                                                 workspace.sorted, make),
        world_(world),
        toSphere_(toSphere) {}

  /// The candidate in `slot`, in sphere space.
  detail::ExactCold& made(std::uint32_t slot) {
    detail::ExactCold& cold = (*this)[slot];
    if (cold.madeIn != this->generation()) {
      cold.triangle = this->triangle(slot);
      cold.sphere = detail::TriangleD(sphereSpaceTriangle(world_, cold.triangle, toSphere_));
      cold.measured.distance = -1;
      cold.madeIn = this->generation();
    }
    return cold;
  }

 private:
  const World& world_;
  Vec3 toSphere_;
};

// How far the unit sphere at `p` (sphere space) rests in front of the plane
// of `tri` when it rests there at the gap `padding` (within rounding) and
// `move` presses it into the plane far enough to meet it; else 0.
double restingGap(const detail::TriangleD& tri, const Eigen::Vector3d& p,
                  const Eigen::Vector3d& move, float padding) {
  // The gap the slide leaves is made in float, about 1e-5 off in sphere
  // space at 100 m from the origin: a tenth of the default skin's.
  constexpr double kGapTolerance = 1e-4;
  const double side = tri.normal.dot(p - tri.a);
  const double approach = tri.normal.dot(move);
  if (!(std::abs(side - 1 - padding) <= kGapTolerance) || !(-approach >= side - 1)) return 0;
  return side;
}

// Whether the centre moving from `p`, `side` in front of the plane of `tri`,
// along `move` is over the inside of the face where it meets the plane: the
// sweep then meets the face there, unless it meets something else first (no
// edge or corner of the triangle sooner: they lie in the plane). Checked
// where it meets the plane, not at the start: a fast body may be past the
// face by then, and meet what lies beyond it.
bool meetsFace(const detail::TriangleD& tri, const Eigen::Vector3d& p, const Eigen::Vector3d& move,
               double side) {
  const Eigen::Vector3d meets = p + ((side - 1) / -tri.normal.dot(move)) * move;
  const Eigen::Vector3d corners[3] = {tri.a, tri.b, tri.c};
  for (int k = 0; k < 3; ++k) {
    // Inside edge k: n . (edge x (point - its start)) > 0, as the face stage
    // measures it, written (n x edge) . (point - its start).
    const Eigen::Vector3d inward = tri.normal.cross(corners[(k + 1) % 3] - corners[k]);
    if (!(inward.dot(meets - corners[k]) > 0)) return false;
  }
  return true;
}

// The world-space unit normal of a sphere-space normal: normals scale by the
// inverse of the position scale, so by (1/rxz, 1/ry, 1/rxz) again.
Vec3 worldNormal(const Vec3& sphereNormal, const Vec3& toSphere) {
  return sphereNormal.cwiseProduct(toSphere).normalized();
}

void addContact(SlideResult& result, const Vec3& normal, float walkableNormalY, bool edge,
                const Vec3& point, std::uint32_t triangle) {
  if (result.contactCount < kMaxReportedContacts)
    result.contacts[result.contactCount++] = {normal, normal.y() >= walkableNormalY, edge, point,
                                              triangle};
}

// Pushes a centre that starts within the unit distance of triangles (in
// front of them: penetration) out along each closest-point direction, to
// 1 + padding, in up to 8 rounds.
// `local` is the slide's own candidate list (LocalCandidates).
void recoverFromPenetration(const World& world, Vec3& p, const Vec3& toSphere, float padding,
                            float walkableNormalY, EllipsoidRadii radii, float moveLength,
                            auto& local, StepScratch& scratch, SlideResult& result) {
  // Gauss-Seidel: each round pushes out of every penetrated triangle in
  // turn, so a body wedged in a crease leaves it along the bisector instead
  // of bouncing between the two sides.
  for (int round = 0; round < 8; ++round) {
    const Vec3 centre = p.cwiseQuotient(toSphere);
    const Bounds here = sweptBounds(centre, centre, radii);
    bool pushed = false;
    const detail::BlockBoxTest boxTest(here);
    for (const detail::CandidateBlock* const block :
         local.around(world, here, moveLength, radii, scratch)) {
      if (!boxTest.meets(*block)) continue;
      for (std::uint32_t bits = detail::boxMask(*block, here); bits != 0; bits &= bits - 1) {
        const std::uint32_t slot = block->slot[std::countr_zero(bits)];
        const detail::TriangleD& triangle = local.made(slot).sphere;
        // The float triangle (exact: the double one was made from it).
        const Triangle tri{triangle.a.cast<float>(), triangle.b.cast<float>(),
                           triangle.c.cast<float>(), triangle.normal.cast<float>()};
        if (tri.normal.dot(p - tri.a) < 0) continue;
        const Vec3 closest = closestPointOnTriangle<Vec3>(p, tri.a, tri.b, tri.c);
        const Vec3 offset = p - closest;
        const float distance = offset.norm();
        if (distance >= 1) continue;  // within the padding is not penetration
        const Vec3 away = distance > 1e-6f ? Vec3(offset / distance) : tri.normal;
        p += away * (1 + padding - distance);
        pushed = true;
        addContact(result, worldNormal(away, toSphere), walkableNormalY, false,
                   closest.cwiseQuotient(toSphere), local.triangle(slot));
      }
    }
    if (!pushed) return;
  }
}

}  // namespace

namespace {

// slideExact, saying in `restingSlides` how many of its slides were along
// surfaces it rested on at its start.
SlideResult sweepAndSlide(const World& world, const Vec3& start, const Vec3& desiredEnd,
                          EllipsoidRadii radii, const MovementSettings& settings,
                          float walkableNormalY, StepScratch& scratch,
                          std::span<const std::uint32_t> hints,
                          std::span<const std::uint32_t> wallHints, int& restingSlides) {
  SlideResult result;
  const Vec3 toSphere(1 / radii.xz, 1 / radii.y, 1 / radii.xz);
  // The skin in sphere units, so the world gap is at least `skin`.
  const float padding = settings.skin / std::max(radii.xz, radii.y);
  Vec3 p = start.cwiseProduct(toSphere);
  Vec3 move = (desiredEnd - start).cwiseProduct(toSphere);

  std::array<Vec3, 3> planes;  // world-space normals slid along this step
  int planeCount = 0;
  bool recovered = false;
  const float moveLength = (desiredEnd - start).norm();
  detail::StepWorkspace& workspace = scratch.workspace();
  ExactCandidates local(world, toSphere, workspace, [&](std::uint32_t triangle) {
    return detail::exactFaceTest(world, triangle, radii);
  });
  std::vector<std::pair<double, std::uint32_t>>& open = workspace.open;
  const detail::ExactMaskFunction exactMask = detail::exactMaskFunction();
  const bool avx = detail::sweepUsesAvx();
  // The slide along a surface met (world unit normal `normal`, from the
  // sphere-space impact `impact`, at `touched`, world): the rest of the
  // move goes on along it (or along the crease it makes with an earlier
  // one), and the contact is recorded.
  auto slideAlong = [&](const Impact& impact, const Vec3& normal, bool walkable,
                        const Vec3& touched, std::uint32_t triangle) {
    // The rest of the move slides in world space, as the planes method's
    // does (and the classic write-ups). Removing the normal part in sphere
    // space instead removes it along the world normal scaled by the squared
    // radii: a body slid down a 60 degree slope at 0.61 of the right speed,
    // and was lifted up steep slopes and risers. Both spaces agree on which
    // side of a plane a vector points (the dot products have the same sign),
    // so the slid move is tangent in sphere space too.
    Vec3 rest = ((1 - impact.time) * move).cwiseQuotient(toSphere);
    if (walkable) {
      // On walkable ground keep the horizontal move and follow the slope:
      // the fall is cancelled, so gravity does not creep a body downhill.
      rest.y() = -(normal.x() * rest.x() + normal.z() * rest.z()) / normal.y();
    } else {
      if (impact.edge && normal.y() > 0) {
        // A rounded edge met steep and low on the body is the top of a wall
        // (a riser, a ledge), which the planes method meets as the wall:
        // the part of the move going into it horizontally stops there, as
        // against the wall, instead of lifting the body over the edge; what
        // still goes into the edge (a fall) slides off it.
        const Vec3 wall = Vec3(normal.x(), 0, normal.z()).normalized();
        rest -= std::min(0.0f, rest.dot(wall)) * wall;
        rest -= std::min(0.0f, rest.dot(normal)) * normal;
      } else {
        rest -= rest.dot(normal) * normal;
      }
    }
    // In a crease the slide along this surface may lead back into an earlier
    // one: follow the crease line (the cross product of the world normals)
    // instead; in a corner of three, stop.
    for (int i = 0; i < planeCount; ++i) {
      if (rest.dot(planes[i]) >= 0 || planes[i].dot(normal) > 0.9999f) continue;
      const Vec3 crease = planes[i].cross(normal);
      const float length = crease.norm();
      if (length < 1e-4f || planeCount >= 2) {
        rest.setZero();
        break;
      }
      const Vec3 along = crease / length;
      rest = rest.dot(along) * along;
    }
    if (planeCount < int(planes.size())) planes[planeCount++] = normal;
    move = rest.cwiseProduct(toSphere);
    ++result.iterations;
    addContact(result, normal, walkableNormalY, impact.edge, touched, triangle);
  };
  // A body resting on the ground it stood on last step (a hint), its move
  // pressing into it (a walker's frame of gravity), slides along that ground
  // from its start: the first sweep would have met the ground within the
  // move, after the gap the body rests at, and slid the rest of the move
  // along it from there, which takes the body where this does. Then, as
  // much, the walls it rests against. So a walking step sweeps once, not
  // once more for each surface it rests on. Everything the move meets is
  // still swept, and each of these slides is one of its maxIterations.
  // Where the sweep would have met another surface first and slid off the
  // one rested on, the slide along it is one more than the sweep would have
  // made, and a move left refused is made again without these (slideExact):
  // so each is taken only while the move keeps this many slides for what
  // its sweeps meet (with fewer, at 1 and 2 iterations, the chart's crowds
  // on oacmpdm5, oa_dm5 and slopes ran out of slides 1.2 and 1.8 times as
  // often).
  int firstIteration = 0;
  constexpr int kSlidesKeptAfterResting = 3;
  auto slideOnResting = [&](std::span<const std::uint32_t> triangles, bool ground, int most) {
    for (const std::uint32_t t : triangles) {
      if (most == 0 || firstIteration + kSlidesKeptAfterResting > settings.maxIterations) return;
      const auto lane = t == kNoTriangle ? std::nullopt : local.laneOf(t);
      if (!lane) continue;
      const detail::TriangleD& face = local.made(lane->first->slot[lane->second]).sphere;
      const Eigen::Vector3d from = p.cast<double>(), along = move.cast<double>();
      const double side = restingGap(face, from, along, padding);
      if (!(side > 0)) continue;
      const Vec3 faceNormal = face.normal.cast<float>();
      const Vec3 normal = worldNormal(faceNormal, toSphere);
      if ((normal.y() >= walkableNormalY) != ground || !meetsFace(face, from, along, side))
        continue;
      const Vec3 touched = (p - float(side) * faceNormal).cwiseQuotient(toSphere);
      slideAlong({0.0f, faceNormal, false}, normal, ground, touched, t);
      ++firstIteration;
      --most;
    }
  };
  if (!hints.empty() || !wallHints.empty()) {
    const Vec3 from = p.cwiseQuotient(toSphere);
    local.around(world, detail::slideSweptBounds(from, (p + move).cwiseQuotient(toSphere), radii),
                 moveLength, radii, scratch, desiredEnd - start);
    slideOnResting(hints, true, 1);
    slideOnResting(wallHints, false, kWallTriangles);
  }
  for (int iteration = firstIteration;; ++iteration) {
    // A move the ground took all of (a body standing still) is still swept
    // once, as its first sweep was: for a start in penetration.
    const bool firstSweep = iteration == firstIteration && !recovered;
    if (move.squaredNorm() < 1e-14f && !(firstSweep && firstIteration > 0)) break;
    const Vec3 from = p.cwiseQuotient(toSphere);
    const Vec3 to = (p + move).cwiseQuotient(toSphere);
    const Bounds swept = detail::slideSweptBounds(from, to, radii);
    Impact impact;
    std::uint32_t impactSlot = 0;  // the candidate `impact` is with
    bool penetrating = false;
    // The face stage for every candidate the box and the side-value
    // pre-check keep (a path that stays more than the body's extent in
    // front of the plane, or starts behind it, cannot touch the triangle),
    // then the edge stage only for those whose face stage left them open
    // and could come before the earliest impact found so far: on the
    // ground, the face under the body settles its neighbours.
    open.clear();
    const detail::SpherePath path(p, move);
    const detail::BlockBoxTest boxTest(swept);
    for (const detail::CandidateBlock* const block :
         local.around(world, swept, moveLength, radii, scratch, desiredEnd - start)) {
      if (!boxTest.meets(*block)) continue;
      for (std::uint32_t bits = exactMask(*block, swept, from, to); bits != 0; bits &= bits - 1) {
        const std::uint32_t slot = block->slot[std::countr_zero(bits)];
        const float before = impact.time;  // every new impact is earlier
        detail::ExactCold& cold = local.made(slot);
        const double earliest =
            detail::faceStage(avx, cold.sphere, path, impact, penetrating, &cold.measured);
        if (impact.time != before) impactSlot = slot;
        if (earliest < 1) open.push_back({earliest, slot});
      }
    }
    for (const auto& [earliest, slot] : open)
      if (earliest < impact.time) {
        const float before = impact.time;
        detail::edgeStage(avx, local.made(slot).sphere, path, impact);
        if (impact.time != before) impactSlot = slot;
      }
    // A start in penetration (pushed there by another body, or placed there)
    // is first moved out, then the sweep is made again from there.
    if (penetrating && firstSweep) {
      recovered = true;
      recoverFromPenetration(world, p, toSphere, padding, walkableNormalY, radii, moveLength, local,
                             scratch, result);
      --iteration;
      continue;
    }
    if (impact.time > 1) {
      p += move;
      break;
    }
    if (iteration == settings.maxIterations) {
      result.refused = true;
      break;  // p is the last contact point: a safe position
    }
    // Advance to the contact, then step back out to the padding along the
    // contact normal (stepping back along the velocity, as the well-known
    // write-ups do, leaves a grazing body inside the padding).
    p += impact.time * move;
    const Vec3 touched = (p - impact.normal).cwiseQuotient(toSphere);
    const Vec3 normal = worldNormal(impact.normal, toSphere);
    const bool walkable = normal.y() >= walkableNormalY;
    // On walkable ground the gap is made straight up: along a slope's normal
    // it would step the body downhill a little every frame.
    const float gap = impact.normal.dot(move) < 0 ? padding : 0;
    p += walkable ? Vec3(0, gap / impact.normal.y(), 0) : Vec3(impact.normal * gap);
    slideAlong(impact, normal, walkable, touched, local.triangle(impactSlot));
  }
  result.end = p.cwiseQuotient(toSphere);
  restingSlides = firstIteration;
  return result;
}

}  // namespace

SlideResult slideExact(const World& world, const Vec3& start, const Vec3& desiredEnd,
                       EllipsoidRadii radii, const MovementSettings& settings,
                       float walkableNormalY, StepScratch& scratch,
                       std::span<const std::uint32_t> hints,
                       std::span<const std::uint32_t> wallHints) {
  int restingSlides = 0;
  SlideResult result = sweepAndSlide(world, start, desiredEnd, radii, settings, walkableNormalY,
                                     scratch, hints, wallHints, restingSlides);
  // The slides along the surfaces rested on may spend a slide the sweeps
  // alone would not make (where a sweep meets another surface first and
  // slides off the one rested on): a move they leave refused is made again
  // without them, so they never refuse a move the sweeps alone would make.
  if (result.refused && restingSlides > 0)
    result = sweepAndSlide(world, start, desiredEnd, radii, settings, walkableNormalY, scratch, {},
                           {}, restingSlides);
  return result;
}

}  // namespace bspf
