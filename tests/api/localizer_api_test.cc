// The C++ API (cwloc/cwloc.hpp) on the golden index shipped in tests/data: the same poses as
// cwloc-localize, near the ground truth, with real inliers, from many threads at once; and
// every bad argument or file reported as an api::Error with its code and message.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

#include "cwloc/cwloc.hpp"
#include "indexer/index_builder.h"
#include "photo/image_decode.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using testing::HasSubstr;
using testing::StartsWith;

std::filesystem::path GoldenDir() { return test::SourceDir() / "tests" / "data" / "golden"; }
std::filesystem::path GoldenIndex() { return GoldenDir() / "index-1.0.cwl"; }
std::filesystem::path QueryDir() { return GoldenDir() / "index-1.0-queries"; }

// "MODEL W H P1 P2 ..." as the ground-truth file writes it.
api::Camera ParseCamera(const std::string& spec) {
  std::istringstream in(spec);
  api::Camera camera;
  in >> camera.model >> camera.width >> camera.height;
  for (double p; in >> p;) camera.params.push_back(p);
  return camera;
}

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

// The library and the tool are one pipeline: identical poses and counts.
TEST_F(LocalizerApiTest, GivesTheSamePosesAsCwlocLocalize) {
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  const test::TempDir dir;
  for (const auto& [name, truth] : truth_) {
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
    const api::Result result = LocalizeQuery(localizer, name);
    ASSERT_TRUE(cli["success"].get<bool>());
    EXPECT_EQ(result.num_inliers, cli["num_inliers"].get<uint32_t>());
    EXPECT_EQ(result.correspondences, cli["matches"]["correspondences"].get<uint32_t>());
    EXPECT_EQ(result.rotation, (cli["pose"]["qvec"].get<std::array<double, 4>>()));
    EXPECT_EQ(result.translation, (cli["pose"]["tvec"].get<std::array<double, 3>>()));
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

// Checks that fn throws api::Error with this code and message.
template <typename Fn>
void ExpectError(Fn fn, api::ErrorCode code, const std::string& message) {
  try {
    fn();
    ADD_FAILURE() << "no error; expected: " << message;
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(std::string(e.what()), message);
  }
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
              api::ErrorCode::kInvalidArgument, "unknown matcher 'psychic'");

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

// The photo inputs on a real photo (../shared/data/herz_jesu_p25, skipped without it): a file,
// its bytes and its decoded grey pixels give the same pose, near COLMAP's.
class LocalizerApiPhotoTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto data = test::SharedDataDir("herz_jesu_p25");
    if (!data) return;
    data_ = new std::filesystem::path(*data);
    dir_ = new test::TempDir;
    IndexBuildOptions options;
    options.model_dir = *data_ / "mapping_model" / "bin";
    options.database_path = *data_ / "database.db";
    options.output_path = *dir_ / "herz_jesu.cwl";
    BuildIndex(options);
    localizer_ = new api::Localizer(api::Localizer::Open(options.output_path.string()));
  }
  static void TearDownTestSuite() {
    delete localizer_;
    delete dir_;
    delete data_;
    localizer_ = nullptr;
    dir_ = nullptr;
    data_ = nullptr;
  }
  void SetUp() override {
    if (localizer_ == nullptr)
      GTEST_SKIP() << "shared data 'herz_jesu_p25' not found next to the source tree; skipping";
  }

  static std::filesystem::path* data_;
  static test::TempDir* dir_;
  static api::Localizer* localizer_;
};

std::filesystem::path* LocalizerApiPhotoTest::data_ = nullptr;
test::TempDir* LocalizerApiPhotoTest::dir_ = nullptr;
api::Localizer* LocalizerApiPhotoTest::localizer_ = nullptr;

TEST_F(LocalizerApiPhotoTest, FileBytesAndGreyPixelsGiveOnePoseNearColmaps) {
  const std::filesystem::path photo = *data_ / "query_images" / "0012.jpg";
  const auto truth = test::ReadGroundTruth(*data_ / "queries_gt.txt").at("0012.jpg");
  const double metres_per_unit = test::ReadMetresPerUnit(*data_ / "scale_to_metres.txt");
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
