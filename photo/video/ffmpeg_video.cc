// FFmpeg's side of VideoFrames, built as the module libcwloc_video_ffmpeg.so that
// video_frames.cc loads with the first video (video_frames.h says why).
#include "photo/video/video_frames.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/pixdesc.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <new>
#include <string>
#include <type_traits>

#include "base/error.h"
#include "photo/image_decode.h"

namespace cwloc {
namespace {

std::string AvError(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof(text));
  return text;
}

// The frame's layout when it is 8-bit Y'CbCr (planar or semi-planar, as phones and cameras
// record), else nullptr.
const AVPixFmtDescriptor* ByteYCbCr(const AVFrame& frame) {
  const AVPixFmtDescriptor* format = av_pix_fmt_desc_get(static_cast<AVPixelFormat>(frame.format));
  if (format == nullptr || format->nb_components < 3) return nullptr;
  const uint64_t not_ycbcr = AV_PIX_FMT_FLAG_RGB | AV_PIX_FMT_FLAG_PAL | AV_PIX_FMT_FLAG_BITSTREAM |
                             AV_PIX_FMT_FLAG_HWACCEL | AV_PIX_FMT_FLAG_FLOAT | AV_PIX_FMT_FLAG_BE;
  if ((format->flags & not_ycbcr) != 0) return nullptr;
  for (int c = 0; c < 3; ++c) {
    if (format->comp[c].depth != 8 || format->comp[c].shift != 0) return nullptr;
  }
  return format->comp[0].step == 1 ? format : nullptr;  // packed YUYV: through RGB
}

// Full range (JPEG's 0..255) or video's limited range (Y' 16..235, chroma 16..240), which is
// also what a frame that does not say is in.
bool IsFullRange(const AVFrame& frame) {
  switch (frame.format) {
    case AV_PIX_FMT_YUVJ420P:
    case AV_PIX_FMT_YUVJ422P:
    case AV_PIX_FMT_YUVJ444P:
    case AV_PIX_FMT_YUVJ440P:
    case AV_PIX_FMT_YUVJ411P:
      return true;
    default:
      return frame.color_range == AVCOL_RANGE_JPEG;
  }
}

// COLMAP's grey of the RGB that the frame's matrix decodes Y'CbCr to, as a linear form
// grey = Y' + cb Cb + cr Cr (all normalised to a unit range). The rule's weights are BT.709's
// luma weights, so for BT.709 frames cb = cr = 0. Frames that do not say are BT.601, as
// FFmpeg's converter takes them.
struct ChromaWeights {
  double cb = 0.0, cr = 0.0;
};
ChromaWeights GreyChromaWeights(AVColorSpace matrix) {
  double kr = 0.299, kb = 0.114;  // BT.601
  if (matrix == AVCOL_SPC_BT709) kr = 0.2126, kb = 0.0722;
  if (matrix == AVCOL_SPC_BT2020_NCL || matrix == AVCOL_SPC_BT2020_CL) kr = 0.2627, kb = 0.0593;
  if (matrix == AVCOL_SPC_SMPTE240M) kr = 0.212, kb = 0.087;
  if (matrix == AVCOL_SPC_FCC) kr = 0.30, kb = 0.11;
  const double kg = 1.0 - kr - kb;
  // R = Y' + 2 (1 - kr) Cr, B = Y' + 2 (1 - kb) Cb, G = Y' - 2 (kb (1 - kb) Cb + kr (1 - kr) Cr) /
  // kg.
  constexpr double wr = 0.2126, wg = 0.7152, wb = 0.0722;
  ChromaWeights w;
  w.cr = wr * 2.0 * (1.0 - kr) - wg * 2.0 * kr * (1.0 - kr) / kg;
  w.cb = wb * 2.0 * (1.0 - kb) - wg * 2.0 * kb * (1.0 - kb) / kg;
  if (std::abs(w.cr) < 1e-4 && std::abs(w.cb) < 1e-4) w = {};  // BT.709: the rule's own weights
  return w;
}

class FfmpegVideo : public VideoDecoder {
 public:
  FfmpegVideo(const std::filesystem::path& path, uint64_t max_pixels);
  ~FfmpegVideo() override {
    sws_freeContext(to_rgb);
    av_frame_free(&frame);
    av_packet_free(&packet);
    avcodec_free_context(&codec);
    avformat_close_input(&format);
  }
  std::optional<VideoFrame> Next(uint32_t step) override;
  uint32_t width() const override { return width_; }
  uint32_t height() const override { return height_; }
  uint64_t estimated_frames() const override {
    const int64_t frames = format->streams[stream]->nb_frames;
    return frames > 0 ? uint64_t(frames) : 0;
  }

