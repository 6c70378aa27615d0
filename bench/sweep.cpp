// SPDX-License-Identifier: MIT
// bspf_sweep: speed against accuracy of the runtime's two narrow phases
// (planes, exact) and of a Bullet peer (bullet_peer.h, when built), over the
// sample and shared levels and one knob at a time. Writes one CSV
// (docs/speed-accuracy.csv via scripts/chart.sh).
//
//   bspf_sweep [--out FILE] [--quick] [--agents N] [--frames F] [--repeats R]
//              [--seed K] [--samples DIR] [--shared DIR] [--level NAME]...
//              [--obj FILE]... [--default-only] [--method planes|exact|bullet]...
//
// Every level's OBJ is compiled in memory (bspc's library) for each leaf size
// tried. A crowd random-walks as in the walkers sample (same random streams
// and turning rule), but each body is stepped alone against the level with
// stepBody (no body-against-body pushes, which the peer does not have), so
// all methods do the same work. Speed: ns per agent-step, the median over
// frames of (the frame's stepping time / agents), the median over --repeats
// identical runs. Accuracy, from one more identical run, untimed: the
// penetration of every end position (oracle::penetration, a fraction of the
// body's size), the deviation of every step's end from a reference end from
// the same state (the exact sweep with 32 iterations and a 0.1 mm skin),
// agent-frames with the centre inside a brush, and refused moves.
#include <bspc/compile.h>
#include <bspc/import.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "oracle.h"
#include "support/cli.h"
#include "support/median.h"
#include "support/mesh_blob.h"
#include "walkers_sim.h"

#ifdef BSPF_HAVE_BULLET
#include "bullet_peer.h"
#endif

namespace fs = std::filesystem;
using bspf::Body;
using bspf::Vec3;

namespace {

using bspf::bench::median;

constexpr float kSpeed = 6.0f;  // m/s
constexpr bspf::EllipsoidRadii kRadii{0.45f, 0.85f};
constexpr float kDefaultDt = 1.0f / 60.0f;
constexpr std::uint32_t kDefaultLeaf = 8;

enum class Method { Planes, Exact, Bullet };

const char* methodName(Method m) {
  switch (m) {
    case Method::Planes: return "planes";
    case Method::Exact: return "exact";
    case Method::Bullet: return "bullet";
  }
  return "?";
}

// One point of the sweep: a method with one knob changed from the defaults.
struct Config {
  Method method = Method::Planes;
  std::string knob = "default", value = "-";
  bspf::MovementSettings settings;
  std::uint32_t leaf = kDefaultLeaf;
  float dt = kDefaultDt;
};

// The configurations to run: every knob varied, fewer with `quick`, none
// with `defaultOnly`; only the methods named in `methods` (all when empty).
std::vector<Config> makeConfigs(bool quick, bool defaultOnly, bool withBullet,
                                const std::vector<std::string>& methods) {
  std::vector<Config> configs;
  for (const Method method : {Method::Planes, Method::Exact, Method::Bullet}) {
    if (method == Method::Bullet && !withBullet) continue;
    if (!methods.empty() &&
        std::find(methods.begin(), methods.end(), methodName(method)) == methods.end())
      continue;
    Config base;
    base.method = method;
    base.settings.method = method == Method::Planes ? bspf::CollisionMethod::Planes
                                                    : bspf::CollisionMethod::ExactSweep;
    base.settings.maxHorizontalSpeed = kSpeed;
    configs.push_back(base);
    if (defaultOnly) continue;
    auto vary = [&](const char* knob, const std::string& value, auto&& change) {
      Config c = base;
      c.knob = knob;
      c.value = value;
      change(c);
      configs.push_back(c);
    };
    for (const int n : quick ? std::vector<int>{1} : std::vector<int>{1, 2, 3, 4, 7, 10})
      vary("iterations", std::to_string(n), [n](Config& c) { c.settings.maxIterations = n; });
    if (quick) continue;
    if (method != Method::Bullet)
      for (const std::uint32_t leaf : {2u, 32u})
        vary("leaf", std::to_string(leaf), [leaf](Config& c) { c.leaf = leaf; });
    // skin = skin: clang 14 cannot capture a structured binding itself.
    for (const auto& [text, skin] : {std::pair{"0.0001", 1e-4f}, std::pair{"0.01", 1e-2f}})
      vary("skin", text, [skin = skin](Config& c) { c.settings.skin = skin; });
    for (const int rate : {30, 120})
      vary("dt", "1/" + std::to_string(rate), [rate](Config& c) { c.dt = 1.0f / float(rate); });
  }
  return configs;
}

// A level's source and oracles.
struct Level {
  std::string name;
  fs::path obj;
  bspc::Mesh mesh;
  std::vector<Vec3> spawns;
  bspf::walkers::BrushSet brushes;
};

// The level compiled with one leaf size.
bspf::bench::CompiledLevel compile(const Level& level, std::uint32_t leaf) {
  bspc::CompileSettings settings;
  settings.tree.maxLeafTriangles = leaf;
  return {level.mesh, settings, level.obj.filename().string()};
}

// Steps every body of one frame; only this is timed.
using FrameStepper =
    std::function<void(std::span<Body>, std::span<const Vec3>, float, std::span<bspf::StepReport>)>;

// The walkers sample's random walk (walkers::Simulation::step): same streams,
// same turning rule, same push; the stepping is the caller's.
class Crowd {
 public:
  Crowd(std::span<const Vec3> starts, const bspf::MovementSettings& settings, std::uint64_t seed)
      : bodies_(starts.size()), agents_(starts.size()), forces_(starts.size(), Vec3::Zero()) {
    for (std::size_t i = 0; i < starts.size(); ++i) {
      bodies_[i].position = starts[i];
      bodies_[i].radii = kRadii;
      bodies_[i].settings = settings;
      agents_[i] = bspf::walkers::RandomWalk(bspf::walkers::streamSeed(seed, i + 1));
    }
  }

