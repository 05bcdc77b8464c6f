#pragma once

#include <algorithm>
#include <atomic>
#include <cstddef>
#include <exception>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

namespace cwloc {

// Number of threads to use when the user asked for `requested` (0 or less = all cores).
inline int ResolveThreads(int requested) {
  if (requested > 0) return requested;
  return static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
}

// Runs body(i) or body(i, worker) for i in [0, n) on up to `threads` threads (0 = all cores);
// worker in [0, threads) identifies the thread, for per-thread scratch. Items are handed out
// one at a time because they vary a lot in size, so results must depend on i only, never on
// which thread ran it. The first exception is rethrown once all threads have stopped.
template <typename Body>
void ParallelFor(size_t n, int threads, Body&& body) {
  const int workers =
      static_cast<int>(std::min<size_t>(size_t(ResolveThreads(threads)), std::max<size_t>(n, 1)));
  std::atomic<size_t> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto work = [&](int worker) {
    for (size_t i; (i = next.fetch_add(1)) < n;) {
      try {
        if constexpr (std::is_invocable_v<Body&, size_t, int>) {
          body(i, worker);
        } else {
          body(i);
        }
      } catch (...) {
        std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        next = n;
      }
    }
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < workers; ++t) pool.emplace_back(work, t);
  work(0);
  for (auto& thread : pool) thread.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace cwloc