 private:
  std::filesystem::path path;
  uint64_t max_pixels = 0;
  AVFormatContext* format = nullptr;
  AVCodecContext* codec = nullptr;
  AVPacket* packet = nullptr;
  AVFrame* frame = nullptr;
  SwsContext* to_rgb = nullptr;
  int stream = -1;
  uint32_t width_ = 0, height_ = 0;  // the stream's, which every frame must keep
  uint64_t next_index = 0;
  bool flushing = false;  // the file is read: the decoder gives what it still holds
  int broken = 0;         // the error that ended the reading, thrown after the flush
  bool done = false;
  std::vector<uint8_t> rgb;

  [[noreturn]] void Fail(const std::string& what) const {
    throw InputError(path.string() + ": " + what);
  }

  // The decoder's next frame, or false at the end of the stream. A read or decoding error
  // first lets the decoder give the frames it holds, then throws.
  bool Decode() {
    while (true) {
      const int received = avcodec_receive_frame(codec, frame);
      if (received == 0) return true;
      if (received != AVERROR_EOF && received != AVERROR(EAGAIN)) {
        if (!flushing)
          Flush(received);
        else
          Fail("frame " + std::to_string(next_index) + ": " + AvError(received));
        continue;
      }
      if (received == AVERROR_EOF || flushing) {
        if (broken != 0) Fail("frame " + std::to_string(next_index) + ": " + AvError(broken));
        return false;
      }
      const int read = av_read_frame(format, packet);
      if (read == AVERROR_EOF) {
        Flush(0);
        continue;
      }
      if (read < 0) {
        Flush(read);
        continue;
      }
      if (packet->stream_index == stream) {
        const int sent = avcodec_send_packet(codec, packet);
        if (sent < 0 && sent != AVERROR(EAGAIN)) Flush(sent);
      }
      av_packet_unref(packet);
    }
  }

  // No more packets: the decoder gives what it holds; `error` (if not 0) is thrown after.
  void Flush(int error) {
    flushing = true;
    broken = error;
    avcodec_send_packet(codec, nullptr);
  }

  // The frame's grey (video_frames.h): from Y'CbCr directly when it is 8-bit, else through RGB.
  GreyImage ToGrey() {
    if (const AVPixFmtDescriptor* layout = ByteYCbCr(*frame)) return YCbCrToGrey(*layout);
    to_rgb = sws_getCachedContext(
        to_rgb, frame->width, frame->height, static_cast<AVPixelFormat>(frame->format),
        frame->width, frame->height, AV_PIX_FMT_RGB24, SWS_BILINEAR, nullptr, nullptr, nullptr);
    if (to_rgb == nullptr) Fail("frame " + std::to_string(next_index) + ": unsupported pixels");
    // The frame's own matrix and range (FFmpeg's converter assumes BT.601, limited, otherwise).
    sws_setColorspaceDetails(to_rgb, sws_getCoefficients(frame->colorspace), IsFullRange(*frame),
                             sws_getCoefficients(SWS_CS_DEFAULT), 1, 0, 1 << 16, 1 << 16);
    rgb.resize(size_t{width_} * height_ * 3);
    uint8_t* planes[4] = {rgb.data(), nullptr, nullptr, nullptr};
    int strides[4] = {static_cast<int>(width_ * 3), 0, 0, 0};
    sws_scale(to_rgb, frame->data, frame->linesize, 0, frame->height, planes, strides);
    GreyImage grey;
    grey.width = width_;
    grey.height = height_;
    grey.pixels.resize(size_t{width_} * height_);
    for (size_t i = 0; i < grey.pixels.size(); ++i)
      grey.pixels[i] = Luma709(rgb[3 * i], rgb[3 * i + 1], rgb[3 * i + 2]);
    return grey;
  }

