// SPDX-License-Identifier: MIT
// The walkers sample's simulation (samples/walkers_sim.h) on the sample arena
// and the shared levels, checked against the brush oracle: no agent centre is
// ever strictly inside a solid; and the walkers program's --brushes option.
#include <bspc/compile.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <fstream>
#include <sstream>

#include "brushes.h"
#include "support/test_support.h"
#include "walkers_sim.h"
#include "walkers_svg.h"

using bspf::Vec3;
using bspf::walkers::Brush;
using bspf::walkers::BrushSet;

namespace {

constexpr float kMargin = bspf::walkers::kInsideMargin;

// An axis-aligned box as a brush.
Brush boxBrush(const Eigen::Vector3d& low, const Eigen::Vector3d& high) {
  Brush b;
  for (int a = 0; a < 3; ++a) {
    b.push_back({Eigen::Vector3d::Unit(a), high[a]});
    b.push_back({-Eigen::Vector3d::Unit(a), -low[a]});
  }
  return b;
}

// A compiled level with its brush oracle and spawn points.
struct Level {
  std::string name;
  bspf::World world;
  BrushSet brushes;
  std::vector<Vec3> spawns;
};

Level loadLevel(const std::filesystem::path& dir, const std::string& name,
                const std::filesystem::path& outDir) {
  const std::filesystem::path blob = outDir / (name + ".bspf");
  bspc::compileFile(dir / (name + ".obj"), blob, {});
  bspf::OpenResult opened = bspf::openWorld(blob);
  REQUIRE(opened);
  const bspf::walkers::Points spawns = bspf::walkers::loadSpawns(dir / (name + ".spawns.txt"));
  INFO(spawns.error);
  REQUIRE(spawns);
  return {name, *opened.world, BrushSet::load(dir / (name + ".brushes.txt")), spawns.points};
}

// Runs the crowd and counts agent centres inside a solid, over the start
// positions and after every frame; keeps the first few as examples.
struct Outcome {
  long long inside = 0;
  int grounded = 0, groundedOnSolid = 0;  // at the end: agents grounded, and on a brush
  int agentsEverInside = 0;
  std::string examples;
  bspf::walkers::Summary summary;
  double seconds = 0;
};

Outcome walk(const Level& level, std::span<const Vec3> starts,
             const bspf::walkers::Options& options) {
  Outcome out;
  std::vector<bool> everInside(starts.size(), false);
  auto check = [&](int frame, std::span<const bspf::Body> bodies) {
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      const Vec3& p = bodies[i].position;
      const int solid = level.brushes.findSolid(p, kMargin);
      if (solid < 0) continue;
      ++out.inside;
      if (!everInside[i]) ++out.agentsEverInside;
      everInside[i] = true;
      if (out.inside <= 5) {
        std::ostringstream line;
        line.precision(9);
        line << "\n  frame " << frame << " agent " << i << " at (" << p.x() << ", " << p.y() << ", "
             << p.z() << ") inside brush " << solid << " (velocity "
             << bodies[i].velocity.transpose() << ")";
        out.examples += line.str();
      }
    }
  };
  const auto start = std::chrono::steady_clock::now();
  bspf::walkers::Simulation sim(level.world, starts, options);
  check(-1, sim.bodies());
  for (int f = 0; f < options.frames; ++f) {
    sim.step();
    check(f, sim.bodies());
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  out.summary = sim.summary();
  // The oracle is not vacuous: most grounded agents stand on a brush (the
  // rest on curved patches, which have none), so a solid lies just under
  // their feet.
  for (std::size_t i = 0; i < sim.bodies().size(); ++i) {
    if (!sim.reports()[i].grounded) continue;
    ++out.grounded;
    const Vec3 below = sim.bodies()[i].position - Vec3(0, options.radii.y + 0.1f, 0);
    out.groundedOnSolid += level.brushes.insideAnySolid(below, kMargin);
  }
  return out;
}

// The shared levels (the caller skips the test when ../shared/levels is
// absent: a user's clone has no ../shared).
std::vector<Level> sharedLevels(const std::filesystem::path& outDir) {
  std::vector<Level> levels;
  for (const std::string& name : bspf::test::sharedLevelNames())
    levels.push_back(loadLevel(bspf::test::sharedLevelsDir(), name, outDir));
  return levels;
}

}  // namespace

