// SPDX-License-Identifier: MIT
// dropCoveredFaces, classifyEdges and meetablePlanes: which faces and which
// of a triangle's planes a body can meet, decided on small meshes.
#include <bspc/clean.h>
#include <bspc/edges.h>
#include <bspc/mesh.h>

#include <algorithm>
#include <catch2/catch.hpp>

#include "support/test_support.h"

namespace {

using bspc::EdgeKind;
using bspf::test::append;
using bspf::test::boxMesh;
using bspf::test::cleaned;
using Eigen::Vector3d;

// The kinds of every edge of `mesh`, counted.
std::array<int, 4> kindCounts(const bspc::Mesh& mesh) {
  std::array<int, 4> counts{};
  for (const bspc::TriangleEdges& triangle : bspc::classifyEdges(mesh))
    for (const EdgeKind kind : triangle.kind) ++counts[static_cast<int>(kind)];
  return counts;
}

int countOf(const std::array<int, 4>& counts, EdgeKind kind) {
  return counts[static_cast<int>(kind)];
}

// A unit square in the plane y = `height`, facing up, as two triangles.
bspc::Mesh square(double x0, double height) {
  bspc::Mesh mesh;
  mesh.vertices = {{x0, height, 0}, {x0, height, 1}, {x0 + 1, height, 1}, {x0 + 1, height, 0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  return mesh;
}

// Triangles of `mesh` whose normal is `normal` and whose centroid lies
// within `distance` of the plane normal . p = offset.
int facesOn(const bspc::Mesh& mesh, const Vector3d& normal, double offset) {
  int count = 0;
  for (const auto& t : mesh.triangles) {
    const Vector3d a = mesh.vertices[t[0]], b = mesh.vertices[t[1]], c = mesh.vertices[t[2]];
    const Vector3d n = (b - a).cross(c - a).normalized();
    count += n.dot(normal) > 0.999 && std::abs(normal.dot((a + b + c) / 3) - offset) < 1e-9;
  }
  return count;
}

}  // namespace

TEST_CASE(
    "two coplanar triangles of a square: their shared edge is coplanar and mirrored, its plane "
    "kept unless asked to skip it") {
  const bspc::Mesh mesh = cleaned(square(0, 0));
  const auto edges = bspc::classifyEdges(mesh);
  REQUIRE(edges.size() == 2);
  // Square (0,1,2),(0,2,3): edge 2 of the first (2 -> 0) and edge 0 of the
  // second (0 -> 2) are the diagonal.
  CHECK(edges[0].kind == std::array{EdgeKind::Open, EdgeKind::Open, EdgeKind::Coplanar});
  CHECK(edges[1].kind == std::array{EdgeKind::Coplanar, EdgeKind::Open, EdgeKind::Open});
  CHECK(edges[0].mirrored == std::array{false, false, true});
  bspc::EdgeReport report;
  const auto masks = bspc::meetablePlanes(edges, report, /*skipMirrored=*/true);
  CHECK(masks[0] == 0b111011);  // edge 2 skipped, caps kept
  CHECK(masks[1] == 0b111110);
  CHECK(report.skippedEdgePlanes == 2);
  CHECK(report.open == 4);
  // As bspc compiles: every plane kept.
  bspc::EdgeReport kept;
  for (const std::uint8_t mask : bspc::meetablePlanes(edges, kept)) CHECK(mask == 0b111111);
  CHECK(kept.skippedEdgePlanes == 0);
}

TEST_CASE("coplanar triangles that do not make a parallelogram keep the shared edge's plane") {
  // A fan of three triangles about a corner of a floor: coplanar edges, but
  // beyond each the neighbour is not the triangle's mirror image.
  bspc::Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {0, 0, 2}, {1, 0, 2}, {2, 0, 1}, {2, 0, 0}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}};
  const auto edges = bspc::classifyEdges(cleaned(mesh));
  CHECK(edges[1].kind == std::array{EdgeKind::Coplanar, EdgeKind::Open, EdgeKind::Coplanar});
  CHECK(edges[1].mirrored == std::array{false, false, false});
  bspc::EdgeReport report;
  for (const std::uint8_t mask : bspc::meetablePlanes(edges, report, true)) CHECK(mask == 0b111111);
  CHECK(report.coplanar == 4);
  CHECK(report.skippedEdgePlanes == 0);
}

