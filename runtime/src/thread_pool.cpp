// SPDX-License-Identifier: MIT
#include <bspf/thread_pool.h>

#include <algorithm>
#include <cassert>
#include <chrono>
#include <thread>

#if defined(__x86_64__) || defined(_M_X64) || defined(__i386__) || defined(_M_IX86)
#include <emmintrin.h>
#define BSPF_SPIN_PAUSE() _mm_pause()
#else
#define BSPF_SPIN_PAUSE() std::this_thread::yield()
#endif

namespace bspf {

ThreadPool::ThreadPool(int threads) : shares_(new Share[std::size_t(std::max(threads, 1))]) {
  assert(threads >= 1);
  workers_.reserve(std::size_t(threads > 1 ? threads - 1 : 0));
  for (int t = 1; t < threads; ++t) workers_.emplace_back([this, t] { workerLoop(t); });
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

// Spins until done() or for about kSpinMicroseconds, whichever is first;
// returns done(). Long enough to span the gap between two phases of a frame
// (the serial work between them, such as building the body grid), short
// enough to cost little when the pool then sleeps until the next frame.
template <typename Done>
bool spinUntil(Done done) {
  constexpr auto kSpinMicroseconds = std::chrono::microseconds(50);
  const auto until = std::chrono::steady_clock::now() + kSpinMicroseconds;
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
    spinUntil([&] {
      return stopping_.load(std::memory_order_relaxed) ||
             generation_.load(std::memory_order_relaxed) != seen;
    });
    {
      std::unique_lock lock(mutex_);
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
  if (joined_.fetch_or(kClosed, std::memory_order_acq_rel) != 0 && !spinUntil(left)) {
    std::unique_lock lock(mutex_);
    done_.wait(lock, left);
  }
  std::lock_guard lock(mutex_);
  task_ = nullptr;
}

}  // namespace bspf
