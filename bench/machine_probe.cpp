// SPDX-License-Identifier: MIT
// bspf_machine_probe: the state of the machine a benchmark runs on, in one
// JSON line, so that figures from a shared, noisy machine can be read in
// context. On the 2-core machines the team measures on, the same build's
// walkers figures moved by up to 1.7 times from hour to hour: at times one
// core ran 20% slower than the other, and at times a random memory read took
// 2.5 times as long (other tenants). Each figure is the median of
// --repeats:
//   - compute_ns_cpuK: one dependent floating-point multiply-add, ns, on
//     core K alone (pinned; Linux only, else one figure for the thread);
//   - compute_ns_side_by_side: the slowest core's, with every core running
//     the same loop at once;
//   - throughput_ns / throughput_ns_side_by_side: 64 independent multiplies
//     (16 vectors of four), ns, on the first core alone and the slowest core
//     with every core running them at once. Bound by the core's width, not
//     its clock: two virtual CPUs placed on one physical core (two hardware
//     threads) share it, and the side-by-side figure rises (1.5 times,
//     measured, when the round trip also fell from about 500 to 117 ns),
//     which the dependent chain above does not show. No two threads then
//     run twice as fast as one;
//   - cache_ns: one dependent read at a random place of a 4 MiB buffer,
//     beyond a core's own caches but within the shared last-level cache of a
//     quiet machine (where a level blob's working set lives): the figure
//     that moved most with the walkers' (2.5 times), as other tenants took
//     that cache;
//   - memory_ns / memory_ns_side_by_side: the same in a 64 MiB buffer
//     (a DRAM access), alone and on every core at once;
//   - round_trip_ns: a cache line passed from the first core to the second
//     and back (what a thread pool's hand-off, or a line written on one core
//     and read on the other, costs).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <numeric>
#include <string>
#include <thread>
#include <vector>

#include "support/cli.h"
#include "support/median.h"

#ifdef __linux__
#include <pthread.h>
#include <sched.h>
#endif

namespace {

using bspf::bench::median;

using Clock = std::chrono::steady_clock;

double nanosecondsSince(Clock::time_point start, double operations) {
  return std::chrono::duration<double, std::nano>(Clock::now() - start).count() / operations;
}

// The cores this process may run on (one entry, -1, where they are unknown).
std::vector<int> allowedCores() {
  std::vector<int> cores;
#ifdef __linux__
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0)
    for (int core = 0; core < CPU_SETSIZE; ++core)
      if (CPU_ISSET(core, &set)) cores.push_back(core);
#endif
  if (cores.empty()) cores.push_back(-1);
  return cores;
}

// Pins the calling thread to `core` (-1: leaves it where it is).
void pinTo(int core) {
#ifdef __linux__
  if (core < 0) return;
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(core, &set);
  pthread_setaffinity_np(pthread_self(), sizeof set, &set);
#else
  (void)core;
#endif
}

// ns per step of a dependent multiply-add chain (latency-bound: the core's
// clock, not its width).
double computeNs() {
  constexpr long kSteps = 50'000'000;
  volatile float seed = 1;
  float x = seed;
  const auto start = Clock::now();
  for (long k = 0; k < kSteps; ++k) x = x * 0.999999f + 1e-7f;
  seed = x;
  return nanosecondsSince(start, kSteps);
}

// ns per 64 independent multiplies (16 chains of four-float vectors, as the
// compiler vectorises the inner loop: enough in flight to keep every
// multiplier busy).
double throughputNs() {
  constexpr long kSteps = 10'000'000;
  constexpr int kLanes = 64;
  volatile float seed = 1;
  alignas(16) float x[kLanes];
  for (int k = 0; k < kLanes; ++k) x[k] = seed + float(k) * 1e-7f;
  const auto start = Clock::now();
  for (long step = 0; step < kSteps; ++step)
    for (int k = 0; k < kLanes; ++k) x[k] *= 0.9999999f;
  float sum = 0;
  for (float v : x) sum += v;
  seed = sum;
  return nanosecondsSince(start, kSteps);
}

// A single random cycle through `places` entries (Sattolo's shuffle), so a
// walk reads every entry once, each read depending on the last.
std::vector<std::uint32_t> randomCycle(std::uint32_t places, std::uint64_t seed) {
  std::vector<std::uint32_t> next(places);
  std::iota(next.begin(), next.end(), 0u);
  for (std::uint32_t i = places - 1; i > 0; --i) {
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    std::swap(next[i], next[std::uint32_t((seed >> 33) % i)]);
  }
  return next;
}

