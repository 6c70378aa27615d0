// The failure cases of docs/stability.md, run for both methods: every case
// must stay safe, and each case's verdict must be the one the document
// states (a changed verdict means the table, and this list, need updating).
#include <catch2/catch.hpp>
#include <map>
#include <string>
#include <utility>

#include "stability/scenes.h"

namespace {

using bspf::CollisionMethod;
using namespace bspf::stability;

// The cases docs/stability.md reports as failing, by method.
const std::map<std::pair<std::string, CollisionMethod>, bool>& documentedFailures() {
  static const std::map<std::pair<std::string, CollisionMethod>, bool> failures{
      {{"outer corners and edges passed closely (ghost collisions)", CollisionMethod::Planes},
       true},
      {{"seams between abutting solids: floor and wall of 2 m blocks", CollisionMethod::Planes},
       true},
      {{"slope at 44 degrees (walkable limit 45)", CollisionMethod::Planes}, true},
      {{"stairs, 0.15 m risers", CollisionMethod::Planes}, true},
      {{"stairs, 0.30 m risers", CollisionMethod::Planes}, true},
      {{"stairs, 0.30 m risers", CollisionMethod::ExactSweep}, true},
  };
  return failures;
}

}  // namespace

TEST_CASE("no failure case leaves a centre inside a solid or a body 1% deep, with either method",
          "[stability]") {
  for (const Scene& scene : failureScenes()) {
    for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep}) {
      const CaseResult r = runScene(scene, method);
      INFO(scene.name << ", " << methodName(method) << ": penetration max " << r.penetrationMax
                      << ", inside-solid " << r.insideSolid);
      CHECK(r.insideSolid == 0);
      CHECK(r.penetrationMax <= 0.01);
    }
  }
}

TEST_CASE("each failure case passes or fails its goal as docs/stability.md states", "[stability]") {
  int documented = 0;
  for (const Scene& scene : failureScenes()) {
    for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep}) {
      const bool expectFailure = documentedFailures().count({scene.name, method}) > 0;
      documented += expectFailure;
      const CaseResult r = runScene(scene, method);
      INFO(scene.name << ", " << methodName(method) << ": " << r.goal.detail);
      CHECK(r.pass() == !expectFailure);
    }
  }
  // Every documented failure names a scene that exists.
  CHECK(documented == int(documentedFailures().size()));
}