TEST_CASE("the brush oracle tells points inside a solid from points outside",
          "[samples][walkers][brushes]") {
  SECTION("a box") {
    const BrushSet set({boxBrush({0, 0, 0}, {2, 1, 3})});
    REQUIRE(set.size() == 1);
    REQUIRE(set.bounds(0).min().isApprox(Eigen::Vector3d(-0.01, -0.01, -0.01)));
    REQUIRE(set.insideAnySolid(Vec3(1, 0.5f, 1.5f), kMargin));
    REQUIRE(set.insideAnySolid(Vec3(0.01f, 0.01f, 2.99f), kMargin));
    REQUIRE_FALSE(set.insideAnySolid(Vec3(3, 0.5f, 1.5f), kMargin));
    REQUIRE_FALSE(set.insideAnySolid(Vec3(1, -0.5f, 1.5f), kMargin));
    REQUIRE_FALSE(set.insideAnySolid(Vec3(1, 0.5f, 3.2f), kMargin));
    REQUIRE_FALSE(set.insideAnySolid(Vec3(-100, 100, 0), kMargin));
    // On a face, or within the margin of it: not inside.
    REQUIRE_FALSE(set.insideAnySolid(Vec3(2, 0.5f, 1.5f), kMargin));
    REQUIRE_FALSE(set.insideAnySolid(Vec3(1, 0.9995f, 1.5f), kMargin));
    REQUIRE(set.insideAnySolid(Vec3(1, 0.9995f, 1.5f), 0.0f));
    REQUIRE(set.findSolid(Vec3(1, 0.5f, 1.5f), kMargin) == 0);
  }
  SECTION("a slanted wedge, and many boxes against a brute-force check") {
    // A wedge: floor y > 0, x in 0..4, z in 0..1, under the plane rising at
    // 45 degrees along +x (y < x).
    Brush wedge = boxBrush({0, 0, 0}, {4, 4, 1});
    wedge.push_back({Eigen::Vector3d(-1, 1, 0).normalized(), 0});
    std::vector<Brush> brushes{wedge};
    bspf::walkers::Random rng(7);
    for (int i = 0; i < 300; ++i) {
      const Eigen::Vector3d low(rng.uniform(-50, 50), rng.uniform(-5, 5), rng.uniform(-50, 50));
      brushes.push_back(boxBrush(
          low,
          low + Eigen::Vector3d(rng.uniform(0.1f, 6), rng.uniform(0.1f, 3), rng.uniform(0.1f, 6))));
    }
    brushes.push_back(boxBrush({-200, -20, -200}, {200, -19, 200}));  // spans many cells
    const BrushSet set(brushes);
    const BrushSet wedgeOnly({wedge});
    REQUIRE(wedgeOnly.insideAnySolid(Vec3(3, 1, 0.5f), kMargin));
    REQUIRE_FALSE(wedgeOnly.insideAnySolid(Vec3(1, 3, 0.5f), kMargin));  // above the slope
    REQUIRE(wedgeOnly.bounds(0).max().y() == Approx(4.01));
    REQUIRE(set.findSolid(Vec3(0, -19.5f, 100), kMargin) == int(brushes.size()) - 1);
    for (int i = 0; i < 20000; ++i) {
      const Vec3 p(rng.uniform(-60, 60), rng.uniform(-22, 10), rng.uniform(-60, 60));
      int expected = -1;
      for (std::size_t b = 0; b < brushes.size() && expected < 0; ++b) {
        bool in = true;
        for (const auto& plane : brushes[b])
          in = in && plane.normal.dot(p.cast<double>()) < plane.distance - kMargin;
        if (in) expected = int(b);
      }
      INFO("point " << p.transpose());
      REQUIRE(set.findSolid(p, kMargin) == expected);
    }
  }
  SECTION("loaded from a file; malformed files are refused naming the line") {
    const std::filesystem::path dir = bspf::test::freshTempDir("brushes");
    {
      std::ofstream good(dir / "good.brushes.txt");
      good << "1 0 0 1 -1 0 0 1 0 1 0 1 0 -1 0 1 0 0 1 1 0 0 -1 1\n\n"
              "1 0 0 11 -1 0 0 -9 0 1 0 1 0 -1 0 1 0 0 1 1 0 0 -1 1\n";
      std::ofstream bad(dir / "bad.brushes.txt");
      bad << "1 0 0 1 -1 0 0 1\n1 0 0\n";
    }
    const BrushSet set = BrushSet::load(dir / "good.brushes.txt");
    REQUIRE(set.size() == 2);
    REQUIRE(set.findSolid(Vec3(0, 0, 0), kMargin) == 0);
    REQUIRE(set.findSolid(Vec3(10, 0, 0), kMargin) == 1);
    REQUIRE_FALSE(set.insideAnySolid(Vec3(5, 0, 0), kMargin));
    REQUIRE_THROWS_WITH(BrushSet::load(dir / "bad.brushes.txt"),
                        Catch::Contains("line 2") && Catch::Contains("groups of four"));
    REQUIRE_THROWS_WITH(BrushSet::load(dir / "absent.brushes.txt"), Catch::Contains("cannot open"));
  }
}

