// SPDX-License-Identifier: MIT
// walkers: a crowd of ellipsoid bodies random-walking through a compiled
// level, as a demo of the runtime and a benchmark of its movement step.
//
//   walkers LEVEL.bspf [--spawns FILE] [--agents N] [--frames F] [--speed M_PER_S]
//           [--seed K] [--dt S] [--radius-xz R] [--radius-y R] [--method planes|exact]
//           [--step-height M] [--step-down M] [--threads N] [--pin-threads] [--spin-us US]
//           [--trace OUT.csv] [--svg OUT.svg] [--json]
//           [--brushes FILE]
//
// Each agent walks in a random direction (a new one every 0.5 to 2 s) at
// --speed, under gravity; all agents step together through bspf::stepBodies,
// so they also push each other apart. Agents start 0.3 m above the spawn
// points (round robin) or, without --spawns, on random open walkable floor.
// Prints a summary (or one JSON object with --json); --trace writes every
// agent's centre after every frame. With --brushes (the level's solids as
// planes, a `.brushes.txt` file) it counts, after every frame and outside the
// timed region, the agents whose centre is inside a solid (by more than 1 mm):
// 0 when the movement step never lets a body into a wall. --svg draws the
// level from above with every agent's path and the refused moves, fell-out
// points and inside-solid points (walkers_svg.h). Same inputs and
// seed, same trace.
//
// Links the runtime only (never the compiler or assimp).
#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <system_error>

#include "oracle.h"
#include "walkers_sim.h"
#include "walkers_svg.h"

