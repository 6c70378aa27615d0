// SPDX-License-Identifier: MIT
#include <bspf/thread_pool.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <thread>

#ifdef __linux__
#include <pthread.h>
#include <sched.h>
#endif

#if defined(__x86_64__) || defined(_M_X64) || defined(__i386__) || defined(_M_IX86)
#include <emmintrin.h>
#define BSPF_SPIN_PAUSE() _mm_pause()
#else
#define BSPF_SPIN_PAUSE() std::this_thread::yield()
#endif

namespace bspf {

namespace {

#ifdef __linux__
// The k-th CPU (modulo their number) of those the process may run on, as a
// set of one; false when there are none to read.
bool nthAllowedCpu(int k, cpu_set_t& one) {
  cpu_set_t allowed;
  if (sched_getaffinity(0, sizeof(allowed), &allowed) != 0) return false;
  const int count = CPU_COUNT(&allowed);
  if (count == 0) return false;
  int wanted = k % count;
  for (int cpu = 0; cpu < CPU_SETSIZE; ++cpu) {
    if (!CPU_ISSET(cpu, &allowed) || wanted-- > 0) continue;
    CPU_ZERO(&one);
    CPU_SET(cpu, &one);
    return true;
  }
  return false;
}
#endif

}  // namespace

ThreadPool::ThreadPool(int threads, Affinity affinity, std::chrono::microseconds spinBeforeSleep)
    : shares_(new Share[std::size_t(std::max(threads, 1))]), spinBeforeSleep_(spinBeforeSleep) {
  assert(threads >= 1);
  assert(spinBeforeSleep.count() >= 0);
  workers_.reserve(std::size_t(threads > 1 ? threads - 1 : 0));
  for (int t = 1; t < threads; ++t) {
    workers_.emplace_back([this, t] { workerLoop(t); });
#ifdef __linux__
    // The constructing thread's CPUs, which pinning a worker leaves as
    // they are.
    cpu_set_t one;
    if (affinity == Affinity::PinWorkers && nthAllowedCpu(t, one))
      pthread_setaffinity_np(workers_.back().native_handle(), sizeof(one), &one);
#else
    (void)affinity;
#endif
  }
}

bool ThreadPool::pinThisThreadToFirstCpu() {
#ifdef __linux__
  cpu_set_t one;
  return nthAllowedCpu(0, one) && pthread_setaffinity_np(pthread_self(), sizeof(one), &one) == 0;
#else
  return false;
#endif
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

namespace {

// Spins until done() or for about `spin`, whichever is first; returns
// done().
template <typename Done>
bool spinUntil(std::chrono::microseconds spin, Done done) {
  const auto until = std::chrono::steady_clock::now() + spin;
  for (int k = 1;; ++k) {
    if (done()) return true;
    BSPF_SPIN_PAUSE();
    if (k % 64 == 0 && std::chrono::steady_clock::now() >= until) return done();
  }
}

}  // namespace

void ThreadPool::runRanges(int thread) {
  const RangeTask& task = *task_;
  const int shares = threadCount();
  for (int k = 0; k < shares; ++k) {
    Share& share = shares_[std::size_t((thread + k) % shares)];
    for (;;) {
      const std::size_t first = share.next.fetch_add(chunk_, std::memory_order_relaxed);
      if (first >= share.end) break;
      task(thread, first, std::min(share.end, first + chunk_));
    }
  }
}

void ThreadPool::workerLoop(int thread) {
  unsigned long long seen = 0;
  for (;;) {
    spinUntil(spinBeforeSleep_, [&] {
      return stopping_.load(std::memory_order_relaxed) ||
             generation_.load(std::memory_order_relaxed) != seen;
    });
    {
      std::unique_lock lock(mutex_);
      if (!stopping_ && generation_ == seen) sleeps_.fetch_add(1, std::memory_order_relaxed);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    // Joined only while the job is open: a closed one's caller may already
    // have returned, and its task be gone. (The job joined may be a later
    // one than `seen`: its fields were written before it opened, and the
    // acquire here sees them.)
    unsigned state = joined_.load(std::memory_order_relaxed);
    do {
      if (state & kClosed) break;
    } while (!joined_.compare_exchange_weak(state, state + 1, std::memory_order_acquire,
                                            std::memory_order_relaxed));
    if (state & kClosed) continue;
    runRanges(thread);
    if (joined_.fetch_sub(1, std::memory_order_acq_rel) == (kClosed | 1)) {
      std::lock_guard lock(mutex_);
      done_.notify_one();
    }
  }
}

void ThreadPool::parallelFor(std::size_t count, std::size_t chunk, const RangeTask& task,
                             Handout handout) {
  assert(chunk >= 1);
  if (count == 0) return;
  if (workers_.empty() || count <= chunk) {
    for (std::size_t first = 0; first < count; first += chunk)
      task(0, first, std::min(count, first + chunk));
    return;
  }
  {
    std::lock_guard lock(mutex_);
    task_ = &task;
    chunk_ = chunk;
    // Shares of whole chunks, so that every range but the last is a full one.
    const std::size_t shares = std::size_t(threadCount());
    const std::size_t chunks = count / chunk + (count % chunk != 0);
    for (std::size_t p = 0; p < shares; ++p) {
      if (handout == Handout::InOrder) {
        shares_[p].next.store(p == 0 ? 0 : count, std::memory_order_relaxed);
        shares_[p].end = count;
        continue;
      }
      shares_[p].next.store(std::min(count, chunks * p / shares * chunk),
                            std::memory_order_relaxed);
      shares_[p].end = std::min(count, chunks * (p + 1) / shares * chunk);
    }
    joined_.store(0, std::memory_order_release);  // open, after the fields
    ++generation_;
  }
  wake_.notify_all();
  runRanges(0);
  // Every range is taken: closed, no worker joins any more; those that did
  // leave before the task goes out of scope.
  const auto left = [&] { return joined_.load(std::memory_order_acquire) == kClosed; };
  if (joined_.fetch_or(kClosed, std::memory_order_acq_rel) != 0 &&
      !spinUntil(spinBeforeSleep_, left)) {
    std::unique_lock lock(mutex_);
    done_.wait(lock, left);
  }
  std::lock_guard lock(mutex_);
  task_ = nullptr;
}

}  // namespace bspf