TEST_CASE("the sample levels' brushes hold no spawn and the body at each spawn is clear",
          "[samples][walkers][brushes]") {
  for (const std::string name : {"arena", "box_room", "slopes"}) {
    const BrushSet set = BrushSet::load(bspf::test::samplesDir() / (name + ".brushes.txt"));
    const auto spawns =
        bspf::walkers::loadSpawns(bspf::test::samplesDir() / (name + ".spawns.txt"));
    REQUIRE(spawns);
    for (const Vec3& s : spawns.points) {
      REQUIRE_FALSE(set.insideAnySolid(s, kMargin));
      // The floor 0.75 m below the spawn is inside one.
      REQUIRE(set.insideAnySolid(s - Vec3(0, 0.76f, 0), kMargin));
    }
  }
}

TEST_CASE("walkers: spawn files, options, placement and determinism", "[samples][walkers]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("walkers");
  SECTION("spawn files") {
    {
      std::ofstream(dir / "good.txt") << "1 2 3\n\n# comment\n-4.5 0.75 6e1\n";
      std::ofstream(dir / "bad.txt") << "1 2 3\n1 2\n";
      std::ofstream(dir / "extra.txt") << "1 2 3 4\n";
      std::ofstream(dir / "empty.txt") << "\n";
    }
    const auto good = bspf::walkers::loadSpawns(dir / "good.txt");
    REQUIRE(good);
    REQUIRE(good.points.size() == 2);
    REQUIRE(good.points[1] == Vec3(-4.5f, 0.75f, 60));
    const auto starts = bspf::walkers::startsFromSpawns(good.points, 5);
    REQUIRE(starts.size() == 5);
    REQUIRE(starts[3] == Vec3(-4.5f, 0.75f + bspf::walkers::kSpawnLift, 60));
    const auto bad = bspf::walkers::loadSpawns(dir / "bad.txt");
    REQUIRE_FALSE(bad);
    REQUIRE_THAT(bad.error, Catch::Contains("bad.txt") && Catch::Contains("line 2"));
    REQUIRE_FALSE(bspf::walkers::loadSpawns(dir / "extra.txt"));
    REQUIRE_THAT(bspf::walkers::loadSpawns(dir / "empty.txt").error,
                 Catch::Contains("no spawn point"));
    REQUIRE_THAT(bspf::walkers::loadSpawns(dir / "absent.txt").error,
                 Catch::Contains("cannot open"));
  }
  SECTION("options") {
    bspf::walkers::Options o;
    REQUIRE(bspf::walkers::validate(o).empty());
    o.agents = 0;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--agents"));
    o = {};
    o.dt = 0;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--dt"));
    o.dt = std::nanf("");
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--dt"));
    o = {};
    o.speed = -1;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--speed"));
    o = {};
    o.radii.y = 0;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--radius-y"));
    o = {};
    o.stepHeight = -0.1f;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--step-height"));
    o.stepHeight = 0.35f;
    REQUIRE(bspf::walkers::validate(o).empty());
    o.stepDown = -0.1f;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--step-down"));
    o.stepDown = std::nanf("");
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--step-down"));
    o.stepDown = 0;
    REQUIRE(bspf::walkers::validate(o).empty());
    o.threads = 0;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--threads"));
    o = {};
    o.spinMicroseconds = -1;
    REQUIRE_THAT(bspf::walkers::validate(o), Catch::Contains("--spin-us"));
    o.spinMicroseconds = 0;
    REQUIRE(bspf::walkers::validate(o).empty());
  }
  SECTION("placement on floor and determinism, on the arena") {
    const Level level = loadLevel(bspf::test::samplesDir(), "arena", dir);
    bspf::walkers::Options options;
    options.agents = 32;
    options.frames = 120;
    options.seed = 5;
    const auto placed =
        bspf::walkers::placeOnFloor(level.world, options.agents, options.radii, 5, "arena");
    INFO(placed.error);
    REQUIRE(placed);
    REQUIRE(placed.points.size() == 32);
    const auto again =
        bspf::walkers::placeOnFloor(level.world, options.agents, options.radii, 5, "arena");
    REQUIRE(again.points == placed.points);
    bspf::SweepScratch scratch;
    std::vector<std::uint32_t> candidates;
    for (const Vec3& p : placed.points) {
      INFO("placed at " << p.transpose());
      // Inside the walls, outside every solid, the body clear of the level.
      REQUIRE(std::abs(p.x()) < 19);
      REQUIRE(std::abs(p.z()) < 19);
      REQUIRE_FALSE(level.brushes.insideAnySolid(p, kMargin));
      REQUIRE(bspf::walkers::detail::bodyClear(level.world, p, options.radii, scratch, candidates));
    }
    // The same inputs give the same walk, frame by frame; another seed not.
    bspf::walkers::Simulation a(level.world, placed.points, options);
    bspf::walkers::Simulation b(level.world, placed.points, options);
    options.threads = 3;  // the thread count changes nothing
    bspf::walkers::Simulation threaded(level.world, placed.points, options);
    options.threads = 1;
    options.seed = 6;
    bspf::walkers::Simulation c(level.world, placed.points, options);
    bool differs = false;
    for (int f = 0; f < options.frames; ++f) {
      a.step();
      b.step();
      c.step();
      threaded.step();
      for (std::size_t i = 0; i < placed.points.size(); ++i) {
        REQUIRE(a.bodies()[i].position == b.bodies()[i].position);
        REQUIRE(a.bodies()[i].position == threaded.bodies()[i].position);
        differs = differs || a.bodies()[i].position != c.bodies()[i].position;
      }
    }
    REQUIRE(differs);
    REQUIRE(a.summary().steps == 32 * 120);
    REQUIRE(a.summary().nsPerStep > 0);
    // They walk: most of them went some way from where they started.
    int moved = 0;
    for (std::size_t i = 0; i < placed.points.size(); ++i)
      moved += (a.bodies()[i].position - placed.points[i]).norm() > 1;
    REQUIRE(moved > 16);
  }
  SECTION("a level with no floor refuses placement") {
    bspc::Mesh wall = bspf::test::boxMesh({0, 0, 0}, {0.1, 3, 3});
    bspf::test::AlignedBytes bytes(bspf::test::compile(wall));
    const bspf::World world = *bspf::viewWorld(bytes.span()).world;
    // Its top face is walkable, but a body there is out in the void.
    const auto placed = bspf::walkers::placeOnFloor(world, 4, {0.45f, 0.85f}, 1, "wall");
    REQUIRE_FALSE(placed);
    REQUIRE_THAT(placed.error, Catch::Contains("wall") && Catch::Contains("--spawns"));
  }
}