  void steer(float dt) {
    for (std::size_t i = 0; i < agents_.size(); ++i) forces_[i] = agents_[i].nextForce(kSpeed, dt);
  }

  std::vector<Body>& bodies() { return bodies_; }
  const std::vector<Vec3>& forces() const { return forces_; }

 private:
  std::vector<Body> bodies_;
  std::vector<bspf::walkers::RandomWalk> agents_;
  std::vector<Vec3> forces_;
};

// What one level and configuration measured.
struct Result {
  double nsPerStep = 0;
  std::vector<double> penetrations, deviations;
  long long insideSolid = 0, refused = 0, steps = 0, iterations = 0;
  int frames = 0;
};

struct RunInput {
  const bspf::World& world;
  const Level& level;
  const Config& config;
  std::span<const Vec3> starts;
  int frames;
  std::uint64_t seed;
};

// The reference end of one step from `body`'s state: the exact sweep with 32
// iterations and a 0.1 mm skin.
Vec3 referenceEnd(const bspf::World& world, const Body& body, const Vec3& force, float dt,
                  bspf::StepScratch& scratch) {
  Body reference = body;
  reference.settings.method = bspf::CollisionMethod::ExactSweep;
  reference.settings.maxIterations = 32;
  reference.settings.skin = 1e-4f;
  bspf::stepBody(world, reference, force, dt, scratch);
  return reference.position;
}

// One pass of a run from the starts: returns the median over frames of the
// frame's stepping time per agent, ns. With `measure`, also fills it with the
// accuracy figures (outside the timed part; they slow the pass down).
double pass(const RunInput& in, const FrameStepper& stepFrame, Result* measure) {
  std::vector<bspf::StepReport> reports(in.starts.size());
  Crowd crowd(in.starts, in.config.settings, in.seed);
  std::vector<double> frameNs;
  bspf::StepScratch oracleScratch;
  const std::optional<bspf::oracle::LevelTriangles> judged =
      measure ? std::optional<bspf::oracle::LevelTriangles>(in.world) : std::nullopt;
  std::vector<Vec3> references(in.starts.size());
  for (int frame = 0; frame < in.frames; ++frame) {
    crowd.steer(in.config.dt);
    std::vector<Body>& bodies = crowd.bodies();
    if (measure)
      for (std::size_t i = 0; i < bodies.size(); ++i)
        references[i] =
            referenceEnd(in.world, bodies[i], crowd.forces()[i], in.config.dt, oracleScratch);
    const auto start = std::chrono::steady_clock::now();
    stepFrame(bodies, crowd.forces(), in.config.dt, reports);
    const auto stop = std::chrono::steady_clock::now();
    frameNs.push_back(std::chrono::duration<double, std::nano>(stop - start).count() /
                      double(bodies.size()));
    if (!measure) continue;
    for (std::size_t i = 0; i < bodies.size(); ++i) {
      measure->deviations.push_back((bodies[i].position - references[i]).cast<double>().norm());
      measure->penetrations.push_back(
          bspf::oracle::penetration(*judged, bodies[i].position, kRadii));
      measure->refused += reports[i].refused;
      measure->iterations += reports[i].iterations;
    }
    measure->insideSolid += bspf::walkers::countInsideSolid(in.level.brushes, bodies);
    measure->steps += long(bodies.size());
  }
  if (measure) measure->frames = in.frames;
  return median(frameNs);
}

std::string number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

const char* kHeader =
    "level,method,knob,value,dt,agents,frames,steps,ns_per_step,ns_per_agent_second,"
    "penetration_p99,penetration_max,deviation_p50_m,deviation_p99_m,deviation_max_m,"
    "deviation_p99_frac,inside_solid,refused,iterations_mean";

std::string row(const std::string& level, const Config& c, int agents, Result& r) {
  std::ostringstream out;
  const double steps = double(std::max(1LL, r.steps));
  const double devP99 = bspf::oracle::quantile(r.deviations, 0.99);
  out << level << ',' << methodName(c.method) << ',' << c.knob << ',' << c.value << ','
      << number(c.dt) << ',' << agents << ',' << r.frames << ',' << r.steps << ','
      << number(r.nsPerStep) << ',' << number(r.nsPerStep / c.dt) << ','
      << number(bspf::oracle::quantile(r.penetrations, 0.99)) << ','
      << number(bspf::oracle::quantile(r.penetrations, 1.0)) << ','
      << number(bspf::oracle::quantile(r.deviations, 0.5)) << ',' << number(devP99) << ','
      << number(bspf::oracle::quantile(r.deviations, 1.0)) << ',' << number(devP99 / kRadii.xz)
      << ',' << r.insideSolid << ',' << r.refused << ',' << number(double(r.iterations) / steps);
  return out.str();
}

Level loadLevel(const fs::path& obj) {
  Level level;
  level.name = obj.stem().string();
  level.obj = obj;
  level.mesh = bspc::importMesh(obj, {});
  const fs::path base = obj.parent_path() / level.name;
  const bspf::walkers::Points spawns = bspf::walkers::loadSpawns(base.string() + ".spawns.txt");
  if (!spawns) throw std::runtime_error(spawns.error);
  level.spawns = spawns.points;
  // Levels not built from brushes (--obj) may have no brush file: no
  // solid is then counted as entered.
  const fs::path brushes = base.string() + ".brushes.txt";
  if (fs::exists(brushes)) level.brushes = bspf::walkers::BrushSet::load(brushes);
  return level;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"bspf_sweep: speed against accuracy of the narrow phases, one knob at a time",
               "bspf_sweep"};
  std::string outPath = "speed-accuracy.csv", samplesDir = BSPF_SAMPLES_DIR,
              sharedDir = std::getenv("BSPF_SHARED_LEVELS") ? std::getenv("BSPF_SHARED_LEVELS")
                                                            : BSPF_SHARED_LEVELS_DIR;
  std::vector<std::string> only, extraObjs, methods;
  bool quick = false, defaultOnly = false;
  int agents = 32, frames = 300, repeats = 3;
  std::uint64_t seed = 1;
  app.add_option("--out", outPath, "The CSV to write")->capture_default_str();
  app.add_flag("--quick", quick,
               "A smoke run: arena and slopes, 16 agents, 60 frames, default and 1 iteration only");
  app.add_option("--agents", agents, "Agents per run")
      ->capture_default_str()
      ->check(CLI::Range(1, 100000));
  app.add_option("--frames", frames, "Frames per run at dt 1/60 (scaled to the same time)")
      ->capture_default_str()
      ->check(CLI::Range(1, 1000000));
  app.add_option("--repeats", repeats, "Timed repeats per run (median)")
      ->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_option("--seed", seed, "Random seed of the walks")->capture_default_str();
  app.add_option("--samples", samplesDir, "Folder of the sample levels")->capture_default_str();
  app.add_option("--shared", sharedDir, "Folder of the shared levels (skipped when absent)")
      ->capture_default_str();
  app.add_option("--level", only, "Only these levels (by name; repeatable)");
  app.add_option("--obj", extraObjs,
                 "Also this level (an OBJ with NAME.spawns.txt beside it, NAME.brushes.txt "
                 "optional; repeatable)")
      ->check(CLI::ExistingFile);
  app.add_flag("--default-only", defaultOnly, "Only the default settings, no knob varied");
  app.add_option("--method", methods, "Only these methods (repeatable)")
      ->check(CLI::IsMember({"planes", "exact", "bullet"}));
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;
  if (quick) {
    agents = 16;
    frames = 60;
    if (only.empty()) only = {"arena", "slopes"};
  }

#ifdef BSPF_HAVE_BULLET
  const bool withBullet = true;
#else
  const bool withBullet = false;
  std::printf("bspf_sweep: built without Bullet: the bullet peer is skipped\n");
#endif

