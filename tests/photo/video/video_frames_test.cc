// A video frame's grey (video_frames.h) is COLMAP's grey of the frame's RGB: videos that ffmpeg
// encodes losslessly from RGB test pictures, in each matrix, range and layout a phone or camera
// records, decode to the grey that image_decode.h gives the pictures themselves.
#include "photo/video/video_frames.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "base/error.h"
#include "photo/image_decode.h"
#include "photo/video/frames_ahead.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

class VideoFramesTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    std::string output;
    if (test::RunCommand("ffmpeg -version", &output) != 0) return;
    dir_ = new test::TempDir();
    // Colour bars, gradients and moving shapes: saturated colours, where the matrices differ.
    ASSERT_EQ(test::RunCommand("ffmpeg -loglevel error -y -f lavfi -i testsrc2=size=320x240:rate=2"
                               " -frames:v 3 " +
                                   (dir_->path() / "frame_%d.png").string(),
                               &output),
              0)
        << output;
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  void SetUp() override {
    if (dir_ == nullptr) GTEST_SKIP() << "ffmpeg not found";
  }

  // The pictures encoded by ffmpeg with `options` into `name`.
  static std::filesystem::path Encode(const std::string& name, const std::string& options) {
    const std::filesystem::path video = dir_->path() / name;
    std::string output;
    EXPECT_EQ(test::RunCommand("ffmpeg -loglevel error -y -framerate 2 -i " +
                                   (dir_->path() / "frame_%d.png").string() + " " + options + " " +
                                   video.string(),
                               &output),
              0)
        << output;
    return video;
  }

  // The largest difference between each frame's grey and its picture's, over all frames.
  static int LargestDifference(const std::filesystem::path& video) {
    VideoFrames frames(video, kDefaultMaxImagePixels);
    int largest = 0, count = 0;
    while (const std::optional<VideoFrame> frame = frames.Next(1)) {
      const std::filesystem::path picture =
          dir_->path() / ("frame_" + std::to_string(frame->index + 1) + ".png");
      const GreyImage expected = DecodeGreyImage(ReadPhotoFile(picture), picture);
      EXPECT_EQ(frame->image.width, expected.width);
      EXPECT_EQ(frame->image.height, expected.height);
      if (frame->image.pixels.size() != expected.pixels.size()) return 256;
      for (size_t i = 0; i < expected.pixels.size(); ++i)
        largest = std::max(largest, std::abs(int(frame->image.pixels[i]) - expected.pixels[i]));
      ++count;
    }
    EXPECT_EQ(count, 3);
    return largest;
  }

  static inline test::TempDir* dir_ = nullptr;
};

// x264 without loss: Y'CbCr is the pictures' RGB in the given matrix and range, rounded to
// 8 bits, so the grey is the pictures' within the rounding (limited range has 219 luma levels).
constexpr char kLossless444[] = "-c:v libx264 -qp 0 -pix_fmt yuv444p";

TEST_F(VideoFramesTest, Bt709VideoGivesThePicturesGrey) {
  EXPECT_LE(LargestDifference(Encode("bt709.mkv", std::string(kLossless444) +
                                                      " -vf scale=out_color_matrix=bt709"
                                                      " -colorspace bt709")),
            1);
}

// BT.601's luma weights are not the rule's: grey takes a part of the chroma (in testsrc2's
// saturated colours 33 levels without it).
TEST_F(VideoFramesTest, Bt601VideoGivesThePicturesGreyThroughItsChroma) {
  EXPECT_LE(LargestDifference(Encode("bt601.mkv", std::string(kLossless444) +
                                                      " -vf scale=out_color_matrix=bt601"
                                                      " -colorspace smpte170m")),
            1);
}

// A stream that names no matrix is BT.601, as FFmpeg's own converters take it.
TEST_F(VideoFramesTest, VideoThatNamesNoMatrixIsBt601) {
  EXPECT_LE(LargestDifference(Encode(
                "unnamed.mkv", std::string(kLossless444) + " -vf scale=out_color_matrix=bt601")),
            1);
}

TEST_F(VideoFramesTest, FullRangeVideoGivesThePicturesGrey) {
  EXPECT_LE(LargestDifference(
                Encode("full_range.mkv", std::string(kLossless444) +
                                             " -vf scale=out_color_matrix=bt709:out_range=full"
                                             " -colorspace bt709 -color_range pc")),
            1);
}

