#include "serve/work_queue.h"

#include <algorithm>
#include <future>
#include <optional>

namespace cwloc {

struct WorkQueue::Task {
  std::function<void()> work;
  std::function<void(Outcome)> done;
  Clock::time_point deadline;
};

WorkQueue::WorkQueue(int threads, size_t capacity) : capacity_(capacity) {
  for (int i = 0; i < threads; ++i) workers_.emplace_back([this] { Work(); });
  timer_ = std::thread([this] { Expire(); });
}

WorkQueue::~WorkQueue() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  work_ready_.notify_all();
  deadlines_changed_.notify_all();
  for (std::thread& worker : workers_) worker.join();
  timer_.join();
}

void WorkQueue::Post(std::function<void()> work, Clock::time_point deadline,
                     std::function<void(Outcome)> done) {
  auto task = std::make_shared<Task>(Task{std::move(work), std::move(done), deadline});
  std::optional<Outcome> refused;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (stopping_ || queue_.size() >= capacity_)
      refused = stopping_ ? Outcome::kStopped : Outcome::kQueueFull;
    else
      queue_.push_back(task);
  }
  if (refused) return task->done(*refused);
  work_ready_.notify_one();
  deadlines_changed_.notify_one();
}

WorkQueue::Outcome WorkQueue::Run(const std::function<void()>& work, Clock::time_point deadline) {
  std::promise<Outcome> outcome;
  Post(work, deadline, [&](Outcome done) { outcome.set_value(done); });
  return outcome.get_future().get();
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
    ++busy_;
    lock.unlock();
    task->work();
    lock.lock();
    --busy_;  // before done(): whoever it wakes finds the worker free
    lock.unlock();
    task->done(Outcome::kDone);
    lock.lock();
  }
}

void WorkQueue::Expire() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (!stopping_) {
    const auto earliest =
        std::min_element(queue_.begin(), queue_.end(),
                         [](const auto& a, const auto& b) { return a->deadline < b->deadline; });
    if (earliest == queue_.end()) {
      deadlines_changed_.wait(lock);
      continue;
    }
    if (Clock::now() < (*earliest)->deadline) {
      deadlines_changed_.wait_until(lock, (*earliest)->deadline);
      continue;
    }
    std::shared_ptr<Task> expired = std::move(*earliest);
    queue_.erase(earliest);
    lock.unlock();
    expired->done(Outcome::kExpired);
    lock.lock();
  }
}

}  // namespace cwloc