  // grey = Y' + cb Cb + cr Cr in 0..255, rounded and clamped as the rule's (uint8) cast of RGB
  // in 0..255 is; chroma from the sample whose block holds the pixel.
  GreyImage YCbCrToGrey(const AVPixFmtDescriptor& layout) const {
    const bool full_range = IsFullRange(*frame);
    const double luma_scale = full_range ? 1.0 : 255.0 / 219.0;
    const double luma_zero = full_range ? 0.0 : 16.0;
    const double chroma_scale = full_range ? 1.0 : 255.0 / 224.0;
    const ChromaWeights w = GreyChromaWeights(frame->colorspace);
    // Y' in 0..255 (x 256) from a table; the chroma terms from two more.
    int32_t luma[256], from_cb[256], from_cr[256];
    for (int v = 0; v < 256; ++v) {
      luma[v] = int32_t(std::lround(256.0 * (v - luma_zero) * luma_scale));
      from_cb[v] = int32_t(std::lround(256.0 * w.cb * (v - 128) * chroma_scale));
      from_cr[v] = int32_t(std::lround(256.0 * w.cr * (v - 128) * chroma_scale));
    }
    const bool chroma = w.cb != 0.0 || w.cr != 0.0;
    const AVComponentDescriptor &cb = layout.comp[1], &cr = layout.comp[2];
    GreyImage grey;
    grey.width = width_;
    grey.height = height_;
    grey.pixels.resize(size_t{width_} * height_);
    for (uint32_t row = 0; row < height_; ++row) {
      const uint8_t* y_row = frame->data[0] + ptrdiff_t{row} * frame->linesize[0];
      const uint32_t chroma_row = row >> layout.log2_chroma_h;
      const uint8_t* cb_row =
          frame->data[cb.plane] + ptrdiff_t{chroma_row} * frame->linesize[cb.plane];
      const uint8_t* cr_row =
          frame->data[cr.plane] + ptrdiff_t{chroma_row} * frame->linesize[cr.plane];
      uint8_t* out = grey.pixels.data() + size_t{row} * width_;
      uint32_t column = 0;
      if (chroma && layout.log2_chroma_w == 1 && cb.step == 1 && cr.step == 1) {
        // Planar chroma, one sample per two columns (4:2:0, 4:2:2: most video): the pair's
        // chroma term once; the same integer sums as below.
        const uint8_t* cb_samples = cb_row + cb.offset;
        const uint8_t* cr_samples = cr_row + cr.offset;
        for (; column + 1 < width_; column += 2) {
          const int32_t from_chroma =
              128 + from_cb[cb_samples[column >> 1]] + from_cr[cr_samples[column >> 1]];
          out[column] = uint8_t(std::clamp((luma[y_row[column]] + from_chroma) >> 8, 0, 255));
          out[column + 1] =
              uint8_t(std::clamp((luma[y_row[column + 1]] + from_chroma) >> 8, 0, 255));
        }
      }
      for (; column < width_; ++column) {
        int32_t value = luma[y_row[column]] + 128;  // + 0.5, x 256
        if (chroma) {
          const uint32_t c = column >> layout.log2_chroma_w;
          value +=
              from_cb[cb_row[c * cb.step + cb.offset]] + from_cr[cr_row[c * cr.step + cr.offset]];
        }
        out[column] = uint8_t(std::clamp(value >> 8, 0, 255));
      }
    }
    return grey;
  }
};

FfmpegVideo::FfmpegVideo(const std::filesystem::path& path_in, uint64_t max_pixels_in)
    : path(path_in), max_pixels(max_pixels_in) {
  av_log_set_level(AV_LOG_QUIET);  // errors come back as InputError, not on stderr
  if (!std::filesystem::exists(path)) Fail("no such file");
  if (!std::filesystem::is_regular_file(path)) Fail("not a regular file");
  int status = avformat_open_input(&format, path.c_str(), nullptr, nullptr);
  if (status < 0) Fail("not a video FFmpeg can read (" + AvError(status) + ")");
  status = avformat_find_stream_info(format, nullptr);
  if (status < 0) Fail("no stream information (" + AvError(status) + ")");
  const AVCodec* decoder = nullptr;
  stream = av_find_best_stream(format, AVMEDIA_TYPE_VIDEO, -1, -1, &decoder, 0);
  if (stream == AVERROR_STREAM_NOT_FOUND) Fail("no video stream");
  if (stream < 0 || decoder == nullptr) Fail("no decoder for its video stream");
  const AVCodecParameters* parameters = format->streams[stream]->codecpar;
  if (parameters->width < int(kMinImageSide) || parameters->height < int(kMinImageSide)) {
    Fail(std::to_string(parameters->width) + " x " + std::to_string(parameters->height) +
         " frames, smaller than " + std::to_string(kMinImageSide) + " pixels a side");
  }
  if (uint64_t(parameters->width) * uint64_t(parameters->height) > max_pixels) {
    Fail(std::to_string(parameters->width) + " x " + std::to_string(parameters->height) +
         " frames, more than --max-image-pixels " + std::to_string(max_pixels));
  }
  width_ = static_cast<uint32_t>(parameters->width);
  height_ = static_cast<uint32_t>(parameters->height);
  codec = avcodec_alloc_context3(decoder);
  packet = av_packet_alloc();
  frame = av_frame_alloc();
  if (codec == nullptr || packet == nullptr || frame == nullptr) throw std::bad_alloc();
  avcodec_parameters_to_context(codec, parameters);
  codec->thread_count = 1;  // the frames' features use the threads
  status = avcodec_open2(codec, decoder, nullptr);
  if (status < 0) Fail("cannot open its decoder (" + AvError(status) + ")");
}

std::optional<VideoFrame> FfmpegVideo::Next(uint32_t step) {
  if (done) return std::nullopt;
  while (Decode()) {
    const uint64_t index = next_index++;
    if (step > 1 && index % step != 0) continue;
    if (uint32_t(frame->width) != width_ || uint32_t(frame->height) != height_) {
      Fail("frame " + std::to_string(index) + ": its size changed to " +
           std::to_string(frame->width) + " x " + std::to_string(frame->height));
    }
    VideoFrame out;
    out.index = index;
    const AVRational base = format->streams[stream]->time_base;
    const int64_t start = format->streams[stream]->start_time;
    const int64_t pts = frame->best_effort_timestamp;
    out.seconds = pts == AV_NOPTS_VALUE
                      ? 0.0
                      : double(pts - (start == AV_NOPTS_VALUE ? 0 : start)) * av_q2d(base);
    out.image = ToGrey();
    return out;
  }
  done = true;
  return std::nullopt;
}

}  // namespace
}  // namespace cwloc

// The module's entry point (kOpenVideoSymbol); its errors are thrown to the program that loaded
// it, which compares InputError by name as any C++ exception across shared objects.
extern "C" __attribute__((visibility("default"))) cwloc::VideoDecoder* cwloc_open_video(
    const char* path, uint64_t max_pixels) {
  static_assert(std::is_same_v<decltype(&cwloc_open_video), cwloc::OpenVideoFunction>);
  return new cwloc::FfmpegVideo(path, max_pixels);
}