TEST_CASE("a closed box's edges are all convex and keep every plane") {
  const bspc::Mesh box = cleaned(boxMesh({0, 0, 0}, {1, 2, 3}));
  const auto counts = kindCounts(box);
  // 12 box edges seen from both sides, the 6 face diagonals from both.
  CHECK(countOf(counts, EdgeKind::Convex) == 24);
  CHECK(countOf(counts, EdgeKind::Coplanar) == 12);
  CHECK(countOf(counts, EdgeKind::Open) == 0);
  CHECK(countOf(counts, EdgeKind::Concave) == 0);
  bspc::EdgeReport report;
  for (const std::uint8_t mask : bspc::meetablePlanes(bspc::classifyEdges(box), report, true))
    CHECK((mask & 0b111000) == 0b111000);
  CHECK(report.skippedEdgePlanes == 12);  // the diagonals only
}

TEST_CASE("a floor meeting a wall in a concave corner: the edge is concave from both sides") {
  // Floor y = 0 for z in [0, 1], facing up; wall z = 1 rising from it, facing -z.
  bspc::Mesh mesh;
  mesh.vertices = {{0, 0, 0}, {0, 0, 1}, {1, 0, 1}, {1, 0, 0}, {0, 1, 1}, {1, 1, 1}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}, {1, 4, 5}, {1, 5, 2}};
  const bspc::Mesh clean = cleaned(mesh);
  const auto counts = kindCounts(clean);
  CHECK(countOf(counts, EdgeKind::Concave) == 2);  // the corner edge, from each side
  CHECK(countOf(counts, EdgeKind::Coplanar) == 4);
  CHECK(countOf(counts, EdgeKind::Open) == 6);
  CHECK(countOf(counts, EdgeKind::Convex) == 0);
}

TEST_CASE("the back of a two-sided surface met first keeps the edge's plane") {
  // A floor square whose second half is two-sided: the first face met past
  // the diagonal from the front is the underside pair's upper triangle.
  bspc::Mesh mesh = square(0, 0);
  mesh.triangles.push_back({0, 3, 2});  // the second triangle, wound the other way
  const auto edges = bspc::classifyEdges(cleaned(mesh));
  REQUIRE(edges.size() == 3);
  // The diagonal seen from the first triangle meets the coplanar upper face.
  CHECK(edges[0].kind[2] == EdgeKind::Coplanar);
  // The underside's diagonal: turning from its front (down) meets the first
  // triangle's back only after 180 degrees: wound the other way, kept.
  CHECK(edges[2].kind[2] == EdgeKind::Convex);
}

TEST_CASE("two touching boxes: the faces pressed together are dropped, every other face kept") {
  bspc::Mesh mesh = boxMesh({0, 0, 0}, {1, 1, 1});
  append(mesh, boxMesh({1, 0, 0}, {2, 1, 1}));
  const bspc::Mesh clean = cleaned(mesh);
  bspc::EdgeReport report;
  const bspc::Mesh kept = bspc::dropCoveredFaces(clean, report);
  CHECK(report.droppedCovered == 4);
  CHECK(kept.triangles.size() == 20);
  CHECK(facesOn(kept, {1, 0, 0}, 1) == 0);
  CHECK(facesOn(kept, {-1, 0, 0}, -1) == 0);
  // The tops of the two boxes now meet edge to edge: the seam is coplanar.
  const auto counts = kindCounts(kept);
  CHECK(countOf(counts, EdgeKind::Open) == 0);
  CHECK(countOf(counts, EdgeKind::Concave) == 0);
}

