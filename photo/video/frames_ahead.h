#pragma once

#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "photo/video/video_frames.h"

namespace cwloc {

// A video's frames decoded on a thread of their own, at most `depth` ahead of the caller:
// decoding the next frame (11 ms for a 1080 x 1920 frame of a phone's 30 fps stream) overlaps
// the work on this one. The same frames in the same order as VideoFrames::Next(step), and the
// same InputError, thrown after the frames before it came out.
class FramesDecodedAhead {
 public:
  FramesDecodedAhead(VideoFrames& video, uint32_t step, size_t depth = 2);
  ~FramesDecodedAhead();  // stops decoding and waits for the frame being decoded
  FramesDecodedAhead(const FramesDecodedAhead&) = delete;
  FramesDecodedAhead& operator=(const FramesDecodedAhead&) = delete;

  // The next frame; nothing at the end.
  std::optional<VideoFrame> Next();

 private:
  void Decode(VideoFrames& video, uint32_t step);

  const size_t depth_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<VideoFrame> frames_;
  bool ended_ = false;  // the decoder has put its last frame in frames_
  // Why it ended, after frames_: copied, not an exception_ptr, so that no exception object is
  // shared between the threads.
  enum class Failure { kNone, kInput, kMemory, kOther };
  Failure failure_ = Failure::kNone;
  std::string failure_message_;
  bool stop_ = false;
  std::thread decoder_;
};

}  // namespace cwloc
