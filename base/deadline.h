#pragma once

#include <chrono>

namespace cwloc {

// When a stage of a query should stop (cwloc-localize --budget-ms); the default never comes.
// Checking it reads the steady clock (tens of nanoseconds), so stages check per work item.
class Deadline {
 public:
  using Clock = std::chrono::steady_clock;

  Deadline() = default;
  explicit Deadline(Clock::time_point at) : at_(at) {}
  static Deadline After(Clock::time_point start, double seconds) {
    return Deadline(start + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(seconds)));
  }

  bool Never() const { return at_ == Clock::time_point::max(); }
  bool Passed() const { return !Never() && Clock::now() >= at_; }

 private:
  Clock::time_point at_ = Clock::time_point::max();
};

}  // namespace cwloc
