// SPDX-License-Identifier: MIT
#include <bspf/thread_pool.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

#ifdef __linux__
#include <sched.h>
#endif

TEST_CASE("a thread pool's parallelFor covers every item exactly once, call after call",
          "[runtime][threads]") {
  const int threads = GENERATE(1, 2, 3, 4);
  const auto handout =
      GENERATE(bspf::ThreadPool::Handout::ThreadShares, bspf::ThreadPool::Handout::InOrder);
  const auto affinity =
      GENERATE(bspf::ThreadPool::Affinity::None, bspf::ThreadPool::Affinity::PinWorkers);
  INFO(threads << " threads, handout " << int(handout) << ", affinity " << int(affinity));
  bspf::ThreadPool pool(threads, affinity);
  REQUIRE(pool.threadCount() == threads);
  for (int call = 0; call < 50; ++call) {
    const std::size_t count = std::size_t(call * 37 % 301);
    const std::size_t chunk = std::size_t(1 + call % 7);
    INFO("call " << call << ": " << count << " items in ranges of " << chunk);
    const auto visits = std::make_unique<std::atomic<int>[]>(count + 1);
    std::atomic<bool> rangesFit = true, threadsInRange = true;
    pool.parallelFor(
        count, chunk,
        [&](int thread, std::size_t first, std::size_t last) {
          if (thread < 0 || thread >= threads) threadsInRange = false;
          if (first >= last || last > count || last - first > chunk || first % chunk != 0)
            rangesFit = false;
          for (std::size_t i = first; i < last; ++i) ++visits[i];
        },
        handout);
    REQUIRE(rangesFit);
    REQUIRE(threadsInRange);
    for (std::size_t i = 0; i < count; ++i) REQUIRE(visits[i] == 1);
  }
}

