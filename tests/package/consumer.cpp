// SPDX-License-Identifier: MIT
// A game as the package tests build it: against the installed package
// (find_package or pkg-config) or with bspf as a subproject. It opens the
// level named on its command line (samples/box_room compiled), drops a body
// from 2 m above the floor's centre and steps it for two seconds; it must
// come to rest on the floor (its centre one y radius above the floor's top,
// y = 0). Exit status 0 and one line on success, 1 and the reason otherwise.
#include <bspf/movement.h>
#include <bspf/world.h>

#include <cmath>
#include <cstdio>

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s LEVEL.bspf\n", argv[0]);
    return 1;
  }
  const bspf::OpenResult opened = bspf::openWorld(argv[1]);
  if (!opened) {
    std::fprintf(stderr, "consumer: error: %s\n", opened.message.c_str());
    return 1;
  }
  bspf::Body body;
  body.position = bspf::Vec3(0.0f, 2.0f, 0.0f);
  bspf::StepScratch scratch;
  bspf::StepReport report;
  for (int frame = 0; frame < 120; ++frame)
    bspf::stepBody(*opened.world, body, bspf::Vec3::Zero(), 1.0f / 60.0f, scratch, &report);
  const float expected = body.radii.y;
  if (!body.grounded || std::abs(body.position.y() - expected) > 0.01f) {
    std::fprintf(stderr,
                 "consumer: error: the body ended at y = %.4f, grounded %d (expected %.2f, 1)\n",
                 body.position.y(), int(body.grounded), expected);
    return 1;
  }
  std::printf("consumer: the body rests on the floor at y = %.4f\n", body.position.y());
  return 0;
}
