// SPDX-License-Identifier: MIT
#include <bspf/thread_pool.h>

#include <atomic>
#include <catch2/catch.hpp>
#include <chrono>
#include <memory>
#include <thread>
#include <vector>

TEST_CASE("a thread pool's parallelFor covers every item exactly once, call after call",
          "[runtime][threads]") {
  const int threads = GENERATE(1, 2, 3, 4);
  const auto handout =
      GENERATE(bspf::ThreadPool::Handout::ThreadShares, bspf::ThreadPool::Handout::InOrder);
  INFO(threads << " threads, handout " << int(handout));
  bspf::ThreadPool pool(threads);
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
