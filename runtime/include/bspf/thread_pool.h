// SPDX-License-Identifier: MIT
// bspf/thread_pool.h: a small pool of worker threads for stepping many bodies
// (the stepBodies overload in movement.h takes one). Games with a job system
// of their own can ignore it and drive the phases of movement.h themselves.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace bspf {

/// A fixed set of threads, created once and reused: a frame's work costs two
/// wake-ups, never a thread creation. The calling thread takes part in the
/// work, so a pool of N threads starts N - 1 workers (none for N = 1).
/// After each job the workers (and, waiting for them, the caller) spin for
/// a while (50 µs unless the pool is made with another spinBeforeSleep)
/// before sleeping, so the next phase of a frame starts without a wake-up:
/// a pool costs up to that much CPU per job beyond its work.
class ThreadPool {
 public:
  /// A work item: `thread` is the index, 0 to threadCount() - 1, of the
  /// thread running it (0 is the caller of parallelFor), for per-thread
  /// scratch; [first, last) is the range of items to process.
  using RangeTask = std::function<void(int thread, std::size_t first, std::size_t last)>;

  /// Where the workers run.
  enum class Affinity {
    /// Wherever the operating system puts them (the default).
    None,
    /// Worker t (1 to threads - 1) runs only on the t-th CPU, counted from 0
    /// modulo their number, of those the process may run on when the pool
    /// is made; CPU 0 of them is left to the thread that calls parallelFor,
    /// which the application places itself (pinThisThreadToFirstCpu). For a
    /// loop that steps bodies back to back on a machine it has to itself.
    /// On the project's 2-core VM (whose kernel packs threads onto few
    /// CPUs) the scheduler put a new or woken worker on the caller's CPU,
    /// and left it there, in about half the runs of 1,024 walkers, which
    /// then ran on 2 threads no faster than on one; pinned, 1.72 to 1.89
    /// times (docs/measurements.md, the twenty-ninth pass). Linux only;
    /// elsewhere the same as None. A worker that cannot be pinned runs
    /// unpinned.
    PinWorkers,
  };

  /// How long a thread with no work left waits busily for the next job
  /// before it sleeps, unless the pool is made with another time: long
  /// enough to span the gap between two phases of a frame (the serial work
  /// between them, such as the body phase's checks), short enough to cost
  /// little when the pool then sleeps until the next frame.
  static constexpr std::chrono::microseconds kDefaultSpinBeforeSleep{50};

  /// Starts `threads - 1` workers, placed as `affinity` says, that spin for
  /// `spinBeforeSleep` after each job before they sleep. A spin longer than
  /// the gap between a frame's last job and the next frame's first keeps
  /// the workers awake from frame to frame, at the cost of that much CPU
  /// per worker and frame when the frames are further apart: for a loop
  /// that steps back to back (a server, a benchmark). That also keeps a
  /// worker where it runs: a sleeping worker is placed again when it wakes,
  /// and on the project's 2-core VM it was often woken onto the caller's
  /// CPU (1,024 walkers on 2 threads: 1.0 to 1.1 times one with 50 µs,
  /// 1.84 with 5 ms in the same runs; walkers --spin-us,
  /// docs/measurements.md, the twenty-ninth pass).
  /// Preconditions: threads >= 1, spinBeforeSleep >= 0.
  explicit ThreadPool(int threads, Affinity affinity = Affinity::None,
                      std::chrono::microseconds spinBeforeSleep = kDefaultSpinBeforeSleep);
  /// Stops and joins the workers. Precondition: no parallelFor running.
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  /// Pins the calling thread to the first CPU the process may run on (the
  /// one Affinity::PinWorkers leaves to the caller of parallelFor). Returns
  /// false, changing nothing, where that is not possible: off Linux, or
  /// when the system refuses. Call it after making the pool: threads made
  /// later, a pool's workers too, start on the pinned thread's one CPU.
  static bool pinThisThreadToFirstCpu();

  /// The threads that run a parallelFor, the caller included: >= 1.
  int threadCount() const { return int(workers_.size()) + 1; }

  /// How many times, since the pool was made, a worker found no job at the
  /// end of its spin and went to sleep (each worker's first wait counts
  /// too, unless a job came within its spin). For tuning spinBeforeSleep:
  /// a count that grows by the workers' number every frame says they sleep
  /// between frames. Thread safety: may be read while a job runs.
  unsigned long long sleeps() const { return sleeps_.load(std::memory_order_relaxed); }

  /// How parallelFor hands ranges out to the threads.
  enum class Handout {
    /// Thread t starts on the t-th of threadCount() equal consecutive shares
    /// of [0, count), in order, and when its share is done helps with the
    /// others' remaining ranges. With the same count a thread so runs mostly
    /// the same items call after call, and their data stays in its core's
    /// cache (stepping 1,024 bodies on 2 threads: 2.0 times as fast as on one,
    /// 1.7 with InOrder).
    ThreadShares,
    /// Every thread takes the next range in index order as it becomes free:
    /// for items sorted from the costliest down, so that the last ranges,
    /// which may leave a thread waiting, are the cheapest.
    InOrder,
  };

  /// Calls `task` on consecutive ranges of at most `chunk` items covering
  /// [0, count) exactly once, on all the pool's threads, and returns when
  /// every range is done; every range starts at a multiple of `chunk`.
  /// `handout` says which thread takes which range first; either way which
  /// thread runs which range varies from call to call: results must not
  /// depend on it. `task` must not throw (std::terminate otherwise) and
  /// must not call parallelFor on the same pool. Precondition: chunk >= 1.
  /// Thread safety: one parallelFor at a time per pool; call it from one
  /// thread (or serialise the callers).
  void parallelFor(std::size_t count, std::size_t chunk, const RangeTask& task,
                   Handout handout = Handout::ThreadShares);

 private:
  void workerLoop(int thread);
  void runRanges(int thread);

  std::vector<std::thread> workers_;
  std::mutex mutex_;
  std::condition_variable wake_, done_;
  // The current job: task_, chunk_ and shares_ are written under mutex_
  // before generation_ changes, which tells workers a new one started.
  // Workers and the caller spin a little on generation_ and joined_ before
  // sleeping on the condition variables (a frame's phases follow each other
  // within microseconds, and a sleeping thread takes tens of them to wake),
  // and take ranges with atomic counters. A worker joins a job before it
  // reads the job's fields; once the caller has run out of ranges it closes
  // the job, waits only for the workers that joined, and a worker that wakes
  // later finds it closed: the caller never waits for a late wake-up.
  const RangeTask* task_ = nullptr;
  std::size_t chunk_ = 1;
  // Each thread's share of the current job's items, [next, end): a thread
  // takes ranges from its own share first, then from the others' (InOrder:
  // every item in the first share). With ThreadShares a body's data stays in
  // one core's cache from frame to frame; handing every range out from one
  // counter instead moved it between the cores, and the same work took 8 to
  // 11% longer on 2 threads (measured on 1,024 walkers). Padded so that one
  // share's counter does not slow another's.
  struct alignas(64) Share {
    std::atomic<std::size_t> next{0};
    std::size_t end = 0;
  };
  std::unique_ptr<Share[]> shares_;
  std::atomic<unsigned long long> generation_{0};
  /// The workers inside the current job, plus kClosed once it is closed.
  std::atomic<unsigned> joined_{kClosed};
  static constexpr unsigned kClosed = 1u << 31;
  std::atomic<bool> stopping_{false};
  std::chrono::microseconds spinBeforeSleep_;
  std::atomic<unsigned long long> sleeps_{0};
};

}  // namespace bspf