// Half-resolution chroma (what phones record): BT.709's grey needs no chroma, so it stays exact.
TEST_F(VideoFramesTest, SubsampledChromaDoesNotMatterForBt709) {
  EXPECT_LE(LargestDifference(Encode("bt709_420.mp4",
                                     "-c:v libx264 -qp 0 -pix_fmt yuv420p"
                                     " -vf scale=out_color_matrix=bt709"
                                     " -colorspace bt709")),
            1);
}

// RGB frames go through FFmpeg's converter: the rule on the pictures' own pixels.
TEST_F(VideoFramesTest, RgbVideoGivesThePicturesGreyExactly) {
  EXPECT_EQ(LargestDifference(Encode("rgb.mkv", "-c:v png -pix_fmt rgb24")), 0);
}

// A video's frames as a reader gives them out (index, time and grey), and the error it ends with.
struct FramesRead {
  std::vector<VideoFrame> frames;
  std::string error;
};
FramesRead ReadAll(const std::function<std::optional<VideoFrame>()>& next) {
  FramesRead read;
  try {
    while (std::optional<VideoFrame> frame = next()) read.frames.push_back(std::move(*frame));
  } catch (const InputError& e) {
    read.error = e.what();
  }
  return read;
}
void ExpectSameFrames(const FramesRead& ahead, const FramesRead& here) {
  ASSERT_EQ(ahead.frames.size(), here.frames.size());
  for (size_t i = 0; i < here.frames.size(); ++i) {
    EXPECT_EQ(ahead.frames[i].index, here.frames[i].index);
    EXPECT_EQ(ahead.frames[i].seconds, here.frames[i].seconds);
    EXPECT_EQ(ahead.frames[i].image.pixels, here.frames[i].image.pixels);
  }
  EXPECT_EQ(ahead.error, here.error);
}

// Decoded on a thread of their own: the same frames, every one or every second, and a video
// cut short gives the frames before the cut, then the same error.
TEST_F(VideoFramesTest, FramesDecodedAheadAreTheSameFramesAndError) {
  const std::filesystem::path video = Encode("ahead.mp4", "-c:v libx264 -pix_fmt yuv420p");
  for (const uint32_t step : {1u, 2u}) {
    SCOPED_TRACE(step);
    VideoFrames direct(video, kDefaultMaxImagePixels);
    const FramesRead here = ReadAll([&] { return direct.Next(step); });
    EXPECT_EQ(here.frames.size(), step == 1 ? 3u : 2u);
    VideoFrames decoded(video, kDefaultMaxImagePixels);
    FramesDecodedAhead ahead(decoded, step, 1);
    ExpectSameFrames(ReadAll([&] { return ahead.Next(); }), here);
    EXPECT_EQ(ahead.Next(), std::nullopt);  // and stays at the end
  }

  // Cut in its last frame's data: the moov atom first, so that the cut is in the frames.
  const std::filesystem::path whole =
      Encode("whole.mp4", "-c:v libx264 -pix_fmt yuv420p -movflags +faststart");
  const std::vector<uint8_t> bytes = test::ReadBytes(whole);
  const std::filesystem::path cut = dir_->path() / "cut.mp4";
  test::WriteBytes(cut, std::span(bytes).first(bytes.size() * 9 / 10));
  VideoFrames direct(cut, kDefaultMaxImagePixels);
  const FramesRead here = ReadAll([&] { return direct.Next(1); });
  ASSERT_FALSE(here.error.empty());
  ASSERT_GE(here.frames.size(), 1u);
  VideoFrames decoded(cut, kDefaultMaxImagePixels);
  FramesDecodedAhead ahead(decoded, 1);
  ExpectSameFrames(ReadAll([&] { return ahead.Next(); }), here);
}

// Dropped before the end: the decoder stops without the frames being read.
TEST_F(VideoFramesTest, FramesDecodedAheadStopWhenDropped) {
  const std::filesystem::path video = Encode("dropped.mp4", "-c:v libx264 -pix_fmt yuv420p");
  VideoFrames decoded(video, kDefaultMaxImagePixels);
  {
    FramesDecodedAhead ahead(decoded, 1, 1);
    const std::optional<VideoFrame> first = ahead.Next();
    ASSERT_TRUE(first);
    EXPECT_EQ(first->index, 0u);
  }
  // The frames the decoder had not taken are still the file's.
  const std::optional<VideoFrame> next = decoded.Next(1);
  ASSERT_TRUE(next);
  EXPECT_GE(next->index, 1u);
}

}  // namespace
}  // namespace cwloc