  std::vector<fs::path> objs;
  for (const char* name : {"arena", "box_room", "slopes"})
    objs.push_back(fs::path(samplesDir) / (std::string(name) + ".obj"));
  if (fs::is_directory(sharedDir)) {
    for (const char* name : {"fan", "oa_dm1", "oacmpdm5", "oa_dm4", "oa_dm5", "oacmpctf3"})
      objs.push_back(fs::path(sharedDir) / (std::string(name) + ".obj"));
  } else {
    std::printf("bspf_sweep: %s not found: sample levels only\n", sharedDir.c_str());
  }
  for (const std::string& obj : extraObjs) objs.push_back(obj);
  if (!only.empty())
    std::erase_if(objs, [&](const fs::path& p) {
      return std::find(only.begin(), only.end(), p.stem().string()) == only.end();
    });
  if (objs.empty()) {
    std::fprintf(stderr, "bspf_sweep: error: no level selected\n");
    return 2;
  }

  const std::vector<Config> configs = makeConfigs(quick, defaultOnly, withBullet, methods);
  if (configs.empty()) {
    std::fprintf(stderr, "bspf_sweep: error: no method selected is built\n");
    return 2;
  }
  std::vector<std::string> rows;
  std::vector<Result> pooled(configs.size());
  std::vector<std::vector<double>> levelNs(configs.size());
  const auto began = std::chrono::steady_clock::now();
  try {
    for (const fs::path& obj : objs) {
      const Level level = loadLevel(obj);
      const std::vector<Vec3> starts = bspf::walkers::startsFromSpawns(level.spawns, agents);
      std::map<std::uint32_t, bspf::bench::CompiledLevel> compiled;
      for (const Config& c : configs)
        if (!compiled.count(c.leaf)) compiled.emplace(c.leaf, compile(level, c.leaf));
#ifdef BSPF_HAVE_BULLET
      const bspf::bench::BulletPeer peer(compiled.at(kDefaultLeaf).world(), kRadii);
#endif
      bspf::StepScratch scratch;
      std::vector<RunInput> inputs;
      std::vector<FrameStepper> steppers;
      for (const Config& c : configs) {
        const bspf::World* world = &compiled.at(c.leaf).world();
        const int runFrames = std::max(1, int(std::lround(frames * kDefaultDt / c.dt)));
        inputs.push_back({*world, level, c, starts, runFrames, seed});
        steppers.push_back([world, &scratch](std::span<Body> bodies, std::span<const Vec3> forces,
                                             float dt, std::span<bspf::StepReport> reports) {
          for (std::size_t i = 0; i < bodies.size(); ++i)
            bspf::stepBody(*world, bodies[i], forces[i], dt, scratch, &reports[i]);
        });
#ifdef BSPF_HAVE_BULLET
        if (c.method == Method::Bullet)
          steppers.back() = [&peer, iterations = c.settings.maxIterations](
                                std::span<Body> bodies, std::span<const Vec3> forces, float dt,
                                std::span<bspf::StepReport> reports) {
            for (std::size_t i = 0; i < bodies.size(); ++i)
              peer.step(bodies[i], forces[i], dt, iterations, reports[i]);
          };
#endif
      }
      // The timed passes, interleaved: each repeat runs every configuration
      // once, so a burst of other load on the machine spreads over the
      // configurations instead of spoiling all repeats of one.
      std::vector<std::vector<double>> repeatNs(configs.size());
      for (int repeat = 0; repeat < repeats; ++repeat)
        for (std::size_t k = 0; k < configs.size(); ++k)
          repeatNs[k].push_back(pass(inputs[k], steppers[k], nullptr));
      for (std::size_t k = 0; k < configs.size(); ++k) {
        Result r;
        pass(inputs[k], steppers[k], &r);  // the same trajectories, measured
        r.nsPerStep = median(repeatNs[k]);
        rows.push_back(row(level.name, configs[k], agents, r));
        std::fprintf(stderr, "bspf_sweep: %s\n", rows.back().c_str());
        Result& all = pooled[k];
        levelNs[k].push_back(r.nsPerStep);
        all.penetrations.insert(all.penetrations.end(), r.penetrations.begin(),
                                r.penetrations.end());
        all.deviations.insert(all.deviations.end(), r.deviations.begin(), r.deviations.end());
        all.insideSolid += r.insideSolid;
        all.refused += r.refused;
        all.steps += r.steps;
        all.iterations += r.iterations;
        all.frames = r.frames;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bspf_sweep: error: %s\n", e.what());
    return 1;
  }
  for (std::size_t k = 0; k < configs.size(); ++k) {
    pooled[k].nsPerStep = median(levelNs[k]);
    rows.push_back(row("all", configs[k], agents, pooled[k]));
  }

  const std::string temp = outPath + ".tmp";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    out << "# bspf_sweep: " << objs.size() << " levels, " << agents << " agents, " << frames
        << " frames at dt 1/60 (the same simulated time at other dt), seed " << seed << ", "
        << repeats << " timed repeats; speed " << kSpeed << " m/s, radii xz " << kRadii.xz << " y "
        << kRadii.y << " m\n"
        << "# Each body is stepped alone against the level (stepBody; the peer its own step): no "
           "body-against-body pushes.\n"
        << "# ns_per_step: median over frames of (frame's stepping time / agents), median over "
           "repeats; level 'all': median over levels (each level weighted equally).\n"
        << "# penetration: fraction of the body's size (oracle::penetration) of every end "
           "position; deviation: metres from a reference end from the same state (exact sweep, "
           "32 iterations, skin 1e-4 m); deviation_p99_frac: p99 / radius xz.\n"
        << "# level 'all': errors pooled over every step of every level, counts summed; "
           "inside_solid in agent-frames (centre > 1 mm inside a brush).\n"
        << kHeader << '\n';
    for (const std::string& r : rows) out << r << '\n';
    if (!out) {
      std::fprintf(stderr, "bspf_sweep: error: %s: write error\n", temp.c_str());
      return 1;
    }
  }
  fs::rename(temp, outPath);
  std::printf("bspf_sweep: wrote %s: %zu rows in %.1f s\n", outPath.c_str(), rows.size(),
              std::chrono::duration<double>(std::chrono::steady_clock::now() - began).count());
  return 0;
}
