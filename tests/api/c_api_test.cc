// The C API (cwloc/cwloc.h): the same answers as the C++ API, status codes and per-thread
// messages for every misuse, accessors that refuse out-of-range indices.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <thread>

#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"
#include "tests/api/api_test_util.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

const std::string kIndex = GoldenIndex().string();
const std::string kQuery = (QueryDir() / "query_00001.jpg.txt").string();
const double kParams[] = {900, 512, 384, -0.01};  // the generator's camera (queries_gt.txt)

cwloc_camera KnownCamera() {
  return {"SIMPLE_RADIAL", 1024, 768, kParams, 4, CWLOC_CALIBRATION_KNOWN};
}

class CApiTest : public testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(cwloc_localizer_open(kIndex.c_str(), 0, &localizer_), CWLOC_OK) << cwloc_last_error();
    features_ = api::ReadFeatureFile(kQuery);
  }
  void TearDown() override { cwloc_localizer_close(localizer_); }

  cwloc_status Localize(const cwloc_camera* camera, const cwloc_options* options,
                        cwloc_result** result) const {
    return cwloc_localize_features(
        localizer_, features_.keypoints.data(), features_.descriptors.data(),
        static_cast<uint32_t>(features_.keypoints.size() / 2), camera, options, result);
  }

  cwloc_localizer* localizer_ = nullptr;
  api::Features features_;
};

TEST_F(CApiTest, LocalizesLikeTheCppApi) {
  const cwloc_camera camera = KnownCamera();
  cwloc_result* result = nullptr;
  ASSERT_EQ(Localize(&camera, nullptr, &result), CWLOC_OK) << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 1) << cwloc_result_failure_reason(result);
  EXPECT_STREQ(cwloc_result_failure_reason(result), "");

  const api::Localizer cpp = api::Localizer::Open(kIndex);
  const api::Result want =
      cpp.Localize(features_, {"SIMPLE_RADIAL", 1024, 768, {900, 512, 384, -0.01}});
  double rotation[4], translation[3], center[3];
  cwloc_result_pose(result, rotation, translation, center);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(rotation[i], want.rotation[i]);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(translation[i], want.translation[i]);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(center[i], want.center[i]);
  EXPECT_EQ(cwloc_result_num_features(result), want.num_features);
  EXPECT_EQ(cwloc_result_num_correspondences(result), want.correspondences);
  ASSERT_EQ(cwloc_result_num_inliers(result), want.num_inliers);
  for (uint32_t i = 0; i < want.num_inliers; ++i) {
    uint32_t feature = 0, point = 0;
    float keypoint[2];
    double xyz[3];
    ASSERT_EQ(cwloc_result_inlier(result, i, &feature, keypoint, &point, xyz), CWLOC_OK);
    EXPECT_EQ(feature, want.inliers[i].feature);
    EXPECT_EQ(point, want.inliers[i].point);
    EXPECT_EQ(keypoint[0], want.inliers[i].keypoint[0]);
    EXPECT_EQ(xyz[2], want.inliers[i].xyz[2]);
  }
  ASSERT_EQ(cwloc_result_num_ranked_images(result), want.ranked_images.size());
  uint32_t image_id = 0, votes = 0;
  const char* name = nullptr;
  ASSERT_EQ(cwloc_result_ranked_image(result, 0, &image_id, &name, &votes), CWLOC_OK);
  EXPECT_EQ(image_id, want.ranked_images[0].image_id);
  EXPECT_EQ(name, want.ranked_images[0].name);
  EXPECT_EQ(votes, want.ranked_images[0].votes);

  cwloc_camera used{};
  cwloc_result_camera(result, &used);
  EXPECT_STREQ(used.model, "SIMPLE_RADIAL");
  ASSERT_EQ(used.num_params, 4u);
  EXPECT_EQ(used.params[0], 900);
  EXPECT_EQ(used.calibration, CWLOC_CALIBRATION_KNOWN);
  cwloc_stage_times times{};
  cwloc_result_times(result, &times);
  EXPECT_GT(times.total, 0);
  EXPECT_EQ(times.extraction, 0);

  EXPECT_EQ(cwloc_result_inlier(result, want.num_inliers, nullptr, nullptr, nullptr, nullptr),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cwloc_last_error(), "inlier " + std::to_string(want.num_inliers) + ": out of range");
  EXPECT_EQ(cwloc_result_ranked_image(result, 1000, nullptr, nullptr, nullptr),
            CWLOC_ERROR_INVALID_ARGUMENT);
  cwloc_result_destroy(result);
}

TEST_F(CApiTest, UnknownFocalNeedsOnlyTheImageSize) {
  const cwloc_camera size_only = {nullptr, 1024, 768, nullptr, 0, CWLOC_CALIBRATION_UNKNOWN};
  cwloc_result* result = nullptr;
  ASSERT_EQ(Localize(&size_only, nullptr, &result), CWLOC_OK) << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 1) << cwloc_result_failure_reason(result);
  cwloc_camera used{};
  cwloc_result_camera(result, &used);
  EXPECT_STREQ(used.model, "SIMPLE_RADIAL");
  EXPECT_NEAR(used.params[0], 900, 900 * 0.02);  // estimated focal
  cwloc_result_destroy(result);
}

