// The C++ API (cwloc/cwloc.hpp) on the golden index shipped in tests/data, which every build,
// a device build under qemu included, can run: poses near the ground truth with real inliers,
// from many threads at once; every bad argument or file an api::Error with its code and message.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "cwloc/cwloc.hpp"
#include "tests/api/api_test_util.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;
using testing::StartsWith;

class LocalizerApiTest : public testing::Test {
 protected:
  void SetUp() override {
    truth_ = test::ReadGroundTruth(QueryDir() / "queries_gt.txt");
    ASSERT_EQ(truth_.size(), 4u);
  }

  api::Result LocalizeQuery(const api::Localizer& localizer, const std::string& name,
                            const api::Options& options = api::Options()) const {
    const api::Features features = api::ReadFeatureFile((QueryDir() / (name + ".txt")).string());
    return localizer.Localize(features, ParseCamera(truth_.at(name).camera), options);
  }

  std::map<std::string, test::GroundTruthQuery> truth_;
};

TEST_F(LocalizerApiTest, OpensTheIndexAndReportsItsContents) {
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string(), /*verify=*/true);
  const api::IndexInfo info = localizer.Info();
  EXPECT_EQ(info.path, GoldenIndex().string());
  EXPECT_EQ(info.format_version, "1.0");
  EXPECT_EQ(info.num_images, 26u);
  EXPECT_EQ(info.num_points, 718u);
  EXPECT_EQ(info.num_views, 1707u);
  EXPECT_STREQ(api::Version(), "0.1.0");
}

// Near the generator's cameras (the golden test's bounds), with inliers that reproject within
// the inlier threshold through the returned pose and camera.
TEST_F(LocalizerApiTest, LocalizesFeaturesNearTheGroundTruthWithRealInliers) {
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  const double metres_per_unit = test::ReadMetresPerUnit(QueryDir() / "scale_to_metres.txt");
  const api::Options options;
  for (const auto& [name, truth] : truth_) {
    SCOPED_TRACE(name);
    const api::Result result = LocalizeQuery(localizer, name);
    ASSERT_TRUE(result.success) << result.failure_reason;
    EXPECT_EQ(result.failure_reason, "");
    const Eigen::Vector3d center(result.center[0], result.center[1], result.center[2]);
    EXPECT_LT((center - truth.pose.Center()).norm() * metres_per_unit, 0.25);
    const Eigen::Quaterniond rotation(result.rotation[0], result.rotation[1], result.rotation[2],
                                      result.rotation[3]);
    EXPECT_LT(rotation.angularDistance(truth.pose.rotation) * 180 / M_PI, 0.7);

    ASSERT_EQ(result.inliers.size(), result.num_inliers);
    EXPECT_GE(result.num_inliers, static_cast<uint32_t>(options.min_inliers));
    EXPECT_LE(result.num_inliers, result.correspondences);
    const Eigen::Vector3d t(result.translation[0], result.translation[1], result.translation[2]);
    ASSERT_EQ(result.camera.model, "SIMPLE_RADIAL");  // the query's known camera
    const double f = result.camera.params[0], cx = result.camera.params[1],
                 cy = result.camera.params[2], k = result.camera.params[3];
    for (const api::Inlier& inlier : result.inliers) {
      const Eigen::Vector3d x =
          rotation * Eigen::Vector3d(inlier.xyz[0], inlier.xyz[1], inlier.xyz[2]) + t;
      ASSERT_GT(x.z(), 0);
      const Eigen::Vector2d uv = x.hnormalized();
      const Eigen::Vector2d pixel = f * (1 + k * uv.squaredNorm()) * uv + Eigen::Vector2d(cx, cy);
      EXPECT_LT((pixel - Eigen::Vector2d(inlier.keypoint[0], inlier.keypoint[1])).norm(),
                options.max_error_px);
    }
    ASSERT_FALSE(result.ranked_images.empty());
    EXPECT_GT(result.ranked_images[0].votes, 0u);
    EXPECT_THAT(result.ranked_images[0].name, StartsWith("map_"));
    EXPECT_GT(result.times.total, 0.0);
    EXPECT_EQ(result.times.extraction, 0.0);
  }
}