TEST_CASE("a thread pool runs ranges on several threads at once", "[runtime][threads]") {
  // Every range waits until two threads are inside at the same time: with
  // one thread the pool would never return, so this fails by hanging rather
  // than by luck. The wait is bounded to keep a broken pool from blocking
  // the suite forever.
  bspf::ThreadPool pool(2);
  std::atomic<int> inside = 0, mostInside = 0;
  pool.parallelFor(2, 1, [&](int, std::size_t, std::size_t) {
    const int now = ++inside;
    int seen = mostInside.load();
    while (now > seen && !mostInside.compare_exchange_weak(seen, now)) {
    }
    for (long spins = 0; mostInside.load() < 2 && spins < 2'000'000'000L; ++spins)
      std::this_thread::yield();
    --inside;
  });
  REQUIRE(mostInside == 2);
}

TEST_CASE("a thread pool covers every item when its workers have gone to sleep between calls",
          "[runtime][threads]") {
  // Workers spin a little after a job, then sleep: a pause longer than the
  // spin between calls makes each call wake them from the sleep.
  bspf::ThreadPool pool(3);
  for (int call = 0; call < 20; ++call) {
    std::this_thread::sleep_for(std::chrono::milliseconds(call % 2 == 0 ? 2 : 0));
    const std::size_t count = 64;
    const auto visits = std::make_unique<std::atomic<int>[]>(count);
    pool.parallelFor(count, 3, [&](int, std::size_t first, std::size_t last) {
      for (std::size_t i = first; i < last; ++i) ++visits[i];
    });
    INFO("call " << call);
    for (std::size_t i = 0; i < count; ++i) REQUIRE(visits[i] == 1);
  }
}

TEST_CASE("a pool's workers sleep between calls further apart than their spin, and only then",
          "[runtime][threads]") {
  // Calls 2 ms apart: longer than a zero spin, far shorter than a 10 s one.
  // The destructor ends a spin at once, so the long one costs no time here.
  const auto pausedCalls = [](bspf::ThreadPool& pool) {
    for (int call = 0; call < 6; ++call) {
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
      std::atomic<int> visits = 0;
      pool.parallelFor(
          64, 4, [&](int, std::size_t first, std::size_t last) { visits += int(last - first); });
      REQUIRE(visits == 64);
    }
  };
  SECTION("a zero spin: the workers sleep in the pauses") {
    bspf::ThreadPool pool(3, bspf::ThreadPool::Affinity::None, std::chrono::microseconds(0));
    pausedCalls(pool);
    // Each of the 2 workers sleeps in each pause it spends waiting (12 in
    // all); fewer only for one the system kept from running through a
    // pause, so the bound leaves room for a loaded machine.
    REQUIRE(pool.sleeps() >= 3);
  }
  SECTION("a spin longer than the pauses: no worker sleeps once it has run a job") {
    bspf::ThreadPool pool(3, bspf::ThreadPool::Affinity::None, std::chrono::seconds(10));
    // Every worker joins the first job (each of its first ranges waits for
    // both), so each is awake and spinning after it.
    std::atomic<int> started = 0;
    pool.parallelFor(3, 1, [&](int, std::size_t, std::size_t) {
      ++started;
      for (long spins = 0; started.load() < 3 && spins < 2'000'000'000L; ++spins)
        std::this_thread::yield();
    });
    REQUIRE(started == 3);
    const unsigned long long before = pool.sleeps();
    REQUIRE(before <= 2);  // at most each worker's wait for the first job
    pausedCalls(pool);
    REQUIRE(pool.sleeps() == before);
  }
}

TEST_CASE("a thread pool's task may be destroyed as soon as parallelFor returns",
          "[runtime][threads]") {
  // The caller runs out of ranges and returns without waiting for a worker
  // still waking up, but must wait for every worker running a range: each
  // range here takes tens of microseconds, so returning early leaves an
  // item unvisited, and the task (on the heap, freed at once) used after
  // free for the sanitizer builds to report. The pauses let workers fall
  // asleep between jobs, so some wake too late for any range.
  const int threads = GENERATE(2, 4);
  INFO(threads << " threads");
  bspf::ThreadPool pool(threads);
  for (int call = 0; call < 300; ++call) {
    if (call % 3 == 0) std::this_thread::sleep_for(std::chrono::microseconds(100 + call % 4 * 100));
    const std::size_t count = std::size_t(call % (2 * threads + 1));
    const auto visits = std::make_unique<std::atomic<int>[]>(count + 1);
    auto task = std::make_unique<bspf::ThreadPool::RangeTask>(
        [&visits](int, std::size_t first, std::size_t last) {
          const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(20);
          while (std::chrono::steady_clock::now() < until) {
          }
          for (std::size_t i = first; i < last; ++i) ++visits[i];
        });
    pool.parallelFor(count, 1, *task);
    task.reset();
    INFO("call " << call);
    for (std::size_t i = 0; i < count; ++i) REQUIRE(visits[i] == 1);
  }
}

#ifdef __linux__
// The CPUs the calling thread may run on, in order.
static std::vector<int> allowedCpus() {
  cpu_set_t allowed;
  std::vector<int> cpus;
  if (sched_getaffinity(0, sizeof(allowed), &allowed) != 0) return cpus;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu)
    if (CPU_ISSET(cpu, &allowed)) cpus.push_back(cpu);
  return cpus;
}

TEST_CASE("a pool that pins its workers runs worker t on the t-th of the process's CPUs",
          "[runtime][threads]") {
  const std::vector<int> cpus = allowedCpus();
  if (cpus.size() < 2) {
    WARN("one CPU only: every worker would be pinned to it, nothing to tell apart");
    return;
  }
  const int threads = 3;
  bspf::ThreadPool pool(threads, bspf::ThreadPool::Affinity::PinWorkers);
  // Each worker's CPU and allowed CPUs, as it sees them from inside the
  // first range it runs (ranges this short are otherwise all taken by the
  // first threads awake).
  std::vector<int> ranOn(threads, -1);
  std::vector<std::vector<int>> allowed(threads);
  std::vector<std::atomic<bool>> ran(threads);
  std::atomic<int> workersIn = 0;
  // Every thread's first range waits until each worker has run one, so no
  // thread takes another's ranges before that worker has joined.
  auto waitForWorkers = [&] {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (workersIn < threads - 1 && std::chrono::steady_clock::now() < deadline)
      std::this_thread::yield();
  };
  pool.parallelFor(4096, 1, [&](int thread, std::size_t, std::size_t) {
    if (ran[std::size_t(thread)].exchange(true)) return;
    if (thread != 0) {
      ranOn[std::size_t(thread)] = sched_getcpu();
      allowed[std::size_t(thread)] = allowedCpus();
      ++workersIn;
    }
    waitForWorkers();
  });
  REQUIRE(workersIn == threads - 1);
  for (int t = 1; t < threads; ++t) {
    INFO("worker " << t);
    const int expected = cpus[std::size_t(t) % cpus.size()];
    REQUIRE(ranOn[std::size_t(t)] == expected);
    REQUIRE(allowed[std::size_t(t)] == std::vector<int>{expected});
  }
}

TEST_CASE("pinning a thread to the first CPU leaves it only that one", "[runtime][threads]") {
  const std::vector<int> cpus = allowedCpus();
  REQUIRE_FALSE(cpus.empty());
  // On a thread of its own, so that the test runner's thread keeps its CPUs.
  bool pinned = false;
  std::vector<int> after;
  std::thread([&] {
    pinned = bspf::ThreadPool::pinThisThreadToFirstCpu();
    after = allowedCpus();
  }).join();
  REQUIRE(pinned);
  REQUIRE(after == std::vector<int>{cpus.front()});
  REQUIRE(allowedCpus() == cpus);
}
#endif
