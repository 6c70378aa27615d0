// bspf_crowd_bench: how the body-against-body broad phase scales. Bodies
// stand on a flat floor at constant density (one per 1.5 m square, touching
// neighbours now and then as they walk), and the time of stepBodies per body
// is measured for growing crowds. A linear broad phase keeps it flat.
// Prints one JSON object per crowd size.
#include <bspf/movement.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <vector>

#include "support/mesh_blob.h"

int main() {
  // A 400 m square floor slab, compiled in memory.
  const bspf::bench::CompiledLevel floor(bspf::bench::floorMesh(200.0), {}, "floor");
  for (const int side : {8, 16, 32, 64, 128}) {
    const int n = side * side;
    std::vector<bspf::Body> bodies(n);
    std::vector<bspf::Vec3> forces(n);
    for (int i = 0; i < n; ++i) {
      bodies[i].position = bspf::Vec3(1.5f * (i % side), 0.851f, 1.5f * (i / side));
      bodies[i].radii = {0.45f, 0.85f};
      const float angle = 2.399963f * i;  // golden angle: directions spread evenly
      forces[i] = bspf::Vec3(std::cos(angle), 0, std::sin(angle)) * 20.0f;
    }
    bspf::StepScratch scratch;
    std::vector<bspf::StepReport> reports(n);
    std::vector<double> nsPerBody;
    double contacts = 0;
    for (int frame = 0; frame < 120; ++frame) {
      const auto start = std::chrono::steady_clock::now();
      bspf::stepBodies(floor.world(), bodies, forces, 1.0f / 60, scratch, reports);
      const auto stop = std::chrono::steady_clock::now();
      nsPerBody.push_back(std::chrono::duration<double, std::nano>(stop - start).count() / n);
      for (const auto& r : reports) contacts += r.bodyContacts;
    }
    std::sort(nsPerBody.begin(), nsPerBody.end());
    std::printf("{\"bodies\":%d,\"ns_per_body_step\":%.0f,\"body_contacts_per_step\":%.3f}\n", n,
                nsPerBody[nsPerBody.size() / 2], contacts / (120.0 * n));
  }
  return 0;
}
