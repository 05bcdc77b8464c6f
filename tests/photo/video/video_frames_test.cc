// A video frame's grey (video_frames.h) is COLMAP's grey of the frame's RGB: videos that ffmpeg
// encodes losslessly from RGB test pictures, in each matrix, range and layout a phone or camera
// records, decode to the grey that image_decode.h gives the pictures themselves.
#include "photo/video/video_frames.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "photo/image_decode.h"
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

}  // namespace
}  // namespace cwloc
