// The C++ API against the tools and real photos (full builds: it needs cwloc-localize and the
// indexer): the same poses as cwloc-localize; a photo file, its bytes and its grey pixels give
// one pose near COLMAP's on ../shared/data/herz_jesu_p25.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "cwloc/cwloc.hpp"
#include "photo/image_decode.h"
#include "tests/api/api_test_util.h"
#include "tests/localization_check.h"
#include "tests/shared_data_index.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// The library and the tool are one pipeline: identical poses and counts.
TEST(LocalizerApiToolsTest, GivesTheSamePosesAsCwlocLocalize) {
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  for (const auto& [name, truth] : test::ReadGroundTruth(QueryDir() / "queries_gt.txt")) {
    SCOPED_TRACE(name);
    std::string output;
    ASSERT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " --index " +
                                   test::Quote(GoldenIndex()) + " --features " +
                                   test::Quote(QueryDir() / (name + ".txt")) + " --camera \"" +
                                   truth.camera + "\" -q",
                               &output),
              0)
        << output;
    const nlohmann::json cli = nlohmann::json::parse(output);
    const api::Result result = localizer.Localize(
        api::ReadFeatureFile((QueryDir() / (name + ".txt")).string()), ParseCamera(truth.camera));
    ASSERT_TRUE(cli["success"].get<bool>());
    EXPECT_EQ(result.num_inliers, cli["num_inliers"].get<uint32_t>());
    EXPECT_EQ(result.correspondences, cli["matches"]["correspondences"].get<uint32_t>());
    EXPECT_EQ(result.rotation, (cli["pose"]["qvec"].get<std::array<double, 4>>()));
    EXPECT_EQ(result.translation, (cli["pose"]["tvec"].get<std::array<double, 3>>()));
  }
}

// The photo inputs on a real photo (../shared/data/herz_jesu_p25, skipped without it): a file,
// its bytes and its decoded grey pixels give the same pose, near COLMAP's.
class LocalizerApiPhotoTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto shared = test::BuildSharedDataIndex("herz_jesu_p25");
    if (!shared) return;
    data_ = shared->data;
    localizer_ = new api::Localizer(api::Localizer::Open(shared->index.string()));
  }
  static void TearDownTestSuite() {
    delete localizer_;
    localizer_ = nullptr;
  }
  void SetUp() override {
    if (localizer_ == nullptr)
      GTEST_SKIP() << "shared data 'herz_jesu_p25' not found next to the source tree; skipping";
  }

  static inline std::filesystem::path data_;
  static inline api::Localizer* localizer_ = nullptr;
};

TEST_F(LocalizerApiPhotoTest, FileBytesAndGreyPixelsGiveOnePoseNearColmaps) {
  const std::filesystem::path photo = data_ / "query_images" / "0012.jpg";
  const auto truth = test::ReadGroundTruth(data_ / "queries_gt.txt").at("0012.jpg");
  const double metres_per_unit = test::ReadMetresPerUnit(data_ / "scale_to_metres.txt");
  api::Options options;  // as the data set was extracted (its README)
  options.max_image_size = 1600;
  options.max_features = 6000;

  const api::Result from_file = localizer_->LocalizePhoto(photo.string(), std::nullopt, options);
  ASSERT_TRUE(from_file.success) << from_file.failure_reason;
  EXPECT_TRUE(from_file.focal_estimated);
  EXPECT_EQ(from_file.camera.model, "SIMPLE_RADIAL");
  EXPECT_GT(from_file.times.extraction, 0.0);
  const Eigen::Vector3d center(from_file.center[0], from_file.center[1], from_file.center[2]);
  EXPECT_LT((center - truth.pose.Center()).norm() * metres_per_unit, 0.05);

  const std::vector<uint8_t> bytes = ReadFileBytes(photo);
  const api::Result from_bytes =
      localizer_->LocalizeEncodedPhoto(bytes.data(), bytes.size(), std::nullopt, options);
  EXPECT_EQ(from_bytes.rotation, from_file.rotation);
  EXPECT_EQ(from_bytes.translation, from_file.translation);
  EXPECT_EQ(from_bytes.num_inliers, from_file.num_inliers);

  // A camera frame: the decoded grey image with padded rows, and only its size known.
  const GreyImage grey = DecodeGreyImage(bytes, photo, kDefaultMaxImagePixels);
  const size_t stride = grey.width + 16;
  std::vector<uint8_t> padded(stride * grey.height, 0);
  for (uint32_t y = 0; y < grey.height; ++y)
    std::copy_n(grey.pixels.data() + size_t{y} * grey.width, grey.width, &padded[y * stride]);
  api::Camera size_only;
  size_only.width = grey.width;
  size_only.height = grey.height;
  size_only.calibration = api::Calibration::kUnknown;
  const api::Result from_pixels = localizer_->LocalizeGreyImage(
      padded.data(), grey.width, grey.height, stride, size_only, options);
  EXPECT_EQ(from_pixels.rotation, from_file.rotation);
  EXPECT_EQ(from_pixels.translation, from_file.translation);
  EXPECT_EQ(from_pixels.camera.params, from_file.camera.params);

  // The photo's own size is checked against a given camera.
  api::Camera wrong = size_only;
  wrong.width = 640;
  ExpectError([&] { localizer_->LocalizePhoto(photo.string(), wrong, options); },
              api::ErrorCode::kInvalidArgument,
              photo.string() + ": the camera is 640 x " + std::to_string(grey.height) +
                  " but the image is " + std::to_string(grey.width) + " x " +
                  std::to_string(grey.height));
}

}  // namespace
}  // namespace cwloc