namespace {

// Walkers from the spawns and from random floor, at 6 and 40 m/s, with
// `method`: no agent ever ends a frame inside a solid, and most grounded
// agents stand on a brush.
void walkNeverInsideSolid(const std::vector<Level>& levels, bspf::CollisionMethod method) {
  INFO((method == bspf::CollisionMethod::Planes ? "planes" : "exact") << " method");
  for (const Level& level : levels) {
    bspf::walkers::Options options;
    options.method = method;
    // Starts from the level's spawn points, and from random open floor.
    const std::vector<Vec3> fromSpawns =
        bspf::walkers::startsFromSpawns(level.spawns, options.agents);
    const bspf::walkers::Points onFloor = bspf::walkers::placeOnFloor(
        level.world, options.agents, options.radii, options.seed, level.name);
    INFO(onFloor.error);
    REQUIRE(onFloor);
    for (const auto& [placement, starts] :
         {std::pair{"spawns", fromSpawns}, std::pair{"floor", onFloor.points}}) {
      for (const float speed : {6.0f, 40.0f}) {
        options.speed = speed;
        const Outcome out = walk(level, starts, options);
        INFO(level.name << " from " << placement << " at " << speed << " m/s: " << out.inside
                        << " agent-frames inside a solid (" << out.agentsEverInside << " of "
                        << options.agents << " agents); refused " << out.summary.refusedMoves
                        << ", " << out.seconds << " s" << out.examples);
        CHECK(out.inside == 0);
        INFO(out.groundedOnSolid << " of " << out.grounded << " grounded agents on a brush");
        CHECK(out.groundedOnSolid * 2 > out.grounded);
      }
    }
  }
}

}  // namespace