double memoryNs(const std::vector<std::uint32_t>& cycle) {
  constexpr long kReads = 4'000'000;
  std::uint32_t at = 0;
  const auto start = Clock::now();
  for (long k = 0; k < kReads; ++k) at = cycle[at];
  volatile std::uint32_t sink = at;
  (void)sink;
  return nanosecondsSince(start, kReads);
}

// Runs `work` on a thread pinned to `core`, and waits for it.
template <typename Work>
void onCore(int core, Work work) {
  std::thread pinned([&] {
    pinTo(core);
    work();
  });
  pinned.join();
}

// Runs `measure` on every core at once, each thread pinned to its own;
// returns the largest result.
template <typename Measure>
double sideBySide(const std::vector<int>& cores, Measure measure) {
  std::vector<double> results(cores.size());
  std::vector<std::thread> threads;
  for (std::size_t t = 0; t < cores.size(); ++t)
    threads.emplace_back([&, t] {
      pinTo(cores[t]);
      results[t] = measure(t);
    });
  for (std::thread& thread : threads) thread.join();
  return *std::max_element(results.begin(), results.end());
}

double roundTripNs(int first, int second) {
  constexpr int kTrips = 100'000;
  alignas(64) std::atomic<int> turn{0};
  std::thread other([&] {
    pinTo(second);
    for (int k = 0; k < kTrips; ++k) {
      while (turn.load(std::memory_order_acquire) != 2 * k + 1) {
      }
      turn.store(2 * k + 2, std::memory_order_release);
    }
  });
  pinTo(first);
  const auto start = Clock::now();
  for (int k = 0; k < kTrips; ++k) {
    turn.store(2 * k + 1, std::memory_order_release);
    while (turn.load(std::memory_order_acquire) != 2 * k + 2) {
    }
  }
  const double ns = nanosecondsSince(start, kTrips);
  other.join();
  return ns;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "bspf_machine_probe: the machine's state for reading benchmark figures: each core's "
      "speed alone and side by side (latency and throughput), a read's latency in the shared cache "
      "and in DRAM alone and "
      "side by side, a cache "
      "line's round trip between two cores. Prints one JSON object (ns; medians).",
      "bspf_machine_probe"};
  int repeats = 3;
  app.add_option("--repeats", repeats, "Repetitions of each measurement (median quoted)")
      ->check(CLI::Range(1, 99));
  if (const int status = bspf::bench::parseCommandLine(app, argc, argv); status >= 0) return status;

  const std::vector<int> cores = allowedCores();
  constexpr std::uint32_t kPlaces = 16u << 20;                             // 64 MiB of entries
  const std::vector<std::uint32_t> cacheCycle = randomCycle(1u << 20, 7);  // 4 MiB
  std::vector<std::vector<std::uint32_t>> cycles;
  for (std::size_t t = 0; t < cores.size() && t < 2; ++t)
    cycles.push_back(randomCycle(kPlaces, t + 1));

  auto repeated = [&](auto measure) {
    std::vector<double> values;
    for (int r = 0; r < repeats; ++r) values.push_back(measure());
    return median(values);
  };
  std::string json = "{\"case\":\"machine\",\"cores\":" + std::to_string(cores.size());
  auto add = [&](const std::string& key, double value) {
    char text[64];
    std::snprintf(text, sizeof text, ",\"%s\":%.2f", key.c_str(), value);
    json += text;
  };
  for (int core : cores)
    onCore(core, [&] {
      add(core < 0 ? "compute_ns" : "compute_ns_cpu" + std::to_string(core), repeated(computeNs));
    });
  if (cores.size() > 1)
    add("compute_ns_side_by_side",
        repeated([&] { return sideBySide(cores, [](std::size_t) { return computeNs(); }); }));
  onCore(cores[0], [&] { add("throughput_ns", repeated(throughputNs)); });
  if (cores.size() > 1)
    add("throughput_ns_side_by_side",
        repeated([&] { return sideBySide(cores, [](std::size_t) { return throughputNs(); }); }));
  onCore(cores[0], [&] {
    add("cache_ns", repeated([&] { return memoryNs(cacheCycle); }));
    add("memory_ns", repeated([&] { return memoryNs(cycles[0]); }));
  });
  if (cores.size() > 1) {
    const std::vector<int> two{cores[0], cores[1]};
    add("memory_ns_side_by_side", repeated([&] {
          return sideBySide(two, [&](std::size_t t) { return memoryNs(cycles[t]); });
        }));
    add("round_trip_ns", repeated([&] { return roundTripNs(cores[0], cores[1]); }));
  }
  std::printf("%s}\n", json.c_str());
  return 0;
}
