// SPDX-License-Identifier: MIT
// Blobs built around one hostile triangle beside an ordinary floor: the
// loader refuses what the step cannot handle (degenerate triangles, planes
// that disagree with their vertices, coordinates beyond kMaxCoordinate), and
// on whatever it accepts, neither narrow phase ever produces a non-finite
// position from finite inputs.
#include <bspc/build_tree.h>
#include <bspc/planes.h>
#include <bspc/write.h>
#include <bspf/movement.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <string>
#include <vector>

#include "support/test_support.h"

namespace bspf {
namespace {

using Vec3d = Eigen::Vector3d;

// A 40 m floor (two triangles at y = 0, facing up) plus `extra` triangles
// over `extraVertices`, as one leaf. The planes are computed as bspc does,
// except that a triangle bspc cannot make planes for (zero area) gets the
// floor's, so that only the new checks can refuse it.
std::vector<std::uint8_t> floorPlus(const std::vector<Vec3d>& extraVertices,
                                    const std::vector<std::array<std::uint32_t, 3>>& extra) {
  bspc::Mesh mesh;
  mesh.vertices = {{-20, 0, -20}, {-20, 0, 20}, {20, 0, 20}, {20, 0, -20}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  for (const Vec3d& v : extraVertices) mesh.vertices.push_back(v.cast<float>().cast<double>());
  for (const auto& t : extra) mesh.triangles.push_back({t[0] + 4, t[1] + 4, t[2] + 4});
  std::vector<schema::TrianglePlanes> planes = bspc::computeTrianglePlanes(mesh);
  for (schema::TrianglePlanes& p : planes) {
    const float len = std::sqrt(p.face().normal().x() * p.face().normal().x() +
                                p.face().normal().y() * p.face().normal().y() +
                                p.face().normal().z() * p.face().normal().z());
    if (!(std::abs(len - 1) < 1e-4f)) p = planes[0];
  }
  bspc::BspTree tree;
  tree.leaves.emplace_back(0, std::uint32_t(mesh.triangles.size()));
  for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) tree.leafTriangles.push_back(t);
  tree.root = -1;
  bspc::BlobMetadata metadata;
  metadata.sourceFile = "hostile";
  return bspc::serializeWorld(mesh, planes, tree, metadata);
}

struct Case {
  std::string name;
  std::vector<Vec3d> vertices;
  std::vector<std::array<std::uint32_t, 3>> triangles;
  bool mustRefuse;
};

std::vector<Case> cases() {
  std::vector<Case> out{
      {"a repeated vertex index", {{-1, 0, 0}, {1, 2, 0}}, {{0, 0, 1}}, true},
      {"three distinct collinear corners", {{-1, 0, 0}, {0, 1, 0}, {1, 2, 0}}, {{0, 1, 2}}, true},
      {"corners a few float steps off a line",
       {{-1, 0, 0}, {0, 1.0000001, 0}, {1, 2, 0}},
       {{0, 1, 2}},
       true},
      {"1e19 m coordinates",
       {{-1e19, 0.5, -1e19}, {1e19, 0.5, -1e19}, {0, 0.5, 1e19}},
       {{0, 2, 1}},
       true},
      {"coordinates that overflow once divided by a radius",
       {{-3e38, 1, 0}, {3e38, 1, 0}, {0, 1, 3e38}},
       {{0, 2, 1}},
       true},
      {"a 1e14 m sliver", {{-1e14, 0.5, 0}, {1e14, 0.5, 0}, {0, 0.5, 1e-3}}, {{0, 2, 1}}, true},
      {"a wall just inside the coordinate bound",
       {{-9e4, 0, 1}, {9e4, 0, 1}, {0, 9e4, 1}},
       {{0, 1, 2}},
       false},
      {"a thin sliver real levels hold (60 um high)",
       {{-1, 0.5, 0.3}, {1, 0.5, 0.3}, {0, 0.50006, 0.3}},
       {{0, 1, 2}},
       false},
      {"a tiny triangle", {{0, 0.001, 0}, {1e-4, 0.001, 0}, {0, 0.001, 1e-4}}, {{0, 2, 1}}, false},
  };
  return out;
}

bool finite(const Vec3& v) { return v.allFinite(); }

// Steps bodies of several shapes, standing and walking into and across the
// hostile triangle, for a few frames; every position must stay finite.
void requireFiniteSteps(const World& world, CollisionMethod method) {
  const EllipsoidRadii shapes[] = {{0.45f, 0.85f}, {0.25f, 0.25f}, {2.0f, 0.1f}, {0.05f, 1.5f}};
  const Vec3 forces[] = {{0, 0, 0}, {40, 0, 0}, {-40, 0, 10}, {0, 0, 40}};
  StepScratch scratch;
  for (const EllipsoidRadii& radii : shapes)
    for (const Vec3& force : forces)
      for (const float x : {-0.5f, 0.0f, 0.5f}) {
        Body body;
        body.radii = radii;
        body.settings.method = method;
        body.settings.maxStepHeight = 0.3f * radii.y;
        body.position = Vec3(x, radii.y + 0.01f, 0);
        body.velocity = force * 0.1f;
        for (int frame = 0; frame < 30; ++frame) {
          StepReport report;
          stepBody(world, body, force, 1.0f / 60, scratch, &report);
          INFO("radii " << radii.xz << " " << radii.y << ", force " << force.transpose()
                        << ", frame " << frame);
          REQUIRE(finite(body.position));
          REQUIRE(finite(body.velocity));
        }
      }
}

TEST_CASE(
    "the loader refuses triangles the step cannot handle, and the step stays finite on "
    "every blob it accepts",
    "[loader][movement][hostile]") {
  for (const Case& c : cases()) {
    DYNAMIC_SECTION(c.name) {
      const test::AlignedBytes bytes(floorPlus(c.vertices, c.triangles));
      const OpenResult opened = viewWorld(bytes.span());
      INFO(opened.message);
      if (c.mustRefuse)
        CHECK(opened.status == LoadStatus::Malformed);
      else
        CHECK(opened);
      if (opened) {
        requireFiniteSteps(*opened.world, CollisionMethod::Planes);
        requireFiniteSteps(*opened.world, CollisionMethod::ExactSweep);
      }
    }
  }
}

}  // namespace
}  // namespace bspf