TEST_CASE("walkers at 6 and 40 m/s never end inside a solid, on the arena", "[samples][walkers]") {
  const std::filesystem::path outDir = bspf::test::freshTempDir("walkers-arena");
  const std::vector<Level> levels{loadLevel(bspf::test::samplesDir(), "arena", outDir)};
  walkNeverInsideSolid(levels,
                       GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep));
}

TEST_CASE("walkers at 6 and 40 m/s never end inside a solid, on the shared levels",
          "[samples][walkers][shared-levels]") {
  BSPF_SKIP_WITHOUT_SHARED_LEVELS();
  const std::filesystem::path outDir = bspf::test::freshTempDir("walkers-levels");
  const std::vector<Level> levels = sharedLevels(outDir);
  walkNeverInsideSolid(levels,
                       GENERATE(bspf::CollisionMethod::Planes, bspf::CollisionMethod::ExactSweep));
}

namespace {

std::string quoted(const std::filesystem::path& path) {
  std::string out = "'";
  for (const char c : path.string()) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bspf::test::CommandResult runWalkers(const std::string& arguments) {
  return bspf::test::run(quoted(WALKERS_EXECUTABLE) + " " + arguments);
}

// The value of `key` in walkers' one-line JSON, as text ("" when absent).
std::string jsonValue(const std::string& json, const std::string& key) {
  const std::string tag = "\"" + key + "\": ";
  const std::size_t at = json.find(tag);
  if (at == std::string::npos) return {};
  const std::size_t from = at + tag.size();
  return json.substr(from, json.find_first_of(",}", from) - from);
}

}  // namespace

TEST_CASE("walkers --brushes counts the agent-frames inside a solid", "[samples][walkers]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("walkers-brushes");
  const std::filesystem::path samples = bspf::test::samplesDir();
  bspc::compileFile(samples / "box_room.obj", dir / "box_room.bspf", {});
  const std::string common = quoted(dir / "box_room.bspf") + " --spawns " +
                             quoted(samples / "box_room.spawns.txt") +
                             " --agents 8 --frames 60 --json";

  SECTION("the level's own brushes: no agent ever inside") {
    const auto r = runWalkers(common + " --brushes " + quoted(samples / "box_room.brushes.txt"));
    INFO(r.err << r.out);
    REQUIRE(r.status == 0);
    REQUIRE(jsonValue(r.out, "steps") == "480");
    REQUIRE(jsonValue(r.out, "inside_solid") == "0");
  }
  SECTION("without --brushes the count is null") {
    const auto r = runWalkers(common);
    INFO(r.err << r.out);
    REQUIRE(r.status == 0);
    REQUIRE(jsonValue(r.out, "inside_solid") == "null");
  }
  SECTION("a brush over one spawn, and one filling the room") {
    // Spawn 0 is at (0, 0.75, 0); agents 0 and 4 start 0.3 m above it and
    // walk out of a 0.6 m column around it within a few frames.
    std::ofstream(dir / "spawn.brushes.txt")
        << "1 0 0 0.3 -1 0 0 0.3 0 1 0 3 0 -1 0 0 0 0 1 0.3 0 0 -1 0.3\n";
    // The room's inside less 0.1 m: every centre is in it, every frame.
    std::ofstream(dir / "room.brushes.txt")
        << "1 0 0 2.9 -1 0 0 2.9 0 1 0 2.9 0 -1 0 -0.1 0 0 1 2.9 0 0 -1 2.9\n";
    const auto spawn = runWalkers(common + " --brushes " + quoted(dir / "spawn.brushes.txt"));
    INFO(spawn.err << spawn.out);
    REQUIRE(spawn.status == 0);
    const long long inside = std::stoll(jsonValue(spawn.out, "inside_solid"));
    REQUIRE(inside > 0);
    REQUIRE(inside < 480);
    const auto room = runWalkers(common + " --brushes " + quoted(dir / "room.brushes.txt"));
    INFO(room.err << room.out);
    REQUIRE(room.status == 0);
    REQUIRE(jsonValue(room.out, "inside_solid") == "480");
    // The text summary says it too.
    const std::string text =
        quoted(dir / "box_room.bspf") + " --spawns " + quoted(samples / "box_room.spawns.txt") +
        " --agents 8 --frames 60 --brushes " + quoted(dir / "room.brushes.txt");
    const auto summary = runWalkers(text);
    INFO(summary.err << summary.out);
    REQUIRE(summary.status == 0);
    REQUIRE_THAT(summary.out, Catch::Contains("inside a solid") && Catch::Contains("480"));
  }
  SECTION("a bad brush file is one error line naming it, and no output") {
    std::ofstream(dir / "bad.brushes.txt") << "1 0 0 1 -1 0 0 1\n0 1 0\n";
    for (const auto& [file, reason] :
         {std::pair{dir / "bad.brushes.txt", std::string("line 2")},
          std::pair{dir / "absent.brushes.txt", std::string("cannot open")}}) {
      const auto r = runWalkers(common + " --brushes " + quoted(file));
      INFO(r.err << r.out);
      REQUIRE(r.status == 1);
      REQUIRE(r.out.empty());
      REQUIRE_THAT(r.err, Catch::StartsWith("walkers: error: " + file.string() + ": ") &&
                              Catch::Contains(reason) && Catch::EndsWith("\n"));
      REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
    }
  }
}

TEST_CASE("walkers --accuracy reports penetration and the deviation between narrow phases",
          "[samples][walkers]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("walkers-accuracy");
  const std::filesystem::path samples = bspf::test::samplesDir();
  bspc::compileFile(samples / "arena.obj", dir / "arena.bspf", {});
  const std::string common = quoted(dir / "arena.bspf") + " --spawns " +
                             quoted(samples / "arena.spawns.txt") +
                             " --agents 16 --frames 120 --speed 40 --json";
  const auto plain = runWalkers(common);
  INFO(plain.err << plain.out);
  REQUIRE(plain.status == 0);
  for (const char* key :
       {"penetration_p99", "penetration_max", "deviation_p50", "deviation_p99", "deviation_max"})
    REQUIRE(jsonValue(plain.out, key) == "null");

  const auto measured = runWalkers(common + " --accuracy");
  INFO(measured.err << measured.out);
  REQUIRE(measured.status == 0);
  // The measurement is untimed and changes nothing: same run.
  REQUIRE(jsonValue(measured.out, "refused_moves") == jsonValue(plain.out, "refused_moves"));
  // Bodies keep their skin: no penetration beyond float noise.
  REQUIRE(std::stod(jsonValue(measured.out, "penetration_max")) < 1e-4);
  // The two narrow phases agree on most steps (the skin apart), and differ
  // where the planes method meets ghost contacts or refuses a move.
  const double p50 = std::stod(jsonValue(measured.out, "deviation_p50"));
  const double max = std::stod(jsonValue(measured.out, "deviation_max"));
  REQUIRE(p50 < 0.01);
  REQUIRE(max > p50);
  REQUIRE(max <= 40.0 / 60.0 + 0.05);  // never more than one frame's travel
}

TEST_CASE(
    "walkers takes every documented option and reports every documented JSON key with the "
    "inputs it was given",
    "[samples][walkers]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("walkers-keys");
  const std::filesystem::path samples = bspf::test::samplesDir();
  bspc::compileFile(samples / "box_room.obj", dir / "box_room.bspf", {});
  const auto r = runWalkers(
      quoted(dir / "box_room.bspf") + " --spawns " + quoted(samples / "box_room.spawns.txt") +
      " --agents 5 --frames 7 --speed 3.5 --seed 9 --dt 0.025"
      " --radius-xz 0.3 --radius-y 0.6 --method exact --step-height 0.2 --step-down 0.1"
      " --trace " +
      quoted(dir / "trace.csv") + " --json");
  INFO(r.err << r.out);
  REQUIRE(r.status == 0);
  REQUIRE(jsonValue(r.out, "agents") == "5");
  REQUIRE(jsonValue(r.out, "frames") == "7");
  REQUIRE(jsonValue(r.out, "steps") == "35");
  REQUIRE(jsonValue(r.out, "seed") == "9");
  REQUIRE(jsonValue(r.out, "placement") == "\"spawns\"");
  REQUIRE(jsonValue(r.out, "method") == "\"exact\"");
  REQUIRE_THAT(jsonValue(r.out, "level"), Catch::Contains("box_room.bspf"));
  for (const auto& [key, value] :
       {std::pair{"speed", 3.5}, std::pair{"dt", 0.025}, std::pair{"step_height", 0.2},
        std::pair{"step_down", 0.1}, std::pair{"radius_xz", 0.3}, std::pair{"radius_y", 0.6}}) {
    INFO(key);
    REQUIRE(std::stod(jsonValue(r.out, key)) == Approx(value));
  }
  for (const char* key : {"ns_per_step", "refused_moves", "iterations_mean", "iterations_max",
                          "grounded_fraction", "body_contacts_mean", "fell_out"}) {
    INFO(key);
    const std::string value = jsonValue(r.out, key);
    REQUIRE(!value.empty());
    REQUIRE(std::stod(value) >= 0);
  }
  REQUIRE(std::stod(jsonValue(r.out, "grounded_fraction")) <= 1);
  for (const char* key : {"inside_solid", "penetration_p99", "penetration_max", "deviation_p50",
                          "deviation_p99", "deviation_max"}) {
    INFO(key);
    REQUIRE(jsonValue(r.out, key) == "null");
  }
  // The trace: a header, then one row per agent per frame.
  std::ifstream trace(dir / "trace.csv");
  std::string line;
  int rows = 0;
  while (std::getline(trace, line)) rows += !line.empty();
  REQUIRE(rows >= 35);
  REQUIRE(rows <= 36);
}

TEST_CASE("walkers exits with status 2 for bad options and 1 for a level it cannot open",
          "[samples][walkers]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("walkers-status");
  bspc::compileFile(bspf::test::samplesDir() / "box_room.obj", dir / "box_room.bspf", {});
  const std::string level = quoted(dir / "box_room.bspf");
  for (const std::string options :
       {"--agents 0", "--method sideways", "--dt -1", "--no-such-option", "--radius-xz 0"}) {
    INFO(options);
    const auto r = runWalkers(level + " " + options);
    INFO(r.err);
    REQUIRE(r.status == 2);
    REQUIRE_THAT(r.err, Catch::StartsWith("walkers: error: ") && Catch::EndsWith("\n"));
    // The line names the option it is about.
    REQUIRE_THAT(r.err, Catch::Contains(options.substr(0, options.find(' '))));
    REQUIRE(std::count(r.err.begin(), r.err.end(), '\n') == 1);
  }
  const auto missing = runWalkers(quoted(dir / "absent.bspf"));
  INFO(missing.err);
  REQUIRE(missing.status == 1);
  REQUIRE_THAT(missing.err, Catch::Contains("absent.bspf"));
}

namespace {

// How often `needle` occurs in `text`.
std::size_t occurrences(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos;
       at = text.find(needle, at + needle.size()))
    ++count;
  return count;
}

std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace

TEST_CASE("walkers --svg draws the level, one path per agent, and the run's events with its counts",
          "[samples][walkers][svg]") {
  const std::filesystem::path dir = bspf::test::freshTempDir("walkers-svg");
  const std::filesystem::path samples = bspf::test::samplesDir();
  bspc::compileFile(samples / "box_room.obj", dir / "box_room.bspf", {});
  // Spawn 0 in the room; spawn 1 far outside it: that agent falls out.
  std::ofstream(dir / "spawns.txt") << "0 0.75 0\n100 0.75 100\n";
  // A brush filling the room's inside less 0.1 m: every agent in the room is
  // inside it every frame.
  std::ofstream(dir / "room.brushes.txt")
      << "1 0 0 2.9 -1 0 0 2.9 0 1 0 2.9 0 -1 0 -0.1 0 0 1 2.9 0 0 -1 2.9\n";
  const auto r =
      runWalkers(quoted(dir / "box_room.bspf") + " --spawns " + quoted(dir / "spawns.txt") +
                 " --agents 4 --frames 90 --brushes " + quoted(dir / "room.brushes.txt") +
                 " --svg " + quoted(dir / "run.svg") + " --json");
  INFO(r.err << r.out);
  REQUIRE(r.status == 0);
  REQUIRE(jsonValue(r.out, "fell_out") == "2");
  REQUIRE(jsonValue(r.out, "inside_solid") == "180");
  const std::string svg = readFile(dir / "run.svg");
  REQUIRE_THAT(svg, Catch::StartsWith("<svg xmlns=\"http://www.w3.org/2000/svg\"") &&
                        Catch::EndsWith("</svg>\n"));
  REQUIRE_FALSE(std::filesystem::exists(dir / "run.svg.tmp"));
  // The counts in the picture are walkers' own.
  REQUIRE_THAT(svg, Catch::Contains("refused moves " + jsonValue(r.out, "refused_moves") +
                                    ", fell out 2, inside-solid agent-frames 180"));
  REQUIRE(occurrences(svg, "<polyline") == 4);
  // A magenta ring where each of the two crossed the level's lowest point,
  // an orange dot per spot inside the brush; the room's walls as lines.
  REQUIRE(occurrences(svg, "fill=\"none\" stroke=\"#d000d0\"") == 2);
  REQUIRE(occurrences(svg, "fill=\"#ff8c00\"/>") > 0);
  REQUIRE(occurrences(svg, "<path fill=\"none\" stroke=\"#5a3214\"") > 0);
}

TEST_CASE("the walkers picture marks a refused move where the agent stood, once per 5 cm square",
          "[samples][walkers][svg]") {
  const bspf::World world = bspf::test::compileSample("box_room");
  bspf::walkers::SvgRecorder recorder(world);
  std::vector<bspf::Body> bodies(2);
  bodies[0].position = Vec3(1.01f, 0.85f, 2.01f);
  bodies[1].position = Vec3(-1, 0.85f, -1);
  std::vector<bspf::StepReport> reports(2);
  reports[0].refused = true;
  recorder.frame(bodies, reports, {});
  bodies[0].position = Vec3(1.02f, 0.85f, 2.02f);  // the same 5 cm square
  recorder.frame(bodies, reports, {});
  REQUIRE(recorder.refusedMoves() == 2);
  const std::string svg = recorder.svg("test");
  // The two share a 5 cm square: one cross drawn (one path), two counted.
  REQUIRE(occurrences(svg, "stroke=\"#e00000\"") == 1);
  REQUIRE_THAT(svg, Catch::Contains("refused moves 2,"));
  // No brush results were given: the picture says so rather than 0.
  REQUIRE_THAT(svg, Catch::Contains("inside-solid agent-frames not checked"));
  REQUIRE(occurrences(svg, "<polyline") == 2);
}
