#include "photo/video/frames_ahead.h"

#include <algorithm>
#include <new>
#include <stdexcept>
#include <utility>

#include "base/error.h"

namespace cwloc {

FramesDecodedAhead::FramesDecodedAhead(VideoFrames& video, uint32_t step, size_t depth)
    : depth_(std::max<size_t>(depth, 1)), decoder_([this, &video, step] { Decode(video, step); }) {}

FramesDecodedAhead::~FramesDecodedAhead() {
  {
    const std::lock_guard lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  decoder_.join();
}

void FramesDecodedAhead::Decode(VideoFrames& video, uint32_t step) {
  Failure failure = Failure::kNone;
  std::string message;
  for (;;) {
    {
      std::unique_lock lock(mutex_);
      changed_.wait(lock, [this] { return stop_ || frames_.size() < depth_; });
      if (stop_) return;
    }
    std::optional<VideoFrame> frame;
    try {
      frame = video.Next(step);
    } catch (const InputError& e) {
      failure = Failure::kInput;
      message = e.what();
    } catch (const std::bad_alloc&) {
      failure = Failure::kMemory;
    } catch (const std::exception& e) {
      failure = Failure::kOther;
      message = e.what();
    }
    {
      const std::lock_guard lock(mutex_);
      if (frame) {
        frames_.push_back(std::move(*frame));
      } else {
        ended_ = true;
        failure_ = failure;
        failure_message_ = std::move(message);
      }
    }
    changed_.notify_all();
    if (!frame) return;
  }
}

std::optional<VideoFrame> FramesDecodedAhead::Next() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [this] { return !frames_.empty() || ended_; });
  if (frames_.empty()) {
    switch (std::exchange(failure_, Failure::kNone)) {
      case Failure::kNone:
        return std::nullopt;
      case Failure::kInput:
        throw InputError(failure_message_);
      case Failure::kMemory:
        throw std::bad_alloc();
      case Failure::kOther:
        throw std::runtime_error(failure_message_);
    }
  }
  VideoFrame frame = std::move(frames_.front());
  frames_.pop_front();
  lock.unlock();
  changed_.notify_all();
  return frame;
}

}  // namespace cwloc
