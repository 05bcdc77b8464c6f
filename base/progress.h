#pragma once

#include <cstdint>
#include <mutex>
#include <string>

#include "base/stopwatch.h"

namespace cwloc {

// A one-line progress bar on stderr, drawn only when stderr is a terminal so that pipes and
// logs stay quiet. Thread-safe; redraws at most ten times a second.
class Progress {
 public:
  Progress(std::string label, uint64_t total);
  ~Progress();  // finishes the line
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void Advance(uint64_t amount = 1);
  void Finish();

  // stderr is a terminal, CWLOC_NO_PROGRESS is unset and no Silence is alive.
  static bool Enabled();

  // While one lives, bars made after it stay quiet (work repeated inside a longer task that
  // shows its own bar); bars made before it draw on.
  class Silence {
   public:
    Silence();
    ~Silence();
    Silence(const Silence&) = delete;
    Silence& operator=(const Silence&) = delete;
  };

 private:
  void Draw(bool final_draw);

  std::string label_;
  uint64_t total_;
  uint64_t done_ = 0;
  bool enabled_;
  bool finished_ = false;
  Stopwatch elapsed_;
  Stopwatch since_draw_;
  std::mutex mutex_;
};

}  // namespace cwloc
