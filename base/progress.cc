#include "base/progress.h"

#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>

namespace cwloc {

namespace {
std::atomic<int> silences{0};
}  // namespace

bool Progress::Enabled() {
  return silences.load() == 0 && ::isatty(STDERR_FILENO) == 1 &&
         std::getenv("CWLOC_NO_PROGRESS") == nullptr;
}

Progress::Silence::Silence() { ++silences; }
Progress::Silence::~Silence() { --silences; }

Progress::Progress(std::string label, uint64_t total)
    : label_(std::move(label)), total_(total), enabled_(Enabled()) {}

Progress::~Progress() { Finish(); }

void Progress::Advance(uint64_t amount) {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  done_ += amount;
  if (since_draw_.Seconds() >= 0.1) {
    since_draw_.Restart();
    Draw(false);
  }
}

void Progress::Finish() {
  if (!enabled_) return;
  std::lock_guard lock(mutex_);
  if (finished_) return;
  finished_ = true;
  done_ = total_;
  Draw(true);
}

void Progress::Draw(bool final_draw) {
  constexpr int kWidth = 30;
  const double fraction = total_ == 0 ? 1.0 : std::min(1.0, double(done_) / double(total_));
  const int filled = static_cast<int>(fraction * kWidth);
  std::fprintf(stderr, "\r%-24s [%.*s%*s] %5.1f%% %7.1fs", label_.c_str(), filled,
               "##############################", kWidth - filled, "", 100.0 * fraction,
               elapsed_.Seconds());
  if (final_draw) std::fputc('\n', stderr);
  std::fflush(stderr);
}

}  // namespace cwloc