TEST_F(CApiTest, OptionsAreSetByFlagNameAndChecked) {
  cwloc_options* options = nullptr;
  ASSERT_EQ(cwloc_options_create(&options), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set(options, "min-inliers", 100000), CWLOC_OK);
  const cwloc_camera camera = KnownCamera();
  cwloc_result* result = nullptr;
  ASSERT_EQ(Localize(&camera, options, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_success(result), 0);
  EXPECT_THAT(cwloc_result_failure_reason(result), HasSubstr("< 100000"));
  cwloc_result_destroy(result);

  EXPECT_EQ(cwloc_options_set(options, "warp-speed", 9), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "unknown option 'warp-speed'");
  EXPECT_EQ(cwloc_options_set(options, "k", 2.5), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "option 'k': 2.500000 is not a valid value");
  EXPECT_EQ(cwloc_options_set(options, "seed", -1), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cwloc_options_set(options, "refine", 2), CWLOC_ERROR_INVALID_ARGUMENT);

  // In range for the type, out of range for the pipeline: refused when the query runs.
  EXPECT_EQ(cwloc_options_set(options, "min-inliers", 12), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set(options, "k", 64), CWLOC_OK);
  EXPECT_EQ(Localize(&camera, options, &result), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(result, nullptr);
  EXPECT_STREQ(cwloc_last_error(), "--k 64: expected 1 to 63");

  EXPECT_EQ(cwloc_options_set(options, "k", 5), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set_matcher(options, "cluster-exhaustive"), CWLOC_OK);
  ASSERT_EQ(Localize(&camera, options, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_success(result), 1) << cwloc_result_failure_reason(result);
  cwloc_result_destroy(result);
  EXPECT_EQ(cwloc_options_set_matcher(options, "psychic"), CWLOC_OK);
  EXPECT_EQ(Localize(&camera, options, &result), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "unknown matcher 'psychic'");
  cwloc_options_destroy(options);
}

TEST_F(CApiTest, MisuseGetsAStatusAndAMessage) {
  cwloc_localizer* other = reinterpret_cast<cwloc_localizer*>(1);
  EXPECT_EQ(cwloc_localizer_open("/no/such/index.cwl", 0, &other), CWLOC_ERROR_BAD_INPUT);
  EXPECT_EQ(other, nullptr);
  EXPECT_STREQ(cwloc_last_error(), "/no/such/index.cwl: cannot open: No such file or directory");
  EXPECT_EQ(cwloc_localizer_open(nullptr, 0, &other), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "index_path is NULL");

  cwloc_result* result = nullptr;
  EXPECT_EQ(Localize(nullptr, nullptr, &result), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "features need a camera (at least the image size)");
  const cwloc_camera camera = KnownCamera();
  EXPECT_EQ(cwloc_localize_features(localizer_, nullptr, nullptr, 10, &camera, nullptr, &result),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "keypoints or descriptors is NULL");
  EXPECT_EQ(cwloc_localize_features(nullptr, nullptr, nullptr, 0, &camera, nullptr, &result),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "localizer is NULL");
  const cwloc_camera bad = {"SIMPLE_RADIAL", 1024, 768, kParams, 3, CWLOC_CALIBRATION_KNOWN};
  EXPECT_EQ(Localize(&bad, nullptr, &result), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "camera: SIMPLE_RADIAL takes 4 parameters, got 3");

  // A query with no features is the caller's bad input, reported, never a crash.
  EXPECT_EQ(cwloc_localize_features(localizer_, nullptr, nullptr, 0, &camera, nullptr, &result),
            CWLOC_ERROR_BAD_INPUT);
  EXPECT_THAT(cwloc_last_error(), HasSubstr("no features"));

  EXPECT_EQ(cwloc_localize_photo(localizer_, "/no/such/photo.jpg", nullptr, nullptr, &result),
            CWLOC_ERROR_BAD_INPUT);
  EXPECT_THAT(cwloc_last_error(), HasSubstr("/no/such/photo.jpg"));

  // Accessors of a NULL result answer "nothing" instead of crashing.
  EXPECT_EQ(cwloc_result_success(nullptr), 0);
  EXPECT_EQ(cwloc_result_num_inliers(nullptr), 0u);
  cwloc_result_destroy(nullptr);
  cwloc_localizer_close(nullptr);
  cwloc_options_destroy(nullptr);
}

// Messages belong to the thread that failed.
TEST_F(CApiTest, TheLastErrorIsPerThread) {
  cwloc_localizer* none = nullptr;
  ASSERT_EQ(cwloc_localizer_open("/no/such/index.cwl", 0, &none), CWLOC_ERROR_BAD_INPUT);
  std::string other_thread;
  std::thread([&] { other_thread = cwloc_last_error(); }).join();
  EXPECT_EQ(other_thread, "");
  EXPECT_THAT(cwloc_last_error(), HasSubstr("/no/such/index.cwl"));
}

TEST(CApiVersion, IsTheProjectVersion) { EXPECT_STREQ(cwloc_version(), "0.1.0"); }

}  // namespace
}  // namespace cwloc
