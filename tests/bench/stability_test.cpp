// SPDX-License-Identifier: MIT
// The failure cases of docs/stability.md, run for both methods: every case
// must stay safe, and each case's verdict must be the one the document
// states (a changed verdict means the table, and this list, need updating);
// a case documented as failing must not fail worse than the table says.
#include <catch2/catch.hpp>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "stability/scenes.h"

namespace {

using bspf::CollisionMethod;
using namespace bspf::stability;

// One figure of a case's goal (GoalResult::figures[index]) and the worst
// value accepted: the documented figure plus a small margin.
struct FigureBound {
  std::size_t index;
  const char* what;
  double limit;
  bool atMost;  // else at least
};

// A case docs/stability.md reports as failing, bounded so that it cannot get
// worse unnoticed: its goal figures, and the run's own figures from the
// table (documented value plus a margin; refusals exactly).
struct DocumentedFailure {
  std::vector<FigureBound> goal;
  long long refusedMax = 0;
  long long framesStuckMax = 0;
  double jitterMax = 0;
};

const std::map<std::pair<std::string, CollisionMethod>, DocumentedFailure>& documentedFailures() {
  static const std::map<std::pair<std::string, CollisionMethod>, DocumentedFailure> failures{
      // "bumps a body 0.67 m off its line"
      {{"outer corners and edges passed closely (ghost collisions)", CollisionMethod::Planes},
       {{{0, "deviation from the open-floor run, m", 0.70, true}}, 0, 5, 0.005}},
      // "climbs 0.00 m": the figure cannot drop; frames stuck can grow
      {{"stairs, 0.15 m risers", CollisionMethod::Planes}, {{}, 0, 165, 0.005}},
      {{"stairs, 0.30 m risers", CollisionMethod::Planes}, {{}, 0, 165, 0.005}},
      // Risers are walls for the exact sweep too (issue 10): "0.00 m climbed"
      {{"stairs, 0.15 m risers", CollisionMethod::ExactSweep}, {{}, 0, 70, 0.005}},
      {{"stairs, 0.30 m risers", CollisionMethod::ExactSweep}, {{}, 0, 165, 0.005}},
  };
  return failures;
}

void checkNoWorseThanDocumented(const CaseResult& r, const DocumentedFailure& bounds) {
  for (const FigureBound& bound : bounds.goal) {
    REQUIRE(bound.index < r.goal.figures.size());
    const double figure = r.goal.figures[bound.index];
    INFO(bound.what << " " << figure << (bound.atMost ? ", at most " : ", at least ")
                    << bound.limit);
    CHECK((bound.atMost ? figure <= bound.limit : figure >= bound.limit));
  }
  CHECK(r.refusedMoves <= bounds.refusedMax);
  CHECK(r.framesStuck <= bounds.framesStuckMax);
  CHECK(r.jitter <= bounds.jitterMax);
}

}  // namespace

// docs/stability.md: "no body came within the skin of a surface (penetration
// 0 of the size)"; 1e-6 leaves room for float rounding only.
TEST_CASE(
    "no failure case leaves a centre inside a solid or a body in a surface, with either method",
    "[stability]") {
  for (const Scene& scene : failureScenes()) {
    for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep}) {
      const CaseResult r = runScene(scene, method);
      INFO(scene.name << ", " << methodName(method) << ": penetration max " << r.penetrationMax
                      << ", inside-solid " << r.insideSolid);
      CHECK(r.insideSolid == 0);
      CHECK(r.penetrationMax <= 1e-6);
    }
  }
}

TEST_CASE(
    "each failure case passes or fails its goal as docs/stability.md states, failures no worse",
    "[stability]") {
  int documented = 0;
  for (const Scene& scene : failureScenes()) {
    for (const CollisionMethod method : {CollisionMethod::Planes, CollisionMethod::ExactSweep}) {
      const auto failure = documentedFailures().find({scene.name, method});
      const bool expectFailure = failure != documentedFailures().end();
      documented += expectFailure;
      const CaseResult r = runScene(scene, method);
      INFO(scene.name << ", " << methodName(method) << ": " << r.goal.detail << "; refused "
                      << r.refusedMoves << ", stuck " << r.framesStuck << ", jitter " << r.jitter);
      CHECK(r.pass() == !expectFailure);
      if (expectFailure) checkNoWorseThanDocumented(r, failure->second);
    }
  }
  // Every documented failure names a scene that exists.
  CHECK(documented == int(documentedFailures().size()));
}
