#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>

#include "photo/grey_image.h"

namespace cwloc {

// A frame of a video file as grey pixels: COLMAP's grey rule (image_decode.h) applied to the
// RGB that the frame's matrix (BT.709, BT.601, BT.2020, ...; BT.601 when the stream does not
// say) and range decode it to, as a photo of the frame would be. For 8-bit Y'CbCr frames (what
// phones and cameras record) it is computed from Y'CbCr directly, grey = Y' + a Cb + b Cr, with
// chroma from the sample that covers the pixel: the rule's weights are BT.709's, so a = b = 0
// for BT.709 video and the conversion to RGB is skipped. Other frames (RGB, 10-bit) go through
// FFmpeg's converter to RGB.
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
