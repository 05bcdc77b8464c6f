#pragma once

// The server's localization workers: a fixed pool of threads and a bounded queue in front of
// it. A request that finds the queue full is turned away at once (503), one that waits past
// its deadline is taken out of the queue at that moment (503), so memory and waiting stay
// bounded however many requests arrive.

#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <thread>
#include <vector>

namespace cwloc {

class WorkQueue {
 public:
  using Clock = std::chrono::steady_clock;

  enum class Outcome {
    kDone,       // the work ran
    kQueueFull,  // it was not queued
    kExpired,    // its deadline passed before a worker took it
    kStopped,    // the queue is stopping
  };

  WorkQueue(int threads, size_t capacity);
  ~WorkQueue();  // finishes the work queued, then joins the workers
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;

  // Runs `work` on a worker, then done(kDone) there; or done(kQueueFull) at once on this thread
  // when the queue is full, done(kStopped) when it is stopping, done(kExpired) on the queue's
  // timer thread when no worker started it by `deadline`. Once started, work runs to its end
  // (its own budget bounds it); work and done must catch their own exceptions.
  void Post(std::function<void()> work, Clock::time_point deadline,
            std::function<void(Outcome)> done);
  // The same, waiting for the outcome.
  Outcome Run(const std::function<void()>& work, Clock::time_point deadline);

  size_t queued() const;  // waiting for a worker
  size_t busy() const;    // running on a worker
  int threads() const { return static_cast<int>(workers_.size()); }
  size_t capacity() const { return capacity_; }

 private:
  struct Task;
  void Work();
  void Expire();  // the timer thread: takes out the tasks whose deadline passed

  const size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable work_ready_;
  std::condition_variable deadlines_changed_;
  std::deque<std::shared_ptr<Task>> queue_;
  size_t busy_ = 0;
  bool stopping_ = false;
  std::vector<std::thread> workers_;
  std::thread timer_;
};

}  // namespace cwloc