TEST_CASE("a small box against a larger box's face: only the small box's covered face is dropped") {
  bspc::Mesh mesh = boxMesh({0, 0, 0}, {1, 3, 3});
  append(mesh, boxMesh({1, 1, 1}, {2, 2, 2}));  // its -x face lies inside the big +x face
  bspc::EdgeReport report;
  const bspc::Mesh kept = bspc::dropCoveredFaces(cleaned(mesh), report);
  CHECK(report.droppedCovered == 2);
  CHECK(facesOn(kept, {-1, 0, 0}, -1) == 0);  // the small face, covered
  CHECK(facesOn(kept, {1, 0, 0}, 1) == 2);    // the big face, partly free
}

TEST_CASE("a face only partly against another solid is kept") {
  bspc::Mesh mesh = boxMesh({0, 0, 0}, {1, 1, 1});
  append(mesh, boxMesh({1, 0.5, 0}, {2, 1.5, 1}));  // overlaps half of the +x face
  bspc::EdgeReport report;
  const bspc::Mesh kept = bspc::dropCoveredFaces(cleaned(mesh), report);
  CHECK(report.droppedCovered == 0);
  CHECK(kept.triangles.size() == 24);
}

TEST_CASE("a two-sided panel and an open surface lose nothing") {
  // A panel as front and back triangles with the same corners (as curved
  // patches are exported): each covers the other, but no solid lies behind.
  bspc::Mesh panel = square(0, 0);
  panel.triangles.push_back({0, 2, 1});
  panel.triangles.push_back({0, 3, 2});
  bspc::EdgeReport report;
  CHECK(bspc::dropCoveredFaces(cleaned(panel), report).triangles.size() == 4);
  // The same panel lying on a box's top: its upward pair duplicates the
  // top (clean drops them), its downward pair faces into the box and goes.
  bspc::Mesh pressed = boxMesh({0, -1, 0}, {1, 0, 1});
  append(pressed, panel);
  bspc::EdgeReport pressedReport;
  const bspc::Mesh kept = bspc::dropCoveredFaces(cleaned(pressed), pressedReport);
  CHECK(pressedReport.droppedCovered == 2);
  CHECK(kept.triangles.size() == 12);
  CHECK(facesOn(kept, {0, 1, 0}, 0) == 2);
}

TEST_CASE("a closed surface of two-sided panels keeps both sides of every panel") {
  // A box made of panels, each exported front and back: every inward face
  // lies on an outward one, but the outward faces' neighbours are panels
  // too (they have twins), so no solid lies behind them.
  bspc::Mesh mesh = boxMesh({0, 0, 0}, {1, 1, 1});
  const std::size_t outward = mesh.triangles.size();
  for (std::size_t t = 0; t < outward; ++t) {
    const auto& f = mesh.triangles[t];
    mesh.triangles.push_back({f[0], f[2], f[1]});
  }
  bspc::EdgeReport report;
  CHECK(bspc::dropCoveredFaces(cleaned(mesh), report).triangles.size() == 24);
  CHECK(report.droppedCovered == 0);
}

TEST_CASE("dropping covered faces gives the same mesh whatever the run") {
  bspc::Mesh mesh;
  for (int k = 0; k < 6; ++k) append(mesh, boxMesh({2.0 * k, 0, 0}, {2.0 * k + 2, 1, 4}));
  bspc::EdgeReport first, second;
  const bspc::Mesh a = bspc::dropCoveredFaces(cleaned(mesh), first);
  const bspc::Mesh b = bspc::dropCoveredFaces(cleaned(mesh), second);
  CHECK(first.droppedCovered == 20);  // 5 seams, 2 faces of 2 triangles each
  CHECK(a.triangles == b.triangles);
  CHECK(a.vertices == b.vertices);
}
