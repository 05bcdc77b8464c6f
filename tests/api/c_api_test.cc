// The C API (cwloc/cwloc.h): the same answers as the C++ API, status codes and per-thread
// messages for every misuse, accessors that refuse out-of-range indices.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"
#include "tests/api/api_test_util.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

const std::string kIndex = GoldenIndex().string();
const std::string kQuery = (QueryDir() / "query_00001.jpg.txt").string();
const double kParams[] = {900, 512, 384, -0.01};  // the generator's camera (queries_gt.txt)

// A JSON record without its times, which differ from run to run.
nlohmann::json WithoutTimes(const std::string& record) {
  nlohmann::json json = nlohmann::json::parse(record);
  json.erase("times_ms");
  return json;
}

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
  ASSERT_EQ(cwloc_result_success(result), 1) << CText(result, "failure_reason");
  EXPECT_EQ(CText(result, "failure_reason"), "");

  const api::Localizer cpp = api::Localizer::Open(kIndex);
  const api::Result want =
      cpp.Localize(features_, {"SIMPLE_RADIAL", 1024, 768, {900, 512, 384, -0.01}});
  EXPECT_EQ(CValues(result, "rotation"), Doubles(want.rotation));
  EXPECT_EQ(CValues(result, "translation"), Doubles(want.translation));
  EXPECT_EQ(CValues(result, "center"), Doubles(want.center));
  EXPECT_EQ(CValue(result, "num_features"), want.num_features);
  EXPECT_EQ(CValue(result, "correspondences"), want.correspondences);
  EXPECT_EQ(CValue(result, "num_inliers"), want.num_inliers);
  ASSERT_EQ(CSize(result, "inliers"), want.num_inliers);
  for (uint32_t i = 0; i < want.num_inliers; ++i) {
    const std::string at = "inliers." + std::to_string(i);
    ASSERT_EQ(CValue(result, (at + ".feature").c_str()), want.inliers[i].feature);
    EXPECT_EQ(CValue(result, (at + ".point").c_str()), want.inliers[i].point);
    EXPECT_EQ(CValues(result, (at + ".keypoint").c_str()), Doubles(want.inliers[i].keypoint));
    EXPECT_EQ(CValues(result, (at + ".xyz").c_str()), Doubles(want.inliers[i].xyz));
  }
  ASSERT_EQ(CSize(result, "ranked_images"), want.ranked_images.size());
  EXPECT_EQ(CValue(result, "ranked_images.0.image_id"), want.ranked_images[0].image_id);
  EXPECT_EQ(CText(result, "ranked_images.0.name"), want.ranked_images[0].name);
  EXPECT_EQ(CValue(result, "ranked_images.0.votes"), want.ranked_images[0].votes);

  EXPECT_EQ(CText(result, "camera.model"), "SIMPLE_RADIAL");
  EXPECT_EQ(CValues(result, "camera.params"), std::vector<double>({900, 512, 384, -0.01}));
  EXPECT_EQ(CText(result, "camera.calibration"), "known");
  EXPECT_EQ(CValue(result, "camera.calibration"), CWLOC_CALIBRATION_KNOWN);
  EXPECT_EQ(CText(result, "camera.distortion.fit"), "given");
  EXPECT_GT(CValue(result, "times.total"), 0);
  EXPECT_EQ(CValue(result, "times.extraction"), 0);
  EXPECT_EQ(CValue(result, "covariance.position_radius95"), want.covariance->position_radius95);
  EXPECT_EQ(CValues(result, "covariance.pose"), Doubles(want.covariance->pose));
  EXPECT_EQ(WithoutTimes(cwloc_result_json(result)),
            WithoutTimes(api::ToJson(want, api::Options())));

  // Out of range, unknown, absent, or not what the accessor reads: a status and why.
  double value = 0;
  const std::string last = "inliers." + std::to_string(want.num_inliers) + ".feature";
  EXPECT_EQ(cwloc_result_value(result, last.c_str(), &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cwloc_last_error(), "'inliers' has " + std::to_string(want.num_inliers) +
                                    " items, no item '" + std::to_string(want.num_inliers) + "'");
  EXPECT_EQ(cwloc_result_value(result, "ranked_images.x.votes", &value),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(cwloc_result_value(result, "num_outliers", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_THAT(cwloc_last_error(),
              testing::StartsWith("'num_outliers' is no field; Result has name, success, "));
  EXPECT_EQ(cwloc_result_value(result, "camera.distortion.k", &value), CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_THAT(cwloc_last_error(), testing::StartsWith("'camera.distortion.k' is absent"));
  EXPECT_EQ(cwloc_result_value(result, "tracking.mode", &value), CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_EQ(cwloc_result_value(result, "camera", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "'camera' is an object: name one of its fields");
  EXPECT_EQ(cwloc_result_value(result, "rotation", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "'rotation' is numbers: cwloc_result_values");
  EXPECT_EQ(cwloc_result_value(result, "num_inliers.x", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "'num_inliers' has no field 'x'");
  double rotation[3];
  EXPECT_EQ(cwloc_result_values(result, "rotation", rotation, 3, nullptr),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "'rotation' has 4 values, more than the capacity 3");
  const char* text = nullptr;
  EXPECT_EQ(cwloc_result_text(result, "num_inliers", &text), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "'num_inliers' is a number: cwloc_result_value");
  cwloc_result_destroy(result);
}

// Two golden queries as a rig frame (cam_from_rig from their true poses).
TEST_F(CApiTest, LocalizesRigsLikeTheCppApi) {
  const auto truth = test::ReadGroundTruth(QueryDir() / "queries_gt.txt");
  const std::vector<std::string> names = {"query_00001.jpg", "query_00003.jpg"};
  std::vector<api::Features> features;
  std::vector<cwloc_camera> cameras(names.size(), KnownCamera());
  std::vector<cwloc_rig_image> images(names.size());
  std::vector<api::RigImage> cpp_images(names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    features.push_back(ReadQueryFeatures(QueryDir(), names[i]));
    std::istringstream pose(test::CamFromRigText(truth.at(names[i]).pose, truth.at(names[0]).pose));
    cwloc_rig_image& image = images[i];
    image.name = names[i].c_str();
    image.keypoints = features[i].keypoints.data();
    image.descriptors = features[i].descriptors.data();
    image.num_features = static_cast<uint32_t>(features[i].keypoints.size() / 2);
    image.camera = &cameras[i];
    for (double& v : image.cam_from_rig_rotation_wxyz) pose >> v;
    for (double& v : image.cam_from_rig_translation) pose >> v;
    cpp_images[i] = {names[i], features[i],
                     "",       api::Camera{"SIMPLE_RADIAL", 1024, 768, {900, 512, 384, -0.01}},
                     {},       {}};
    std::copy_n(image.cam_from_rig_rotation_wxyz, 4, cpp_images[i].cam_from_rig_rotation.begin());
    std::copy_n(image.cam_from_rig_translation, 3, cpp_images[i].cam_from_rig_translation.begin());
  }
  cwloc_result* result = nullptr;
  ASSERT_EQ(cwloc_localize_rig(localizer_, images.data(), images.size(), 0, "f", nullptr, &result),
            CWLOC_OK)
      << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 1) << CText(result, "failure_reason");
  const api::RigResult want =
      api::Localizer::Open(kIndex).LocalizeRig(cpp_images, false, api::Options(), "f");
  EXPECT_EQ(CValues(result, "rig.rig_from_world.rotation"),
            Doubles(want.rig.rig_from_world->rotation));
  EXPECT_EQ(CValues(result, "rig.rig_from_world.translation"),
            Doubles(want.rig.rig_from_world->translation));
  EXPECT_EQ(CValue(result, "rig.scale"), 1.0);
  EXPECT_EQ(CValue(result, "rig.num_inliers"), want.rig.num_inliers);
  EXPECT_EQ(CValue(result, "rig.refined"), want.rig.refined ? 1 : 0);
  ASSERT_EQ(CSize(result, "images"), 2u);
  for (uint32_t i = 0; i < 2; ++i) {
    const std::string at = "images." + std::to_string(i);
    EXPECT_EQ(CValues(result, (at + ".pose.rotation").c_str()),
              Doubles(want.images[i].pose->rotation));
    EXPECT_EQ(CValues(result, (at + ".pose.translation").c_str()),
              Doubles(want.images[i].pose->translation));
    EXPECT_EQ(CValue(result, (at + ".num_inliers").c_str()), want.images[i].num_inliers);
  }
  double value = 0;
  EXPECT_EQ(cwloc_result_value(result, "images.2.num_inliers", &value),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "'images' has 2 items, no item '2'");
  EXPECT_EQ(CValue(result, "covariance.position_radius95"), want.covariance->position_radius95);
  EXPECT_EQ(WithoutTimes(cwloc_result_json(result)),
            WithoutTimes(api::ToJson(want, api::Options())));
  EXPECT_THAT(cwloc_result_json(result), HasSubstr("\"rig\""));
  cwloc_result_destroy(result);

  // A quaternion that is not of unit length is the caller's argument.
  images[1].cam_from_rig_rotation_wxyz[0] = 2.0;
  EXPECT_EQ(cwloc_localize_rig(localizer_, images.data(), images.size(), 0, "f", nullptr, &result),
            CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_THAT(cwloc_last_error(), HasSubstr("rig image 'query_00003.jpg': cam_from_rig: the "
                                            "quaternion (w, x, y, z) has length"));
  EXPECT_EQ(result, nullptr);
}

TEST_F(CApiTest, UnknownFocalNeedsOnlyTheImageSize) {
  const cwloc_camera size_only = {nullptr, 1024, 768, nullptr, 0, CWLOC_CALIBRATION_UNKNOWN};
  cwloc_result* result = nullptr;
  ASSERT_EQ(Localize(&size_only, nullptr, &result), CWLOC_OK) << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 1) << CText(result, "failure_reason");
  EXPECT_EQ(CText(result, "camera.model"), "SIMPLE_RADIAL");
  EXPECT_EQ(CValue(result, "camera.focal_estimated"), 1);
  EXPECT_NEAR(CValues(result, "camera.params")[0], 900, 900 * 0.02);  // estimated focal
  EXPECT_GT(CValue(result, "focal_depth.focal_std_px"), 0);
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
  EXPECT_THAT(CText(result, "failure_reason"), HasSubstr("< 100000"));
  cwloc_result_destroy(result);

  EXPECT_EQ(cwloc_options_set(options, "warp-speed", 9), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "unknown option 'warp-speed'");
  EXPECT_EQ(cwloc_options_set(options, "k", 2.5), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--k 2.5: expected a whole number");
  EXPECT_EQ(cwloc_options_set(options, "seed", -1), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--seed -1: expected at least 0");
  EXPECT_EQ(cwloc_options_set(options, "refine", 2), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--refine 2: expected true or false (1 or 0)");

  // Out of the pipeline's range: refused at once, with cwloc-localize's message.
  EXPECT_EQ(cwloc_options_set(options, "min-inliers", 12), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set(options, "k", 64), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--k 64: expected 1 to 63");
  // A rule between options: refused when the query runs.
  EXPECT_EQ(cwloc_options_set(options, "min-ransac-iterations", 20000), CWLOC_OK);
  EXPECT_EQ(Localize(&camera, options, &result), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(result, nullptr);
  EXPECT_STREQ(cwloc_last_error(),
               "--min-ransac-iterations 20000: expected at most --max-ransac-iterations 10000");
  EXPECT_EQ(cwloc_options_set(options, "min-ransac-iterations", 100), CWLOC_OK);

  EXPECT_EQ(cwloc_options_set(options, "k", 5), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set_matcher(options, "cluster-exhaustive"), CWLOC_OK);
  ASSERT_EQ(Localize(&camera, options, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_success(result), 1) << CText(result, "failure_reason");
  cwloc_result_destroy(result);
  EXPECT_EQ(cwloc_options_set_matcher(options, "psychic"), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(),
               "--matcher psychic: expected cluster-wise, global-ratio or cluster-exhaustive");
  EXPECT_EQ(cwloc_options_set_text(options, "matcher", "global-ratio"), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set_text(options, "nb", "1e2"), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set_text(options, "nb", "many"), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--nb many: expected a whole number");
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
  double value = 0;
  EXPECT_EQ(cwloc_result_value(nullptr, "num_inliers", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "result or path is NULL");
  EXPECT_STREQ(cwloc_result_json(nullptr), "");
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

// The georeferenced golden index through C: the same geo poses, priors and index information
// as C++, bit for bit; a value a result does not have is CWLOC_ERROR_NOT_AVAILABLE and why.
class CApiGeoTest : public testing::Test {
 protected:
  void SetUp() override {
    ASSERT_EQ(cwloc_localizer_open(GeoIndex().string().c_str(), 0, &localizer_), CWLOC_OK)
        << cwloc_last_error();
    features_ = ReadQueryFeatures(GeoQueryDir(), "query_00001.jpg");
    ASSERT_EQ(cwloc_options_create(&options_), CWLOC_OK);
  }
  void TearDown() override {
    cwloc_options_destroy(options_);
    cwloc_localizer_close(localizer_);
  }

  cwloc_status Localize(const cwloc_localizer* localizer, const cwloc_options* options,
                        cwloc_result** result) const {
    const cwloc_camera camera = KnownCamera();
    return cwloc_localize_features(
        localizer, features_.keypoints.data(), features_.descriptors.data(),
        static_cast<uint32_t>(features_.keypoints.size() / 2), &camera, options, result);
  }

  api::Result LocalizeCpp(const api::Options& options) const {
    return api::Localizer::Open(GeoIndex().string())
        .Localize(features_, {"SIMPLE_RADIAL", 1024, 768, {900, 512, 384, -0.01}}, options);
  }

  cwloc_localizer* localizer_ = nullptr;
  cwloc_options* options_ = nullptr;
  api::Features features_;
};

// The true position of query_00001.jpg (queries_geo.txt) and a gravity near its camera's down.
constexpr double kLatitude = 47.377881256397, kLongitude = 8.541045729524;
constexpr double kGravity[3] = {0.0, 1.0, 0.06};

TEST_F(CApiGeoTest, IndexInfoIsTheCppApis) {
  const api::IndexInfo want = api::Localizer::Open(GeoIndex().string()).Info();
  cwloc_index_info info{};
  ASSERT_EQ(cwloc_localizer_info(localizer_, &info), CWLOC_OK);
  EXPECT_EQ(info.path, want.path);
  EXPECT_STREQ(info.format_version, "1.1");
  EXPECT_EQ(info.num_images, want.num_images);
  EXPECT_EQ(info.num_points, want.num_points);
  EXPECT_EQ(info.num_views, want.num_views);
  EXPECT_EQ(info.georeferenced, 1);
  EXPECT_EQ(info.origin_latitude_deg, want.origin_latitude_deg);
  EXPECT_EQ(info.origin_longitude_deg, want.origin_longitude_deg);
  EXPECT_EQ(info.origin_height_m, want.origin_height_m);

  cwloc_localizer* plain = nullptr;
  ASSERT_EQ(cwloc_localizer_open(kIndex.c_str(), 0, &plain), CWLOC_OK);
  ASSERT_EQ(cwloc_localizer_info(plain, &info), CWLOC_OK);
  EXPECT_STREQ(info.format_version, "1.0");
  EXPECT_EQ(info.num_images, 26u);
  EXPECT_EQ(info.georeferenced, 0);
  EXPECT_EQ(info.origin_latitude_deg, 0.0);
  cwloc_localizer_close(plain);

  EXPECT_EQ(cwloc_localizer_info(nullptr, &info), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "localizer is NULL");
  EXPECT_EQ(cwloc_localizer_info(localizer_, nullptr), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "info is NULL");
}

TEST_F(CApiGeoTest, GeoPoseAndPriorsAreTheCppApis) {
  // No height (NaN) is a horizontal prior, as std::nullopt is in C++.
  const cwloc_position_prior prior = {kLatitude, kLongitude, NAN, 50.0};
  ASSERT_EQ(cwloc_options_set_position_prior(options_, &prior), CWLOC_OK);
  ASSERT_EQ(cwloc_options_set_gravity(options_, kGravity), CWLOC_OK);
  ASSERT_EQ(cwloc_options_set(options_, "prior-gravity-sigma", 2.5), CWLOC_OK);
  cwloc_result* result = nullptr;
  ASSERT_EQ(Localize(localizer_, options_, &result), CWLOC_OK) << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 1) << CText(result, "failure_reason");

  api::Options options;
  options.position_prior.emplace();
  options.position_prior->latitude_deg = kLatitude;
  options.position_prior->longitude_deg = kLongitude;
  options.position_prior->radius_m = 50.0;
  options.gravity = std::array<double, 3>{kGravity[0], kGravity[1], kGravity[2]};
  options.prior_gravity_sigma_deg = 2.5;
  const api::Result want = LocalizeCpp(options);
  ASSERT_TRUE(want.geo);
  EXPECT_EQ(CValue(result, "geo.latitude_deg"), want.geo->latitude_deg);
  EXPECT_EQ(CValue(result, "geo.longitude_deg"), want.geo->longitude_deg);
  EXPECT_EQ(CValue(result, "geo.height_m"), want.geo->height_m);
  EXPECT_EQ(CValues(result, "geo.enu"), Doubles(want.geo->enu));
  EXPECT_EQ(CValue(result, "geo.heading_deg"), want.geo->heading_deg);
  EXPECT_EQ(CValue(result, "geo.pitch_deg"), want.geo->pitch_deg);
  EXPECT_EQ(CValue(result, "geo.roll_deg"), want.geo->roll_deg);
  EXPECT_NEAR(CValue(result, "geo.latitude_deg"), kLatitude, 2e-5);  // 2 m
  ASSERT_TRUE(want.covariance && want.covariance->enu_position);
  EXPECT_EQ(CValues(result, "covariance.enu_position"), Doubles(*want.covariance->enu_position));
  EXPECT_EQ(CValue(result, "covariance.position_radius95_m"),
            *want.covariance->position_radius95_m);

  EXPECT_EQ(CValue(result, "priors.position.latitude_deg"), kLatitude);
  EXPECT_EQ(CValue(result, "priors.position.longitude_deg"), kLongitude);
  double height = 0;
  EXPECT_EQ(cwloc_result_value(result, "priors.position.height_m", &height),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_EQ(CValue(result, "priors.position.radius_m"), 50.0);
  EXPECT_EQ(CText(result, "priors.position.source"), "option");
  EXPECT_EQ(CValue(result, "priors.position.clusters_in_radius"),
            want.priors.position->clusters_in_radius);
  EXPECT_EQ(CValue(result, "priors.position.clusters_in_radius"), 3);
  ASSERT_TRUE(want.priors.gravity && want.priors.gravity->error_deg);
  EXPECT_EQ(CValues(result, "priors.gravity.direction"),
            std::vector<double>(kGravity, kGravity + 3));
  EXPECT_EQ(CValue(result, "priors.gravity.error_deg"), *want.priors.gravity->error_deg);
  EXPECT_GT(CValue(result, "priors.gravity.error_deg"), 0.0);
  cwloc_result_destroy(result);

  // A height is kept; NULL removes a prior again.
  const cwloc_position_prior with_height = {kLatitude, kLongitude, 456.6, 50.0};
  ASSERT_EQ(cwloc_options_set_position_prior(options_, &with_height), CWLOC_OK);
  ASSERT_EQ(cwloc_options_set_gravity(options_, nullptr), CWLOC_OK);
  ASSERT_EQ(Localize(localizer_, options_, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(CValue(result, "priors.position.height_m"), 456.6);
  double error_deg = 0;
  EXPECT_EQ(cwloc_result_value(result, "priors.gravity.error_deg", &error_deg),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(), "'priors.gravity' is absent");
  cwloc_result_destroy(result);
  ASSERT_EQ(cwloc_options_set_position_prior(options_, nullptr), CWLOC_OK);
  ASSERT_EQ(Localize(localizer_, options_, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_value(result, "priors.position.radius_m", &error_deg),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(), "'priors.position' is absent");
  EXPECT_GE(CValue(result, "geo.heading_deg"), 0);  // no priors, still on the globe
  cwloc_result_destroy(result);
}

TEST_F(CApiGeoTest, CovarianceIsNotAvailableWithoutAPose) {
  // Two features cannot localize: no pose, so no covariance.
  const float keypoints[4] = {10, 10, 20, 20};
  const uint8_t descriptors[256] = {};
  const double params[3] = {500, 320, 240};
  const cwloc_camera camera = {"SIMPLE_PINHOLE", 640, 480, params, 3, CWLOC_CALIBRATION_KNOWN};
  cwloc_result* result = nullptr;
  ASSERT_EQ(
      cwloc_localize_features(localizer_, keypoints, descriptors, 2, &camera, options_, &result),
      CWLOC_OK)
      << cwloc_last_error();
  ASSERT_EQ(cwloc_result_success(result), 0);
  double value = 0;
  EXPECT_EQ(cwloc_result_value(result, "covariance.position_radius95", &value),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(),
               "'covariance' is absent (On success, unless the refinement problem is singular)");
  EXPECT_EQ(cwloc_result_values(result, "covariance.enu_position", nullptr, 0, nullptr),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_EQ(cwloc_result_value(result, "covariance.calibration.position", &value),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_NE(std::string(cwloc_result_json(result)).find("\"success\":false"), std::string::npos);
  cwloc_result_destroy(result);
}

TEST_F(CApiGeoTest, MissingValuesAreNotAvailableSayingWhy) {
  // Not localized: a position prior 7.5 km east of the city.
  const cwloc_position_prior far = {47.3779, 8.6403, NAN, 100.0};
  ASSERT_EQ(cwloc_options_set_position_prior(options_, &far), CWLOC_OK);
  ASSERT_EQ(cwloc_options_set_gravity(options_, kGravity), CWLOC_OK);
  cwloc_result* result = nullptr;
  ASSERT_EQ(Localize(localizer_, options_, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_success(result), 0);
  EXPECT_EQ(CText(result, "failure_reason"), "no model camera within 100 m of the position prior");
  double value = 0;
  EXPECT_EQ(cwloc_result_value(result, "geo.latitude_deg", &value), CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(), "'geo' is absent (On success with a georeferenced index)");
  EXPECT_EQ(cwloc_result_value(result, "priors.gravity.error_deg", &value),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(),
               "'priors.gravity.error_deg' is absent (Angle between the prior and the localized "
               "pose's gravity)");
  EXPECT_EQ(CValue(result, "priors.position.longitude_deg"), 8.6403);
  EXPECT_EQ(CValue(result, "priors.position.clusters_in_radius"), 0);
  cwloc_result_destroy(result);

  // Not georeferenced: the golden 1.0 index localizes, but not on the globe.
  cwloc_localizer* plain = nullptr;
  ASSERT_EQ(cwloc_localizer_open(kIndex.c_str(), 0, &plain), CWLOC_OK);
  ASSERT_EQ(Localize(plain, nullptr, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_success(result), 1);
  EXPECT_EQ(cwloc_result_value(result, "geo.latitude_deg", &value), CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_EQ(cwloc_result_value(result, "priors.gravity.error_deg", &value),
            CWLOC_ERROR_NOT_AVAILABLE);
  // A 1.0 index has no calibration: the covariance is the keypoints' alone.
  EXPECT_GT(CValue(result, "covariance.position_radius95"), 0);
  EXPECT_EQ(cwloc_result_value(result, "covariance.calibration.position", &value),
            CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(),
               "'covariance.calibration' is absent (What the index's calibration multiplied the "
               "covariance by; none when the index has no calibration for the query's "
               "calibration mode)");
  EXPECT_EQ(cwloc_result_value(result, "covariance.position_radius95_m", &value),
            CWLOC_ERROR_NOT_AVAILABLE);
  cwloc_result_destroy(result);

  // ... and priors there are the caller's mistake, with the pipeline's message.
  EXPECT_EQ(Localize(plain, options_, &result), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_EQ(result, nullptr);
  EXPECT_EQ(cwloc_last_error(),
            "features: a position or gravity prior needs a georeferenced index (" + kIndex +
                " is not; see cwloc-index build --georef)");
  cwloc_localizer_close(plain);
}

TEST_F(CApiGeoTest, BadPriorsAndKnobsAreRefused) {
  cwloc_result* result = nullptr;
  const auto expect_refused = [&](const std::string& message) {
    EXPECT_EQ(Localize(localizer_, options_, &result), CWLOC_ERROR_INVALID_ARGUMENT);
    EXPECT_EQ(result, nullptr);
    EXPECT_EQ(cwloc_last_error(), message);
  };
  // Out of range: refused when the query runs, with the pipeline's message.
  const cwloc_position_prior north_of_the_pole = {91.0, kLongitude, NAN, 50.0};
  ASSERT_EQ(cwloc_options_set_position_prior(options_, &north_of_the_pole), CWLOC_OK);
  expect_refused(
      "features: position prior 91.000000, 8.541046 is not a latitude in [-90, 90] and a "
      "longitude");
  const cwloc_position_prior no_radius = {kLatitude, kLongitude, NAN, 0.0};
  ASSERT_EQ(cwloc_options_set_position_prior(options_, &no_radius), CWLOC_OK);
  expect_refused("features: position prior radius must be a positive number of metres");
  ASSERT_EQ(cwloc_options_set_position_prior(options_, nullptr), CWLOC_OK);
  const double zero[3] = {0, 0, 0};
  ASSERT_EQ(cwloc_options_set_gravity(options_, zero), CWLOC_OK);
  expect_refused("features: gravity prior must be a finite, non-zero vector");
  ASSERT_EQ(cwloc_options_set_gravity(options_, nullptr), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set(options_, "prior-gravity-sigma", 0), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--prior-gravity-sigma 0: expected degrees in (0, 90]");
  ASSERT_EQ(cwloc_options_set(options_, "prior-gravity-sigma", 90), CWLOC_OK);
  EXPECT_EQ(cwloc_options_set(options_, "exif-gps-radius", -1), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--exif-gps-radius -1: expected a number of metres > 0");
  ASSERT_EQ(cwloc_options_set(options_, "exif-gps-radius", 30), CWLOC_OK);
  // A flag is 0 or 1.
  EXPECT_EQ(cwloc_options_set(options_, "use-exif-gps", 2), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "--use-exif-gps 2: expected true or false (1 or 0)");
  EXPECT_EQ(cwloc_options_set(options_, "use-exif-gps", 1), CWLOC_OK);
  ASSERT_EQ(Localize(localizer_, options_, &result), CWLOC_OK) << cwloc_last_error();
  EXPECT_EQ(cwloc_result_success(result), 1);  // features have no EXIF: no prior
  cwloc_result_destroy(result);

  // NULL handles and outputs.
  const cwloc_position_prior prior = {kLatitude, kLongitude, NAN, 50.0};
  EXPECT_EQ(cwloc_options_set_position_prior(nullptr, &prior), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "options is NULL");
  EXPECT_EQ(cwloc_options_set_gravity(nullptr, kGravity), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "options is NULL");
  EXPECT_EQ(cwloc_options_set(nullptr, "use-exif-gps", 1), CWLOC_ERROR_INVALID_ARGUMENT);
  ASSERT_EQ(Localize(localizer_, nullptr, &result), CWLOC_OK);
  double value = 0;
  const char* text = nullptr;
  size_t size = 0;
  EXPECT_EQ(cwloc_result_value(nullptr, "geo.heading_deg", &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "result or path is NULL");
  EXPECT_EQ(cwloc_result_value(result, nullptr, &value), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "result or path is NULL");
  EXPECT_EQ(cwloc_result_value(result, "geo.heading_deg", nullptr), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "value is NULL");
  EXPECT_EQ(cwloc_result_text(result, "name", nullptr), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "text is NULL");
  EXPECT_EQ(cwloc_result_size(result, "ranked_images", nullptr), CWLOC_ERROR_INVALID_ARGUMENT);
  EXPECT_STREQ(cwloc_last_error(), "size is NULL");
  // A success clears the last error.
  EXPECT_EQ(cwloc_result_value(result, "geo.heading_deg", &value), CWLOC_OK);
  EXPECT_STREQ(cwloc_last_error(), "");
  EXPECT_EQ(cwloc_result_text(result, "name", &text), CWLOC_OK);
  EXPECT_EQ(cwloc_result_size(result, "ranked_images", &size), CWLOC_OK);
  cwloc_result_destroy(result);
}

TEST(CApiVersion, IsTheProjectVersion) { EXPECT_STREQ(cwloc_version(), "0.1.0"); }

}  // namespace
}  // namespace cwloc
