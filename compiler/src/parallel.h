// SPDX-License-Identifier: MIT
// The compiler's one way of sharing work between a pool's threads.
#pragma once

#include <bspf/thread_pool.h>

#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>

namespace bspc {

/// Runs `task(thread, first, last)` on ranges of at most `chunk` items
/// covering [0, count), on `pool`'s threads, or all at once on this thread
/// (as thread 0) without a pool. `thread` is below the pool's thread count,
/// for per-thread working memory. Ranges are handed out in index order
/// (ThreadPool::Handout::InOrder): the tree build lists its subtrees
/// largest first. Which thread runs which range varies, so
/// a result must not depend on it. An exception thrown by a task (out of
/// memory) is carried back and rethrown here, the first one if several,
/// instead of ending the process.
inline void runParallel(bspf::ThreadPool* pool, std::size_t count, std::size_t chunk,
                        const std::function<void(int, std::size_t, std::size_t)>& task) {
  if (!pool) {
    if (count) task(0, 0, count);
    return;
  }
  std::mutex mutex;
  std::exception_ptr failure;
  pool->parallelFor(
      count, chunk,
      [&](int thread, std::size_t first, std::size_t last) {
        try {
          task(thread, first, last);
        } catch (...) {
          std::lock_guard lock(mutex);
          if (!failure) failure = std::current_exception();
        }
      },
      bspf::ThreadPool::Handout::InOrder);
  if (failure) std::rethrow_exception(failure);
}

}  // namespace bspc
