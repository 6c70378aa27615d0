// SPDX-License-Identifier: MIT
// bspf_stability: runs every failure-case scene (bench/stability/scenes.h)
// with both collision methods and prints the table of docs/stability.md as
// Markdown: per case and method, pass or fail against the tolerances and the
// case's goal, and the measured figures.
#include <cstdio>
#include <exception>

#include "stability/scenes.h"
#include "support/cli.h"

int main(int argc, char** argv) {
  CLI::App app{
      "bspf_stability: runs every failure case of docs/stability.md with both collision "
      "methods and prints its table (Markdown), then how many cases fail.",
      "bspf_stability"};
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;
  using namespace bspf::stability;
  const Tolerances tolerances;
  std::printf(
      "| case | method | verdict | penetration max / p99 (of size) | inside-solid | refused moves "
      "| frames stuck | jitter m | goal figure |\n"
      "|---|---|---|---:|---:|---:|---:|---:|---|\n");
  int failed = 0;
  try {
    for (const Scene& scene : failureScenes()) {
      for (const bspf::CollisionMethod method :
           {bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep}) {
        const CaseResult r = runScene(scene, method, tolerances);
        failed += !r.pass();
        const char* verdict =
            r.pass() ? "pass" : (r.safe ? "**fail** (goal)" : "**fail** (unsafe)");
        std::printf("| %s | %s | %s | %.1e / %.1e | %lld | %lld | %lld | %.4f | %s |\n",
                    scene.name.c_str(), methodName(method), verdict, r.penetrationMax,
                    r.penetrationP99, r.insideSolid, r.refusedMoves, r.framesStuck, r.jitter,
                    r.goal.detail.c_str());
        std::fflush(stdout);
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bspf_stability: %s\n", e.what());
    return 1;
  }
  std::fprintf(stderr, "bspf_stability: %d of the cases fail (see the table)\n", failed);
  return 0;
}
