#include <bspf/query.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <random>

#include "support/exact_geometry.h"
#include "support/test_support.h"

using bspf::EllipsoidRadii;
using bspf::Vec3;

namespace {

Eigen::Vector3d corner(const bspf::World& world, std::uint32_t vertex) {
  return bspf::toVec3(world.vertices()[vertex]).cast<double>();
}

struct Sweep {
  Vec3 from, to;
  EllipsoidRadii radii;
};

// Sweeps of all sizes, half starting near a surface (where bodies are), half
// anywhere in the level's bounds.
std::vector<Sweep> randomSweeps(const bspf::World& world, int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::normal_distribution<float> gauss;
  std::uniform_int_distribution<std::size_t> pick(0, world.triangles().size() - 1);
  const Vec3 low = bspf::toVec3(*world.blob().bounds_min());
  const Vec3 high = bspf::toVec3(*world.blob().bounds_max());
  std::vector<Sweep> sweeps;
  for (int i = 0; i < count; ++i) {
    Sweep s;
    s.radii = {0.05f + 1.5f * unit(rng), 0.05f + 2.0f * unit(rng)};
    if (i % 2 == 0) {
      const std::size_t t = pick(rng);
      const auto& tri = world.triangles()[t];
      float u = unit(rng), v = unit(rng);
      if (u + v > 1) u = 1 - u, v = 1 - v;
      const Vec3 a = bspf::toVec3(world.vertices()[tri.v0()]);
      const Vec3 b = bspf::toVec3(world.vertices()[tri.v1()]);
      const Vec3 c = bspf::toVec3(world.vertices()[tri.v2()]);
      const Vec3 n = bspf::toVec3(world.trianglePlanes()[t].face().normal());
      s.from = a + u * (b - a) + v * (c - a) + n * (3.0f * unit(rng) - 1.0f);
    } else {
      s.from = low + (high - low).cwiseProduct(Vec3(unit(rng), unit(rng), unit(rng)));
    }
    const Vec3 direction = Vec3(gauss(rng), gauss(rng), gauss(rng)).normalized();
    s.to = s.from + direction * (i % 7 == 0 ? 0.f : 4.0f * unit(rng) * unit(rng));
    sweeps.push_back(s);
  }
  return sweeps;
}

// Every triangle the swept volume touches (exact oracle) is a candidate.
void requireNoTouchedTriangleMissed(const bspf::World& world, int sweepCount) {
  bspf::SweepScratch scratch;
  std::vector<std::uint32_t> candidates;
  std::vector<char> isCandidate(world.triangles().size());
  std::size_t touchedTotal = 0, candidateTotal = 0;
  for (const Sweep& s : randomSweeps(world, sweepCount, 1234)) {
    bspf::collectCandidateTriangles(world, s.from, s.to, s.radii, scratch, candidates);
    std::fill(isCandidate.begin(), isCandidate.end(), 0);
    for (const std::uint32_t t : candidates) isCandidate[t] = 1;
    for (std::uint32_t t = 0; t < world.triangles().size(); ++t) {
      const auto& tri = world.triangles()[t];
      if (!bspf::test::sweptEllipsoidTouchesTriangle(
              s.from.cast<double>(), s.to.cast<double>(), s.radii, corner(world, tri.v0()),
              corner(world, tri.v1()), corner(world, tri.v2())))
        continue;
      ++touchedTotal;
      if (!isCandidate[t]) {
        INFO("triangle " << t << " missed; sweep from " << s.from.transpose() << " to "
                         << s.to.transpose() << " radii " << s.radii.xz << ", " << s.radii.y);
        REQUIRE(isCandidate[t]);
      }
    }
    candidateTotal += candidates.size();
    // Each candidate listed once.
    std::sort(candidates.begin(), candidates.end());
    REQUIRE(std::adjacent_find(candidates.begin(), candidates.end()) == candidates.end());
  }
  // The oracle must have had work to do, or the test proves nothing.
  REQUIRE(touchedTotal > std::size_t(sweepCount));
  // The broad phase must prune: far fewer candidates than the whole level.
  REQUIRE(double(candidateTotal) / sweepCount < 0.5 * double(world.triangles().size()));
}

}  // namespace

TEST_CASE("the swept-leaf query lists every triangle a swept ellipsoid touches, on the arena",
          "[runtime][query]") {
  const bspf::World world = bspf::test::compileSample("arena");
  requireNoTouchedTriangleMissed(world, 4000);
}

TEST_CASE("the swept-leaf query lists every triangle a swept ellipsoid touches, on a random soup",
          "[runtime][query]") {
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> coordinate(-10, 10), offset(-1.5, 1.5);
  bspc::Mesh soup;
  for (int i = 0; i < 600; ++i) {
    const Eigen::Vector3d a(coordinate(rng), coordinate(rng), coordinate(rng));
    soup.vertices.push_back(a);
    soup.vertices.push_back(a + Eigen::Vector3d(offset(rng), offset(rng), offset(rng)));
    soup.vertices.push_back(a + Eigen::Vector3d(offset(rng), offset(rng), offset(rng)));
    soup.triangles.push_back({3u * i, 3u * i + 1, 3u * i + 2});
  }
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = 2;  // a deep tree: many planes to get wrong
  const bspf::test::AlignedBytes bytes(bspf::test::compile(soup, settings));
  const bspf::OpenResult opened = bspf::viewWorld(bytes.span());
  REQUIRE(opened);
  REQUIRE(opened.world->treeDepth() > 8);
  requireNoTouchedTriangleMissed(*opened.world, 3000);
}

