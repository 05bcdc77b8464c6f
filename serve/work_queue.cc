#include "serve/work_queue.h"

#include <algorithm>

namespace cwloc {

struct WorkQueue::Task {
  const std::function<void()>* work = nullptr;
  enum class State { kWaiting, kRunning, kDone } state = State::kWaiting;
  std::condition_variable done;
};

WorkQueue::WorkQueue(int threads, size_t capacity) : capacity_(capacity) {
  for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { Work(); });
}

WorkQueue::~WorkQueue() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  for (std::thread& worker : workers_) worker.join();
}

WorkQueue::Outcome WorkQueue::Run(const std::function<void()>& work, Clock::time_point deadline) {
  auto task = std::make_shared<Task>();
  task->work = &work;
  std::unique_lock<std::mutex> lock(mutex_);
  if (stopping_) return Outcome::kStopped;
  if (queue_.size() >= capacity_) return Outcome::kQueueFull;
  queue_.push_back(task);
  work_ready_.notify_one();
  if (!task->done.wait_until(lock, deadline,
                             [&] { return task->state != Task::State::kWaiting; })) {
    queue_.erase(std::find(queue_.begin(), queue_.end(), task));
    return Outcome::kExpired;
  }
  task->done.wait(lock, [&] { return task->state == Task::State::kDone; });
  return Outcome::kDone;
}

size_t WorkQueue::queued() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return queue_.size();
}

size_t WorkQueue::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return busy_;
}

void WorkQueue::Work() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (true) {
    work_ready_.wait(lock, [&] { return stopping_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stopping, nothing left
    std::shared_ptr<Task> task = std::move(queue_.front());
    queue_.pop_front();
    task->state = Task::State::kRunning;
    ++busy_;
    task->done.notify_one();
    lock.unlock();
    (*task->work)();
    lock.lock();
    --busy_;
    task->state = Task::State::kDone;
    task->done.notify_one();
  }
}

}  // namespace cwloc
