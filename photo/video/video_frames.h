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

// What decodes a video's frames: FFmpeg's, in the module libcwloc_video_ffmpeg.so
// (ffmpeg_video.cc). Debian's FFmpeg links some 120 libraries, whose loading took 22 MB of every
// cwloc-localize run's resident memory, a photo's too; the module is loaded with the first
// video instead (docs/benchmarks.md, "Extraction speed").
class VideoDecoder {
 public:
  virtual ~VideoDecoder() = default;
  virtual std::optional<VideoFrame> Next(uint32_t step) = 0;
  virtual uint32_t width() const = 0;
  virtual uint32_t height() const = 0;
  virtual uint64_t estimated_frames() const = 0;
};

// The module's one entry point, by this name: a decoder of `path`, or InputError (VideoFrames).
inline constexpr char kOpenVideoSymbol[] = "cwloc_open_video";
using OpenVideoFunction = VideoDecoder* (*)(const char* path, uint64_t max_pixels);

// The frames of the best video stream of a file FFmpeg reads (MP4, MOV, MKV, AVI, ...; H.264,
// H.265, VP9, MJPEG, ...). Throws InputError naming the file when it cannot be opened, has no
// video stream or no decoder for it, has frames over max_pixels or under kMinImageSide, or when
// its data is corrupt or cut short (then naming the frame); the frames before come out first.
// std::runtime_error when the FFmpeg module cannot be loaded.
class VideoFrames {
 public:
  VideoFrames(const std::filesystem::path& path, uint64_t max_pixels);
  ~VideoFrames();
  VideoFrames(const VideoFrames&) = delete;
  VideoFrames& operator=(const VideoFrames&) = delete;

  // The next frame whose index is a multiple of `step` (1: every frame); nothing at the end.
  std::optional<VideoFrame> Next(uint32_t step) { return decoder_->Next(step); }

  uint32_t width() const { return decoder_->width(); }
  uint32_t height() const { return decoder_->height(); }
  // The stream's frame count as its header gives it; 0 when it does not.
  uint64_t estimated_frames() const { return decoder_->estimated_frames(); }

 private:
  std::unique_ptr<VideoDecoder> decoder_;
};

}  // namespace cwloc
