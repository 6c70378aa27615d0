// SPDX-License-Identifier: MIT
#include <bspf/thread_pool.h>

#include <algorithm>
#include <cassert>

namespace bspf {

ThreadPool::ThreadPool(int threads) {
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

void ThreadPool::runRanges(int thread) {
  std::unique_lock lock(mutex_);
  const RangeTask& task = *task_;
  while (nextRange_ < count_) {
    const std::size_t first = nextRange_;
    const std::size_t last = std::min(count_, first + chunk_);
    nextRange_ = last;
    lock.unlock();
    task(thread, first, last);
    lock.lock();
  }
}

void ThreadPool::workerLoop(int thread) {
  unsigned long long seen = 0;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      wake_.wait(lock, [&] { return stopping_ || generation_ != seen; });
      if (stopping_) return;
      seen = generation_;
    }
    runRanges(thread);
    std::lock_guard lock(mutex_);
    if (--busy_ == 0) done_.notify_one();
  }
}

void ThreadPool::parallelFor(std::size_t count, std::size_t chunk, const RangeTask& task) {
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
    count_ = count;
    chunk_ = chunk;
    nextRange_ = 0;
    busy_ = int(workers_.size());
    ++generation_;
  }
  wake_.notify_all();
  runRanges(0);
  // Every worker leaves the job before the task goes out of scope, even one
  // that woke too late to find a range left.
  std::unique_lock lock(mutex_);
  done_.wait(lock, [&] { return busy_ == 0; });
  task_ = nullptr;
}

}  // namespace bspf
