// SPDX-License-Identifier: MIT
// game_loop: the worked example of docs/integration.md, a small game's frame
// loop on bspf's public API only. Headless: a scripted player and a crowd of
// bodies walk a compiled level for a number of frames; the program prints
// what a game would act on (footsteps per surface, camera pulls, respawns,
// a level reload) and exits with status 1 if any of it did not happen.
//
//   game_loop LEVEL.bspf SPAWNS.txt [FRAMES]
#include <bspf/movement.h>
#include <bspf/scene_query.h>
#include <bspf/thread_pool.h>
#include <bspf/world.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace {

// Spawn points, one "x y z" a line (metres): where bodies start, their feet
// near the floor, so bodies start 0.3 m higher.
std::vector<bspf::Vec3> readSpawns(const char* path) {
  std::vector<bspf::Vec3> spawns;
  std::ifstream in(path);
  float x, y, z;
  while (in >> x >> y >> z) spawns.emplace_back(x, y + 0.3f, z);
  return spawns;
}

// [body]
bspf::Body makeBody(const bspf::Vec3& at) {
  bspf::Body body;
  body.position = at;                   // the centre, metres
  body.radii = {0.45f, 0.85f};          // horizontal and vertical radius, metres
  body.settings.maxStepHeight = 0.35f;  // climbs steps up to 0.35 m
  body.settings.maxStepDown = 0.35f;    // stays on the ground down them (the default)
  return body;
}
// [body]

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: game_loop LEVEL.bspf SPAWNS.txt [FRAMES]\n");
    return 2;
  }
  const int frames = argc > 3 ? std::atoi(argv[3]) : 600;
  const float dt = 1.0f / 60;  // seconds a frame

  // [open]
  bspf::OpenResult opened = bspf::openWorld(argv[1]);
  if (!opened) {  // a missing, truncated, foreign or too-old file
    std::fprintf(stderr, "game_loop: %s\n", opened.message.c_str());
    return 1;
  }
  bspf::World level = *opened.world;  // a cheap handle: copies share the mapping
  // [open]
  const std::vector<bspf::Vec3> spawns = readSpawns(argv[2]);
  if (spawns.empty()) {
    std::fprintf(stderr, "game_loop: %s: no spawn points\n", argv[2]);
    return 1;
  }

  // [crowd]
  // Body 0 is the player; the others are a crowd, stepped on every core.
  std::vector<bspf::Body> bodies;
  for (int i = 0; i < 64; ++i) bodies.push_back(makeBody(spawns[i % spawns.size()]));
  std::vector<bspf::Vec3> forces(bodies.size());  // input as force: m/s^2 (mass 1)
  std::vector<bspf::StepReport> reports(bodies.size());
  bspf::ThreadPool pool(2);
  std::vector<bspf::StepScratch> scratches(pool.threadCount());  // one per thread
  // [crowd]

  std::map<std::string, int> footsteps;
  int respawns = 0, cameraPulls = 0, reloads = 0;
  for (int frame = 0; frame < frames; ++frame) {
    // [input]
    // Walk: a force along the wanted direction; the body's friction and
    // maxHorizontalSpeed turn it into a walk. Jump: set the vertical speed
    // when on the ground.
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const float heading = 0.7f * float(i) + 0.01f * float(frame);
      forces[i] = bspf::Vec3(std::cos(heading), 0, std::sin(heading)) * 40.0f;
    }
    bspf::Body& player = bodies[0];
    if (frame % 90 == 45 && player.grounded) player.velocity.y() = 5.0f;  // m/s up
    // [input]

    // [step]
    bspf::stepBodies(level, bodies, forces, dt, pool, scratches, reports);
    // [step]

    // [footsteps]
    // A footstep sound from the surface under the player: its walkable
    // contact's surface id, named by the level (the source's material).
    const bspf::StepReport& step = reports[0];
    if (step.grounded && frame % 20 == 0)
      for (int c = 0; c < step.contactCount; ++c)
        if (step.contactTriangles[c] != bspf::kBodyContact && step.contactNormals[c].y() > 0.7f) {
          ++footsteps[std::string(level.surfaceName(step.contactSurfaces[c]))];
          break;
        }
    // [footsteps]

    // [camera]
    // A third-person camera 4 m behind the player's head, pulled in front of
    // any wall between them (0.2 m short of it).
    const bspf::Vec3 head = player.position + bspf::Vec3(0, 0.6f, 0);
    const bspf::Vec3 back = -forces[0].normalized();
    float cameraDistance = 4.0f;
    if (const std::optional<bspf::RayHit> wall = bspf::castRay(level, head, back, 4.0f)) {
      cameraDistance = std::max(0.0f, wall->distance - 0.2f);
      ++cameraPulls;
    }
    (void)cameraDistance;  // a renderer would place its camera here
    // [camera]

    // [respawn]
    for (std::size_t i = 0; i < bodies.size(); ++i)
      if (reports[i].belowLevel) {  // fell out of the level: back to a spawn
        bodies[i] = makeBody(spawns[i % spawns.size()]);
        ++respawns;
      }
    // [respawn]

    // [reload]
    // Halfway, the level is opened again, as after bspc rewrote the file:
    // bspc replaces it atomically, so the old mapping (held by `level`
    // until the assignment, and by any copy a thread still holds) stays
    // valid. Bodies and scratches carry over.
    if (frame == frames / 2) {
      bspf::OpenResult again = bspf::openWorld(argv[1]);
      if (again) {
        level = *again.world;
        ++reloads;
      }
    }
    // [reload]
  }

  std::printf(
      "game_loop: %d frames, %zu bodies; camera pulled in %d times; %d respawns; %d "
      "reloads; footsteps:",
      frames, bodies.size(), cameraPulls, respawns, reloads);
  for (const auto& [surface, count] : footsteps) std::printf(" %s %d", surface.c_str(), count);
  std::printf("\n");
  const bool ok = !footsteps.empty() && reloads == 1;
  return ok ? 0 : 1;
}