// One opened index, eight threads, every query many times: each answer equals the
// single-threaded one.
TEST_F(LocalizerApiTest, ConcurrentQueriesOnOneIndexGiveTheSequentialResults) {
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  std::vector<std::string> names;
  std::map<std::string, api::Result> expected;
  for (const auto& [name, truth] : truth_) {
    names.push_back(name);
    expected[name] = LocalizeQuery(localizer, name);
  }
  constexpr int kThreads = 8;
  constexpr int kRounds = 5;
  std::vector<std::vector<api::Result>> results(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (int round = 0; round < kRounds; ++round) {
        for (const std::string& name : names) results[t].push_back(LocalizeQuery(localizer, name));
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  for (int t = 0; t < kThreads; ++t) {
    ASSERT_EQ(results[t].size(), names.size() * kRounds);
    for (size_t i = 0; i < results[t].size(); ++i) {
      const api::Result& want = expected[names[i % names.size()]];
      EXPECT_EQ(results[t][i].rotation, want.rotation);
      EXPECT_EQ(results[t][i].translation, want.translation);
      EXPECT_EQ(results[t][i].num_inliers, want.num_inliers);
    }
  }
}

TEST_F(LocalizerApiTest, OptionsStartAtTheToolDefaultsAndChangeTheRun) {
  const api::Options options;
  EXPECT_EQ(options.matcher, "cluster-wise");
  EXPECT_EQ(options.k, 5u);
  EXPECT_EQ(options.ratio, 0.7);
  EXPECT_EQ(options.min_inliers, 12);
  EXPECT_EQ(options.max_error_px, 6.0);
  EXPECT_EQ(options.max_image_size, 3200u);

  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  api::Options impossible;
  impossible.min_inliers = 100000;
  const api::Result result = LocalizeQuery(localizer, "query_00001.jpg", impossible);
  EXPECT_FALSE(result.success);
  EXPECT_THAT(result.failure_reason, HasSubstr("< 100000"));
  EXPECT_TRUE(result.inliers.empty());
}

TEST_F(LocalizerApiTest, BadFilesAreBadInputNamingTheFile) {
  const test::TempDir dir;
  const std::string missing = (dir / "missing.cwl").string();
  ExpectError([&] { api::Localizer::Open(missing); }, api::ErrorCode::kBadInput,
              missing + ": cannot open: No such file or directory");

  const std::string truncated = (dir / "truncated.cwl").string();
  {
    std::ifstream in(GoldenIndex(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(truncated, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  try {
    api::Localizer::Open(truncated);
    ADD_FAILURE() << "a truncated index opened";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kBadInput);
    EXPECT_THAT(e.what(), StartsWith(truncated + ": "));
    EXPECT_THAT(e.what(), HasSubstr("truncated"));
  }

  const std::string features = (dir / "features.txt").string();
  std::ofstream(features) << "2 128\n1 2 3\n";
  try {
    api::ReadFeatureFile(features);
    ADD_FAILURE() << "a broken feature file was read";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kBadInput);
    EXPECT_THAT(e.what(), StartsWith(features));
  }

  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  const uint8_t garbage[] = {1, 2, 3, 4, 5, 6, 7, 8};
  try {
    localizer.LocalizeEncodedPhoto(garbage, sizeof(garbage));
    ADD_FAILURE() << "garbage decoded as a photo";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kBadInput);
    EXPECT_THAT(e.what(), StartsWith("photo bytes: "));
  }
}

TEST_F(LocalizerApiTest, BadArgumentsAreInvalidArgumentWithTheReason) {
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  const api::Features features =
      api::ReadFeatureFile((QueryDir() / "query_00001.jpg.txt").string());
  const api::Camera good = ParseCamera(truth_.at("query_00001.jpg").camera);

  api::Camera fisheye = good;
  fisheye.model = "NO_SUCH_MODEL";
  try {
    localizer.Localize(features, fisheye);
    ADD_FAILURE() << "an unknown camera model was accepted";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kInvalidArgument);
    EXPECT_THAT(e.what(), StartsWith("camera: unknown camera model 'NO_SUCH_MODEL' (known: "
                                     "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV,"));
  }
  api::Camera short_params = good;
  short_params.params.pop_back();
  ExpectError([&] { localizer.Localize(features, short_params); }, api::ErrorCode::kInvalidArgument,
              "camera: SIMPLE_RADIAL takes 4 parameters, got 3");
  api::Camera no_size = good;
  no_size.calibration = api::Calibration::kUnknown;
  no_size.width = 0;
  ExpectError([&] { localizer.Localize(features, no_size); }, api::ErrorCode::kInvalidArgument,
              "camera: expected a positive image width (at most 1000000)");

  api::Options options;
  options.k = 0;
  ExpectError([&] { localizer.Localize(features, good, options); },
              api::ErrorCode::kInvalidArgument, "--k 0: expected 1 to 63");
  options = api::Options();
  options.matcher = "psychic";
  ExpectError([&] { localizer.Localize(features, good, options); },
              api::ErrorCode::kInvalidArgument,
              "--matcher psychic: expected cluster-wise, global-ratio or cluster-exhaustive");

  const std::vector<uint8_t> pixels(64 * 48, 128);
  api::Camera small = good;
  ExpectError([&] { localizer.LocalizeGreyImage(pixels.data(), 64, 48, 32, small); },
              api::ErrorCode::kInvalidArgument,
              "grey image: 64 x 48 with stride 32: expected a positive size and stride >= width");
  ExpectError([&] { localizer.LocalizeGreyImage(pixels.data(), 64, 48, 64, small); },
              api::ErrorCode::kInvalidArgument,
              "grey image: the camera is 1024 x 768 but the image is 64 x 48");
  ExpectError([&] { localizer.LocalizeGreyImage(nullptr, 64, 48, 64, small); },
              api::ErrorCode::kInvalidArgument, "grey image: null pointer");
}

}  // namespace
}  // namespace cwloc
