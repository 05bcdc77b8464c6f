#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>

#include "photo/grey_image.h"

namespace cwloc {

// A frame of a video file as grey pixels, converted from the decoder's colours to RGB and then
// to grey by COLMAP's rule, as a photo of the frame would be (image_decode.h).
struct VideoFrame {
  uint64_t index = 0;  // in decoding order, from 0
  double seconds = 0;  // its presentation time from the stream's start
  GreyImage image;
};

// The frames of the best video stream of a file FFmpeg reads (MP4, MOV, MKV, AVI, ...; H.264,
// H.265, VP9, MJPEG, ...). Throws InputError naming the file when it cannot be opened, has no
// video stream or no decoder for it, has frames over max_pixels or under kMinImageSide, or when
// its data is corrupt or cut short (then naming the frame); the frames before come out first.
class VideoFrames {
 public:
  VideoFrames(const std::filesystem::path& path, uint64_t max_pixels);
  ~VideoFrames();
  VideoFrames(const VideoFrames&) = delete;
  VideoFrames& operator=(const VideoFrames&) = delete;

  // The next frame whose index is a multiple of `step` (1: every frame); nothing at the end.
  std::optional<VideoFrame> Next(uint32_t step);

  uint32_t width() const;
  uint32_t height() const;
  // The stream's frame count as its header gives it; 0 when it does not.
  uint64_t estimated_frames() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace cwloc
