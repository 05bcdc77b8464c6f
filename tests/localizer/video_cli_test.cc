// cwloc-localize --video end to end (docs/cli.md): a real phone video's frames, encoded with
// ffmpeg into H.264 as a phone would, tracked against the map of the video's other frames
// (../shared/data/fox_video); and the broken videos a user hands it.
#include <gtest/gtest.h>

#include <fstream>
#include <map>
#include <sstream>

#include "tests/localization_check.h"
#include "tests/shared_data_index.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

class VideoCliTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto shared = test::BuildSharedDataIndex("fox_video");
    std::string version;
    if (!shared || test::RunCommand("ffmpeg -version", &version) != 0) return;
    data_ = new std::filesystem::path(shared->data);
    index_ = new std::filesystem::path(shared->index);
    dir_ = new test::TempDir();
    // The first 6 query frames (3 under a sanitizer) at half size, 2 frames per second.
    std::ifstream list(*data_ / "query_list.txt");
    frames_ = new std::vector<std::string>();
    for (std::string name; list >> name && frames_->size() < (test::kSanitized ? 3u : 6u);)
      frames_->push_back(name);
    for (size_t i = 0; i < frames_->size(); ++i) {
      char numbered[32];
      std::snprintf(numbered, sizeof(numbered), "%03zu.jpg", i);
      std::filesystem::create_symlink(*data_ / "query_images" / (*frames_)[i],
                                      dir_->path() / numbered);
    }
    std::string output;
    ASSERT_EQ(test::RunCommand("ffmpeg -loglevel error -y -framerate 2 -i " +
                                   (dir_->path() / "%03d.jpg").string() +
                                   " -vf scale=540:960 -c:v libx264 -pix_fmt yuv420p "
                                   "-movflags +faststart " +
                                   Video().string(),
                               &output),
              0)
        << output;
  }
  static void TearDownTestSuite() {
    delete dir_;
    delete data_;
    delete index_;
    delete frames_;
    dir_ = nullptr;
    data_ = index_ = nullptr;
    frames_ = nullptr;
  }
  void SetUp() override {
    if (data_ == nullptr) GTEST_SKIP() << "shared data 'fox_video' or ffmpeg not found";
  }

  static std::filesystem::path Video() { return dir_->path() / "fox.mp4"; }
  static std::string Localize(const std::string& arguments, int* status) {
    std::string output;
    *status = test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " +
                                   index_->string() + " " + arguments,
                               &output);
    return output;
  }
  // The frame's centre error against COLMAP's pose of the photo it was made from.
  double Error(const nlohmann::json& record, size_t frame) const {
    const auto truth = test::ReadGroundTruth(*data_ / "queries_gt.txt").at((*frames_)[frame]);
    return (test::PoseOfResult(record).Center() - truth.pose.Center()).norm();
  }

  static inline std::filesystem::path* data_ = nullptr;
  static inline std::filesystem::path* index_ = nullptr;
  static inline test::TempDir* dir_ = nullptr;
  static inline std::vector<std::string>* frames_ = nullptr;
};

// With the camera (COLMAP's, at half size) and the frame settings (docs/benchmarks.md,
// "Sequences"): every frame named VIDEO#INDEX, tracked after the first, near COLMAP's pose; the
// trajectory's timestamps are the frames' times.
TEST_F(VideoCliTest, AVideosFramesAreTrackedWithTheirTimes) {
  const auto out = dir_->path() / "video.jsonl", trajectory = dir_->path() / "video.txt";
  int status = 0;
  const std::string output =
      Localize("--video " + Video().string() +
                   " --camera 'SIMPLE_RADIAL 540 960 692.745 270 480 0.0030128' "
                   "--first-octave 0 --max-features 2000 -o " +
                   out.string() + " --trajectory " + trajectory.string(),
               &status);
  if (output.find("built without FFmpeg") != std::string::npos) GTEST_SKIP() << output;
  ASSERT_EQ(status, 0) << output;
  const std::vector<nlohmann::json> records = test::ReadJsonLines(out);
  ASSERT_EQ(records.size(), frames_->size());
  int tracked = 0;
  for (size_t i = 0; i < records.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(records[i]["name"], Video().string() + "#" + std::to_string(i));
    ASSERT_TRUE(records[i]["success"].get<bool>());
    tracked += records[i]["tracking"]["mode"] == "tracked";
    // Measured: 0.0007-0.003 model units (the frames spread over 8.2).
    EXPECT_LE(Error(records[i], i), 0.02);
  }
  EXPECT_EQ(records[0]["tracking"]["mode"], "relocalized");
  EXPECT_GE(tracked, int(records.size()) - 2);
  std::ifstream lines(trajectory);
  for (size_t i = 0; i < records.size(); ++i) {
    double timestamp = -1;
    ASSERT_TRUE(lines >> timestamp);
    lines.ignore(1000, '\n');
    EXPECT_DOUBLE_EQ(timestamp, 0.5 * double(i));
  }

  // Two threads: the next frame decoded while this one is tracked, the same poses bit for bit.
  const auto two = dir_->path() / "two_threads.jsonl";
  Localize("--video " + Video().string() +
               " --camera 'SIMPLE_RADIAL 540 960 692.745 270 480 0.0030128' "
               "--first-octave 0 --max-features 2000 --threads 2 -q -o " +
               two.string(),
           &status);
  ASSERT_EQ(status, 0);
  const std::vector<nlohmann::json> two_records = test::ReadJsonLines(two);
  ASSERT_EQ(two_records.size(), records.size());
  for (size_t i = 0; i < records.size(); ++i) {
    EXPECT_EQ(two_records[i]["name"], records[i]["name"]);
    EXPECT_EQ(two_records[i]["pose"], records[i]["pose"]);
    EXPECT_EQ(two_records[i]["tracking"]["mode"], records[i]["tracking"]["mode"]);
  }
}