namespace {

int fail(const std::string& message, int status = 1) {
  std::cerr << "walkers: error: " << message << "\n";
  return status;
}

// A JSON string literal (paths may hold quotes or backslashes).
std::string jsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char escaped[8];
      std::snprintf(escaped, sizeof escaped, "\\u%04x", c);
      out += escaped;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// Shortest text that reads back as the same float.
std::string exact(float v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.9g", v);
  return text;
}

// Writes `text` to path.tmp, then renames it over `path`: a failed run
// leaves no half-written file. Returns an error message naming the file, or
// an empty string.
std::string writeAtomically(const std::string& path, const std::string& text) {
  const std::filesystem::path temp = path + ".tmp";
  {
    std::ofstream out(temp, std::ios::binary | std::ios::trunc);
    if (!out) return temp.string() + ": cannot write";
    out << text;
    out.close();
    if (!out) {
      std::error_code ignored;
      std::filesystem::remove(temp, ignored);
      return temp.string() + ": write error";
    }
  }
  std::error_code error;
  std::filesystem::rename(temp, path, error);
  if (error) return path + ": cannot replace it: " + error.message();
  return {};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"walkers: random-walking ellipsoid bodies in a compiled .bspf level", "walkers"};
  bspf::walkers::Options options;
  std::string levelPath, spawnsPath, tracePath, brushesPath, svgPath;
  bool json = false;
  app.add_option("level", levelPath, "The compiled level (.bspf)")->type_name("FILE")->required();
  app.add_option("--spawns", spawnsPath,
                 "Spawn points, one 'x y z' a line; agents start 0.3 m above them, round robin "
                 "(default: random open walkable floor)")
      ->type_name("FILE");
  app.add_option("--agents", options.agents, "Number of agents")->capture_default_str();
  app.add_option("--frames", options.frames, "Frames to simulate")->capture_default_str();
  app.add_option("--speed", options.speed, "Walking speed, m/s")->capture_default_str();
  app.add_option("--seed", options.seed, "Random seed (placement and walks)")
      ->capture_default_str();
  app.add_option("--dt", options.dt, "Seconds per frame")->capture_default_str();
  app.add_option("--radius-xz", options.radii.xz, "Body radius along x and z, m")
      ->capture_default_str();
  app.add_option("--radius-y", options.radii.y, "Body radius along y, m")->capture_default_str();
  std::string method = "planes";
  app.add_option("--method", method, "Narrow phase: planes (the article's) or exact")
      ->type_name("planes|exact")
      ->capture_default_str();
  app.add_option("--step-height", options.stepHeight,
                 "Highest ledge a walking agent steps up onto, m (0: off, as in the article)")
      ->capture_default_str();
  app.add_option("--step-down", options.stepDown,
                 "Deepest drop a walking agent is set down onto ground instead of leaving it, m "
                 "(ground snapping; 0: off)")
      ->capture_default_str();
  app.add_option("--threads", options.threads,
                 "Threads stepping the crowd (a thread pool; same trajectories for any number)")
      ->capture_default_str();
  app.add_flag("--pin-threads", options.pinThreads,
               "Each stepping thread on a CPU of its own (Linux; same trajectories)");
  app.add_option("--spin-us", options.spinMicroseconds,
                 "How long a stepping thread with no work waits busily for the next before it "
                 "sleeps, microseconds (the thread pool's spinBeforeSleep; same trajectories)")
      ->capture_default_str();
  app.add_option("--trace", tracePath,
                 "Write 'frame,agent,x,y,z' (every centre after every frame) to this CSV")
      ->type_name("FILE");
  app.add_option("--svg", svgPath,
                 "Draw the level from above, with every agent's path, refused moves, fell-out "
                 "and inside-solid points, to this SVG file")
      ->type_name("FILE");
  app.add_flag("--json", json, "Print one JSON object instead of a summary");
  bool accuracy = false;
  app.add_flag("--accuracy", accuracy,
               "Also measure, untimed, each agent's penetration into the level after every frame "
               "(exact, in sphere space) and each step's deviation between the two narrow phases "
               "from the same state");
  app.add_option("--brushes", brushesPath,
                 "The level's solids as planes (a .brushes.txt file); counts agents whose centre "
                 "is inside one, after every frame")
      ->type_name("FILE");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);
    return fail(std::string(e.what()) + " (see walkers --help)", 2);
  }
  if (CLI::detail::to_lower(method) == "planes")
    options.method = bspf::CollisionMethod::Planes;
  else if (CLI::detail::to_lower(method) == "exact")
    options.method = bspf::CollisionMethod::ExactSweep;
  else
    return fail(
        "--method '" + method + "': the narrow phase is planes or exact (see walkers --help)", 2);
  if (const std::string problem = bspf::walkers::validate(options); !problem.empty())
    return fail(problem, 2);

  const bspf::OpenResult opened = bspf::openWorld(levelPath);
  if (!opened) return fail(opened.message);
  const bspf::World& world = *opened.world;

  std::optional<bspf::walkers::BrushSet> brushes;
  if (!brushesPath.empty()) {
    try {
      brushes = bspf::walkers::BrushSet::load(brushesPath);
    } catch (const std::exception& e) {
      return fail(e.what());  // names the file (and the line)
    }
  }

  const bspf::walkers::Points starts =
      bspf::walkers::placeAgents(world, options, spawnsPath, levelPath);
  if (!starts) return fail(starts.error);

  // The trace goes to OUT.tmp and is renamed over OUT once complete.
  std::ofstream trace;
  std::filesystem::path traceTemp;
  if (!tracePath.empty()) {
    traceTemp = tracePath + ".tmp";
    trace.open(traceTemp, std::ios::binary | std::ios::trunc);
    if (!trace) return fail(traceTemp.string() + ": cannot write the trace");
    trace << "frame,agent,x,y,z\n";
  }

  bspf::walkers::Simulation sim(world, starts.points, options);
  std::optional<bspf::walkers::SvgRecorder> svg;
  if (!svgPath.empty()) svg.emplace(world);
  std::vector<bool> insideNow;
  long long insideSolid = 0;  // agent-frames with the centre inside a solid
  std::vector<double> penetrations, deviations;
  bspf::StepScratch oracleScratch;
  const std::optional<bspf::oracle::LevelTriangles> judged =
      accuracy ? std::optional<bspf::oracle::LevelTriangles>(world) : std::nullopt;
  const auto measureDeviation = [&](std::span<const bspf::Body> bodies,
                                    std::span<const bspf::Vec3> forces) {
    for (std::size_t i = 0; i < bodies.size(); ++i)
      deviations.push_back(
          bspf::oracle::stepDeviation(world, bodies[i], forces[i], options.dt, oracleScratch));
  };
  for (int frame = 0; frame < options.frames; ++frame) {
    if (accuracy)
      sim.step(measureDeviation);  // times stepBodies only
    else
      sim.step();
    if (brushes) insideSolid += bspf::walkers::countInsideSolid(*brushes, sim.bodies());
    if (svg) {
      insideNow.clear();
      if (brushes)
        for (const bspf::Body& b : sim.bodies())
          insideNow.push_back(brushes->insideAnySolid(b.position, bspf::walkers::kInsideMargin));
      svg->frame(sim.bodies(), sim.reports(), insideNow);
    }
    if (accuracy)
      for (const bspf::Body& b : sim.bodies())
        penetrations.push_back(bspf::oracle::penetration(*judged, b.position, b.radii));
    if (trace.is_open()) {
      const auto bodies = sim.bodies();
      for (std::size_t i = 0; i < bodies.size(); ++i) {
        const bspf::Vec3& p = bodies[i].position;
        trace << frame << ',' << i << ',' << exact(p.x()) << ',' << exact(p.y()) << ','
              << exact(p.z()) << '\n';
      }
    }
  }
  if (trace.is_open()) {
    trace.close();
    if (!trace) {
      std::error_code ignored;
      std::filesystem::remove(traceTemp, ignored);
      return fail(traceTemp.string() + ": write error");
    }
    std::error_code error;
    std::filesystem::rename(traceTemp, tracePath, error);
    if (error) return fail(tracePath + ": cannot replace it: " + error.message());
  }

  if (svg) {
    const std::string title =
        std::filesystem::path(levelPath).filename().string() + ": " +
        std::to_string(options.agents) + " agents, " + std::to_string(options.frames) +
        " frames, " + exact(options.speed) + " m/s, " +
        (options.method == bspf::CollisionMethod::Planes ? "planes" : "exact");
    if (const std::string problem = writeAtomically(svgPath, svg->svg(title)); !problem.empty())
      return fail(problem);
  }

  const bspf::walkers::Summary s = sim.summary();
  // Agents that fell out of the level: centre below its lowest point.
  const float floorY = world.blob().bounds_min()->y();
  int fellOut = 0;
  for (const bspf::Body& b : sim.bodies()) fellOut += b.position.y() < floorY;

  // Accuracy figures: penetration as a fraction of the body's size, deviation
  // in metres; null without --accuracy.
  auto figure = [&](std::vector<double>& values, double p) {
    if (!accuracy) return std::string("null");
    std::ostringstream text;
    text.precision(6);
    text << bspf::oracle::quantile(values, p);
    return text.str();
  };
  const std::string penetrationP99 = figure(penetrations, 0.99),
                    penetrationMax = figure(penetrations, 1.0),
                    deviationP50 = figure(deviations, 0.5), deviationP99 = figure(deviations, 0.99),
                    deviationMax = figure(deviations, 1.0);

  if (json) {
    std::ostringstream out;
    out.precision(6);
    out << "{\"level\": " << jsonString(levelPath)
        << ", \"placement\": " << (spawnsPath.empty() ? "\"floor\"" : "\"spawns\"")
        << ", \"agents\": " << options.agents << ", \"frames\": " << options.frames
        << ", \"speed\": " << options.speed << ", \"dt\": " << options.dt << ", \"method\": \""
        << (options.method == bspf::CollisionMethod::Planes ? "planes" : "exact") << "\""
        << ", \"step_height\": " << options.stepHeight << ", \"step_down\": " << options.stepDown
        << ", \"radius_xz\": " << options.radii.xz << ", \"radius_y\": " << options.radii.y
        << ", \"seed\": " << options.seed << ", \"threads\": " << options.threads
        << ", \"pin_threads\": " << (options.pinThreads ? "true" : "false")
        << ", \"spin_us\": " << options.spinMicroseconds
        << ", \"pool_sleeps\": " << sim.poolSleeps() << ", \"steps\": " << s.steps
        << ", \"ns_per_step\": " << s.nsPerStep << ", \"refused_moves\": " << s.refusedMoves
        << ", \"iterations_mean\": " << s.iterationsMean
        << ", \"iterations_max\": " << s.iterationsMax
        << ", \"grounded_fraction\": " << s.groundedFraction
        << ", \"body_contacts_mean\": " << s.bodyContactsMean << ", \"fell_out\": " << fellOut
        << ", \"inside_solid\": " << (brushes ? std::to_string(insideSolid) : "null")
        << ", \"penetration_p99\": " << penetrationP99
        << ", \"penetration_max\": " << penetrationMax << ", \"deviation_p50\": " << deviationP50
        << ", \"deviation_p99\": " << deviationP99 << ", \"deviation_max\": " << deviationMax
        << "}\n";
    std::cout << out.str();
  } else {
    std::printf(
        "walkers: %s: %d agents x %d frames at %g m/s (dt %g s, placement %s, %d threads)\n",
        levelPath.c_str(), options.agents, options.frames, double(options.speed),
        double(options.dt), spawnsPath.empty() ? "on floor" : "from spawns", options.threads);
    std::printf("  %lld steps, %.0f ns per step (median frame)\n", s.steps, s.nsPerStep);
    std::printf("  refused moves %lld, slides per step %.3f (max %d), grounded %.1f%%\n",
                s.refusedMoves, s.iterationsMean, s.iterationsMax, 100 * s.groundedFraction);
    std::printf("  body contacts per step %.3f, fell out of the level %d\n", s.bodyContactsMean,
                fellOut);
    if (brushes)
      std::printf("  inside a solid of %s: %lld agent-frames\n", brushesPath.c_str(), insideSolid);
    if (accuracy)
      std::printf(
          "  penetration p99 %s, max %s (of the body's size); planes-exact deviation per step "
          "p50 %s, p99 %s, max %s m\n",
          penetrationP99.c_str(), penetrationMax.c_str(), deviationP50.c_str(),
          deviationP99.c_str(), deviationMax.c_str());
    if (!tracePath.empty()) std::printf("  trace: %s\n", tracePath.c_str());
    if (!svgPath.empty()) std::printf("  picture: %s\n", svgPath.c_str());
  }
  return 0;
}