TEST_CASE("the swept-leaf query lists every triangle a swept ellipsoid touches, on shared levels",
          "[runtime][query][shared-levels]") {
  BSPF_SKIP_WITHOUT_SHARED_LEVELS();
  const auto dir = bspf::test::sharedLevelsDir();
  for (const std::string name : {"fan", "oa_dm1"}) {
    SECTION(name) {
      const std::filesystem::path out = bspf::test::freshTempDir("query") / (name + ".bspf");
      bspc::compileFile(dir / (name + ".obj"), out, {});
      const bspf::OpenResult opened = bspf::openWorld(out);
      REQUIRE(opened);
      requireNoTouchedTriangleMissed(*opened.world, name == "fan" ? 3000 : 600);
    }
  }
}

TEST_CASE("the swept-leaf query lists leaves in the order the path passes them",
          "[runtime][query]") {
  const bspf::World world = bspf::test::compileSample("arena");
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  const Vec3 low = bspf::toVec3(*world.blob().bounds_min());
  const Vec3 high = bspf::toVec3(*world.blob().bounds_max());
  const EllipsoidRadii point{1e-4f, 1e-4f};  // a near-point sweep: a line through the cells
  std::vector<std::uint32_t> leaves;
  int checked = 0;
  for (int i = 0; i < 500; ++i) {
    const Vec3 from = low + (high - low).cwiseProduct(Vec3(unit(rng), unit(rng), unit(rng)));
    const Vec3 to = low + (high - low).cwiseProduct(Vec3(unit(rng), unit(rng), unit(rng)));
    leaves.clear();
    bspf::collectSweptLeaves(world, from, to, point, leaves);
    REQUIRE(!leaves.empty());
    REQUIRE(leaves.front() == bspf::locateLeaf(world, from));
    // The cells met walking the segment appear in the result in that order.
    std::vector<std::uint32_t> walked;
    for (int k = 0; k <= 2000; ++k) {
      const std::uint32_t leaf = bspf::locateLeaf(world, from + (to - from) * (k / 2000.f));
      if (walked.empty() || walked.back() != leaf) walked.push_back(leaf);
    }
    std::size_t position = 0;
    for (const std::uint32_t leaf : walked) {
      const auto found = std::find(leaves.begin() + position, leaves.end(), leaf);
      INFO("walk " << i << ": leaf " << leaf << " out of order or missing");
      REQUIRE(found != leaves.end());
      position = static_cast<std::size_t>(found - leaves.begin());
    }
    checked += walked.size() > 2;
  }
  REQUIRE(checked > 100);  // most walks cross several cells
}

TEST_CASE(
    "the swept-leaf query lists the far side of a split plane that the volume comes within "
    "kSweepMarginMetres of, and not beyond",
    "[runtime][query]") {
  // The root's split plane of a two-box level; every leaf behind it.
  bspc::Mesh mesh = bspf::test::boxMesh({-3, 0, -1}, {-1, 1, 1});
  bspf::test::append(mesh, bspf::test::boxMesh({1, 0, -1}, {3, 1, 1}));
  const bspf::test::AlignedBytes bytes(bspf::test::compile(mesh));
  const bspf::World world = *bspf::viewWorld(bytes.span()).world;
  REQUIRE(world.root() >= 0);
  const bspf::schema::Node& root = world.nodes()[world.root()];
  std::vector<std::uint32_t> behind;
  std::vector<std::int32_t> stack{root.back()};
  while (!stack.empty()) {
    const std::int32_t ref = stack.back();
    stack.pop_back();
    if (ref < 0) {
      behind.push_back(static_cast<std::uint32_t>(-(ref + 1)));
    } else {
      stack.push_back(world.nodes()[ref].front());
      stack.push_back(world.nodes()[ref].back());
    }
  }
  const Vec3 normal = bspf::toVec3(root.split().normal());
  const Vec3 onPlane = normal * root.split().distance();
  const EllipsoidRadii radii{0.45f, 0.85f};
  const float reach = bspf::effectiveRadius(normal, radii);
  // The margin grows with the plane's offset (float rounding), a little.
  const float slack = 4e-7f * std::abs(root.split().distance()) + 1e-6f;
  auto listsALeafBehind = [&](float gap) {
    const Vec3 centre = onPlane + normal * (reach + gap);
    std::vector<std::uint32_t> leaves;
    bspf::collectSweptLeaves(world, centre, centre, radii, leaves);
    return std::any_of(leaves.begin(), leaves.end(), [&](std::uint32_t leaf) {
      return std::find(behind.begin(), behind.end(), leaf) != behind.end();
    });
  };
  REQUIRE(listsALeafBehind(0.5f * bspf::kSweepMarginMetres));
  REQUIRE(listsALeafBehind(bspf::kSweepMarginMetres - slack));
  REQUIRE_FALSE(listsALeafBehind(bspf::kSweepMarginMetres + 2 * slack + 1e-5f));
  REQUIRE_FALSE(listsALeafBehind(0.01f));
}