// Every second frame, the focal length unknown, shrunk for SIFT (the frames are 540 x 960):
// estimated on each frame near COLMAP's; the kapture trajectory's timestamps are the frames'
// times in microseconds.
TEST_F(VideoCliTest, EveryNthFrameWithAnUnknownFocalLength) {
  const auto out = dir_->path() / "step.jsonl", trajectory = dir_->path() / "step.txt";
  int status = 0;
  const std::string output = Localize(
      "--video " + Video().string() + " --video-step 2 --max-image-size 800 -q -o " + out.string() +
          " --trajectory " + trajectory.string() + " --trajectory-format kapture",
      &status);
  if (output.find("built without FFmpeg") != std::string::npos) GTEST_SKIP() << output;
  ASSERT_EQ(status, 0) << output;
  const std::vector<nlohmann::json> records = test::ReadJsonLines(out);
  ASSERT_EQ(records.size(), (frames_->size() + 1) / 2);
  for (size_t i = 0; i < records.size(); ++i) {
    SCOPED_TRACE(i);
    EXPECT_EQ(records[i]["name"], Video().string() + "#" + std::to_string(2 * i));
    ASSERT_TRUE(records[i]["success"].get<bool>());
    EXPECT_EQ(records[i]["camera"]["calibration"], "unknown");
    EXPECT_EQ(records[i]["photo"]["extraction_width"], 450);  // 540 x 960 at 800 / 960
    EXPECT_EQ(records[i]["photo"]["extraction_height"], 800);
    EXPECT_NEAR(records[i]["camera"]["params"][0].get<double>(), 692.745, 7.0);
    EXPECT_LE(Error(records[i], 2 * i), 0.04);  // measured: 0.002-0.025
  }
  std::ifstream lines(trajectory);
  lines.ignore(1000, '\n').ignore(1000, '\n');  // the two comment lines
  for (size_t i = 0; i < records.size(); ++i) {
    long long timestamp = -1;
    ASSERT_TRUE(lines >> timestamp);
    lines.ignore(1000, '\n');
    EXPECT_EQ(timestamp, 1000000LL * static_cast<long long>(i));  // frame 2i of a 2 fps video
  }
}

// A file that is no video, one that is missing, and a video cut short: exit 2 with the file
// named; the frames decoded before the cut stay in the output.
TEST_F(VideoCliTest, BrokenVideosAreNamedAndTheFramesBeforeACutStay) {
  int status = 0;
  const auto text = dir_->path() / "notes.mp4";
  std::ofstream(text) << "not a video\n";
  std::string output = Localize("--video " + text.string() + " -q", &status);
  if (output.find("built without FFmpeg") != std::string::npos) GTEST_SKIP() << output;
  EXPECT_EQ(status, 2);
  EXPECT_EQ(output, "cwloc-localize: error: " + text.string() +
                        ": not a video FFmpeg can read (Invalid data found when processing "
                        "input)\n");
  output = Localize("--video " + (dir_->path() / "none.mp4").string() + " -q", &status);
  EXPECT_EQ(status, 2);
  EXPECT_EQ(output,
            "cwloc-localize: error: " + (dir_->path() / "none.mp4").string() + ": no such file\n");

  const std::vector<uint8_t> bytes = test::ReadBytes(Video());
  const auto cut = dir_->path() / "cut.mp4";
  test::WriteBytes(cut, std::span(bytes).first(bytes.size() * 3 / 4));
  const auto out = dir_->path() / "cut.jsonl";
  output = Localize("--video " + cut.string() + " --first-octave 0 -q -o " + out.string(), &status);
  EXPECT_EQ(status, 2);
  EXPECT_NE(output.find("cwloc-localize: error: " + cut.string() + ": frame "), std::string::npos)
      << output;
  const std::vector<nlohmann::json> records = test::ReadJsonLines(out);
  EXPECT_GE(records.size(), 1u);
  EXPECT_LT(records.size(), frames_->size());
  for (const nlohmann::json& record : records) EXPECT_TRUE(record["success"].get<bool>());
  // Decoded ahead on a thread of its own: the same frames, then the same error.
  const auto cut_two = dir_->path() / "cut_two.jsonl";
  const std::string two_output = Localize(
      "--video " + cut.string() + " --first-octave 0 --threads 2 -q -o " + cut_two.string(),
      &status);
  EXPECT_EQ(status, 2);
  EXPECT_EQ(two_output, output);
  EXPECT_EQ(test::ReadJsonLines(cut_two).size(), records.size());

  output = Localize("--video " + Video().string() + " --image x.jpg -q", &status);
  EXPECT_EQ(status, 2);
  EXPECT_EQ(output,
            "cwloc-localize: error: --video takes no other queries (its frames are the "
            "sequence)\n");
}

}  // namespace
}  // namespace cwloc
