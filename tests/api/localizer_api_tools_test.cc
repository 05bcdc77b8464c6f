// The C++ API against the tools and real photos (full builds: it needs cwloc-localize and the
// indexer): the same poses as cwloc-localize; a photo file, its bytes and its grey pixels give
// one pose near COLMAP's on ../shared/data/herz_jesu_p25; on a georeferenced generated city the
// same geo poses and priors as cwloc-localize, bit for bit.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "colmap/database.h"
#include "colmap/reconstruction_io.h"
#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"
#include "indexer/index_update.h"
#include "photo/image_decode.h"
#include "tests/api/api_test_util.h"
#include "tests/colmap/model_without_images.h"
#include "tests/localization_check.h"
#include "tests/shared_data_index.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// A query's features as cwloc-localize --database reads them: the stored keypoints and
// descriptors, unchanged.
api::Features DatabaseFeatures(const colmap::DatabaseReader& db, const std::string& name) {
  const auto image = db.FindImage(name);
  if (!image) throw std::runtime_error(name + ": not in the database");
  colmap::ImageFeatures stored = db.ReadFeatures(image->image_id);
  api::Features features;
  for (const colmap::Keypoint& keypoint : stored.keypoints) {
    features.keypoints.push_back(keypoint.x);
    features.keypoints.push_back(keypoint.y);
  }
  features.descriptors = std::move(stored.descriptors.data);
  return features;
}

// A device applies the delta of a grown real model (herz_jesu_p25 without its last three
// images, grown back) through either API and gets the update's bytes; another parent is refused
// with the C API's status and message, and nothing is written.
TEST(LocalizerApiToolsTest, AppliesAnIndexDeltaAsTheUpdateWroteIt) {
  const auto data = test::SharedDataDir("herz_jesu_p25");
  if (!data) GTEST_SKIP() << "../shared/data/herz_jesu_p25 not found";
  const test::TempDir dir;
  const colmap::Reconstruction model = colmap::ReadReconstruction(*data / "mapping_model" / "bin");
  std::set<image_t> last;
  for (auto it = model.images.rbegin(); last.size() < 3; ++it) last.insert(it->first);
  std::filesystem::create_directories(dir / "old");
  colmap::WriteReconstruction(test::ModelWithoutImages(model, last), dir / "old",
                              colmap::ModelFormat::kBinary);
  IndexBuildOptions build;
  build.model_dir = dir / "old";
  build.database_path = *data / "database.db";
  build.output_path = dir / "old.cwl";
  build.calibration_samples = 0;
  BuildIndex(build);
  IndexUpdateOptions update;
  update.index_path = build.output_path;
  update.model_dir = *data / "mapping_model" / "bin";
  update.database_path = build.database_path;
  update.output_path = dir / "updated.cwl";
  update.delta_path = dir / "grown.cwld";
  UpdateIndex(update);
  const std::vector<uint8_t> updated = test::ReadBytes(update.output_path);

  api::ApplyIndexDelta(build.output_path.string(), update.delta_path.string(),
                       (dir / "cpp.cwl").string());
  EXPECT_EQ(test::ReadBytes(dir / "cpp.cwl"), updated);
  ASSERT_EQ(cwloc_index_apply(build.output_path.c_str(), update.delta_path.c_str(),
                              (dir / "c.cwl").c_str(), 1),
            CWLOC_OK)
      << cwloc_last_error();
  EXPECT_EQ(test::ReadBytes(dir / "c.cwl"), updated);

  EXPECT_EQ(cwloc_index_apply(update.output_path.c_str(), update.delta_path.c_str(),
                              (dir / "wrong.cwl").c_str(), 0),
            CWLOC_ERROR_BAD_INPUT);
  EXPECT_THAT(cwloc_last_error(), testing::HasSubstr(update.delta_path.string() +
                                                     ": made for the index with checksum "));
  EXPECT_FALSE(std::filesystem::exists(dir / "wrong.cwl"));
  try {
    api::ApplyIndexDelta(build.output_path.string(), build.output_path.string(),
                         (dir / "wrong.cwl").string());
    FAIL() << "applied an index as a delta";
  } catch (const api::Error& error) {
    EXPECT_EQ(error.code(), api::ErrorCode::kBadInput);
    EXPECT_THAT(error.what(), testing::HasSubstr("not a cwloc index delta"));
  }
}

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

// A rig frame of golden queries (cam_from_rig from their true poses): the API's rig pose and
// image poses are cwloc-localize --frames's, bit for bit, and near the truth.
TEST(LocalizerApiToolsTest, RigFramesAreCwlocLocalizesBitForBit) {
  const auto truth = test::ReadGroundTruth(QueryDir() / "queries_gt.txt");
  const std::vector<std::string> names = {"query_00001.jpg", "query_00002.jpg", "query_00004.jpg"};
  const test::TempDir dir;
  {
    std::ofstream frames(dir / "frames.txt");
    for (const std::string& name : names) {
      frames << "f " << name << ".txt "
             << test::CamFromRigText(truth.at(name).pose, truth.at(names[0]).pose) << " "
             << truth.at(name).camera << "\n";
    }
  }
  std::string output;
  ASSERT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " --index " +
                                 test::Quote(GoldenIndex()) + " --frames " +
                                 test::Quote(dir / "frames.txt") + " --image-dir " +
                                 test::Quote(QueryDir()) + " -q",
                             &output),
            0)
      << output;
  const nlohmann::json cli = nlohmann::json::parse(output);
  std::vector<api::RigImage> images;
  for (const std::string& name : names) {
    api::RigImage& image = images.emplace_back();
    image.name = name + ".txt";
    image.features = ReadQueryFeatures(QueryDir(), name);
    image.camera = ParseCamera(truth.at(name).camera);
    std::istringstream pose(test::CamFromRigText(truth.at(name).pose, truth.at(names[0]).pose));
    for (double& v : image.cam_from_rig_rotation) pose >> v;
    for (double& v : image.cam_from_rig_translation) pose >> v;
  }
  const api::Localizer localizer = api::Localizer::Open(GoldenIndex().string());
  const api::RigResult rig = localizer.LocalizeRig(images, false, api::Options(), "f");
  ASSERT_TRUE(rig.success) << rig.failure_reason;
  ASSERT_TRUE(cli["success"].get<bool>()) << output;
  ASSERT_TRUE(rig.rig.rig_from_world);
  EXPECT_EQ(rig.rig.rig_from_world->rotation,
            (cli["rig"]["rig_from_world"]["qvec"].get<std::array<double, 4>>()));
  EXPECT_EQ(rig.rig.rig_from_world->translation,
            (cli["rig"]["rig_from_world"]["tvec"].get<std::array<double, 3>>()));
  EXPECT_EQ(rig.rig.num_inliers, cli["rig"]["num_inliers"].get<uint32_t>());
  ASSERT_EQ(rig.images.size(), names.size());
  for (size_t i = 0; i < names.size(); ++i) {
    SCOPED_TRACE(names[i]);
    const nlohmann::json& image = cli["images"][i];
    ASSERT_TRUE(rig.images[i].pose);
    const api::Pose& pose = *rig.images[i].pose;
    EXPECT_EQ(pose.rotation, (image["pose"]["qvec"].get<std::array<double, 4>>()));
    EXPECT_EQ(pose.translation, (image["pose"]["tvec"].get<std::array<double, 3>>()));
    const Eigen::Vector3d center(pose.center.data());
    EXPECT_LT((center - truth.at(names[i]).pose.Center()).norm(), 0.05);  // metres
  }
  // The record is the tool's but for its times and where the cameras came from (a list line
  // there, an argument here).
  nlohmann::json api_record = nlohmann::json::parse(api::ToJson(rig, api::Options())),
                 cli_record = cli;
  for (nlohmann::json* record : {&api_record, &cli_record}) {
    record->erase("times_ms");
    for (nlohmann::json& image : (*record)["images"]) image["camera"].erase("intrinsics_source");
  }
  EXPECT_EQ(api_record, cli_record);
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
  // Under a sanitizer, which runs SIFT 10-20x slower, at half size without the doubled octave
  // (about 6x faster; 1.8 mm from the truth): the three ways in must still give one pose.
  if (test::kSanitized) {
    options.max_image_size = 800;
    options.first_octave = 0;
  }

  const api::Result from_file = localizer_->LocalizePhoto(photo.string(), std::nullopt, options);
  ASSERT_TRUE(from_file.success) << from_file.failure_reason;
  EXPECT_TRUE(from_file.camera.focal_estimated);
  EXPECT_EQ(from_file.camera.model, "SIMPLE_RADIAL");
  EXPECT_GT(from_file.times.extraction, 0.0);
  const Eigen::Vector3d center(from_file.center[0], from_file.center[1], from_file.center[2]);
  EXPECT_LT((center - truth.pose.Center()).norm() * metres_per_unit, 0.05);

  const std::vector<uint8_t> bytes = ReadPhotoFile(photo);
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
                  " but the photo is " + std::to_string(grey.width) + " x " +
                  std::to_string(grey.height));
}

// A generated city on the globe (as tests/localizer/geo_localization_test.cc makes it): the
// mapping images' GPS, 3 m noise and 10 % wildly wrong, georeferences the index; each query has
// a position prior 10 m off and a gravity prior 1° off in city/query_priors.txt.
class LocalizerApiGeoToolsTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (!std::filesystem::exists(test::ToolPath("cwloc-synth"))) return;
    dir_ = new test::TempDir();
    fixture_ = new std::filesystem::path(test::SharedFixture("geo_city", [](const auto& out) {
      const auto city = out / "city";
      std::string output;
      ASSERT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-synth")) +
                                     " --preset demo --seed 3 --threads 2"
                                     " --geo '47.3779 8.5403 455' --gps-noise 3 --gps-outliers 0.1"
                                     " --prior-position-error 10 --prior-gravity-error 1 -o " +
                                     test::Quote(city),
                                 &output),
                0)
          << output;
      ASSERT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-index")) + " build --model " +
                                     test::Quote(city / "mapping_model" / "bin") + " --database " +
                                     test::Quote(city / "database.db") + " --georef " +
                                     test::Quote(city / "georef.txt") + " -o " +
                                     test::Quote(out / "city.cwl"),
                                 &output),
                0)
          << output;
    }));
    localizer_ = new api::Localizer(api::Localizer::Open(IndexPath().string()));
  }
  static void TearDownTestSuite() {
    delete localizer_;
    localizer_ = nullptr;
    delete dir_;
    dir_ = nullptr;
    delete fixture_;
    fixture_ = nullptr;
  }
  void SetUp() override {
    if (localizer_ == nullptr) GTEST_SKIP() << "cwloc-synth is not built (CWLOC_BUILD_TOOLS=OFF)";
  }

  // The city and its index, shared by the suite's processes: read only.
  static std::filesystem::path City() { return *fixture_ / "city"; }
  static std::filesystem::path IndexPath() { return *fixture_ / "city.cwl"; }

  // queries_with_intrinsics.txt: "NAME MODEL W H PARAMS...", in query order.
  static std::vector<std::pair<std::string, api::Camera>> Queries() {
    std::vector<std::pair<std::string, api::Camera>> queries;
    std::ifstream in(City() / "queries_with_intrinsics.txt");
    for (std::string line; std::getline(in, line);) {
      std::istringstream fields(line);
      std::string name, camera;
      if (!(fields >> name)) continue;
      std::getline(fields >> std::ws, camera);
      queries.emplace_back(name, ParseCamera(camera));
    }
    return queries;
  }

  // query_priors.txt as the API's options: "NAME position LAT LON HEIGHT|- RADIUS_M" and
  // "NAME gravity GX GY GZ", numbers read with strtod as cwloc-localize reads them.
  static std::map<std::string, api::Options> PriorOptions() {
    std::map<std::string, api::Options> options;
    std::ifstream in(City() / "query_priors.txt");
    const auto number = [](const std::string& text) { return std::strtod(text.c_str(), nullptr); };
    for (std::string line; std::getline(in, line);) {
      std::istringstream fields(line);
      std::string name, kind;
      if (!(fields >> name >> kind) || name[0] == '#') continue;
      std::vector<std::string> v;
      for (std::string value; fields >> value;) v.push_back(value);
      if (kind == "position") {
        options[name].position_prior = api::PositionPrior{
            {number(v.at(0)), number(v.at(1)),
             v.at(2) == "-" ? std::nullopt : std::optional<double>(number(v.at(2))),
             number(v.at(3))}};
      } else {
        options[name].gravity =
            std::array<double, 3>{number(v.at(0)), number(v.at(1)), number(v.at(2))};
      }
    }
    return options;
  }

  // cwloc-localize on every query with `extra` options; its JSON lines by query name.
  static std::map<std::string, nlohmann::json> LocalizeWithTheTool(const std::string& extra) {
    const auto results = *dir_ / "results.jsonl";
    std::string output;
    EXPECT_EQ(test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " --index " +
                                   test::Quote(IndexPath()) + " --database " +
                                   test::Quote(City() / "database.db") + " --query-list " +
                                   test::Quote(City() / "queries_with_intrinsics.txt") +
                                   " --threads 2 -q " + extra + " -o " + test::Quote(results),
                               &output),
              0)
        << output;
    std::map<std::string, nlohmann::json> by_name;
    for (nlohmann::json& line : test::ReadJsonLines(results)) by_name[line["name"]] = line;
    return by_name;
  }

  static inline test::TempDir* dir_ = nullptr;  // this process's scratch
  static inline std::filesystem::path* fixture_ = nullptr;
  static inline api::Localizer* localizer_ = nullptr;
};

// A query localized with its priors by cwloc-localize (its JSON record) and by the C++ API.
struct LocalizedWithPriors {
  std::string name;
  api::Camera camera;
  api::Options options;
  api::Features features;
  api::Result result;
  nlohmann::json json;
};

// Every query of the city with its priors, the same camera and priors through the tool and the
// C++ API.
class LocalizerApiGeoPriorsTest : public LocalizerApiGeoToolsTest {
 protected:
  void SetUp() override {
    LocalizerApiGeoToolsTest::SetUp();
    if (IsSkipped()) return;
    const auto cli = LocalizeWithTheTool("--priors " + test::Quote(City() / "query_priors.txt"));
    const auto priors = PriorOptions();
    const colmap::DatabaseReader db(City() / "database.db");
    const auto queries = Queries();
    ASSERT_EQ(queries.size(), 20u);
    ASSERT_EQ(cli.size(), queries.size());
    for (const auto& [name, camera] : queries) {
      LocalizedWithPriors& q = queries_.emplace_back();
      q.name = name;
      q.camera = camera;
      q.options = priors.at(name);
      q.features = DatabaseFeatures(db, name);
      q.result = localizer_->Localize(q.features, camera, q.options);
      q.json = cli.at(name);
    }
  }

  std::vector<LocalizedWithPriors> queries_;
};

// The library's pose and pose on the globe are cwloc-localize's JSON, bit for bit.
TEST_F(LocalizerApiGeoPriorsTest, GeoPosesAreCwlocLocalizesBitForBit) {
  for (const LocalizedWithPriors& q : queries_) {
    SCOPED_TRACE(q.name);
    ASSERT_TRUE(q.json["success"].get<bool>()) << q.json.dump();
    ASSERT_TRUE(q.result.success) << q.result.failure_reason;
    EXPECT_EQ(q.result.rotation, (q.json["pose"]["qvec"].get<std::array<double, 4>>()));
    EXPECT_EQ(q.result.translation, (q.json["pose"]["tvec"].get<std::array<double, 3>>()));

    ASSERT_TRUE(q.result.geo);
    const nlohmann::json& geo = q.json.at("geo");
    EXPECT_EQ(q.result.geo->latitude_deg, geo["latitude_deg"].get<double>());
    EXPECT_EQ(q.result.geo->longitude_deg, geo["longitude_deg"].get<double>());
    EXPECT_EQ(q.result.geo->height_m, geo["height_m"].get<double>());
    EXPECT_EQ(q.result.geo->enu, (geo["enu"].get<std::array<double, 3>>()));
    EXPECT_EQ(q.result.geo->heading_deg, geo["heading_deg"].get<double>());
    EXPECT_EQ(q.result.geo->pitch_deg, geo["pitch_deg"].get<double>());
    EXPECT_EQ(q.result.geo->roll_deg, geo["roll_deg"].get<double>());
  }
}

// The covariance, in the model frame and in metres on the ground, is cwloc-localize's.
TEST_F(LocalizerApiGeoPriorsTest, CovariancesAreCwlocLocalizesBitForBit) {
  double first_scale = 0;  // metres per model unit, from the first query's covariance
  for (const LocalizedWithPriors& q : queries_) {
    SCOPED_TRACE(q.name);
    ASSERT_TRUE(q.json["success"].get<bool>()) << q.json.dump();
    ASSERT_TRUE(q.result.success) << q.result.failure_reason;
    ASSERT_TRUE(q.result.covariance);
    const api::PoseCovariance& covariance = *q.result.covariance;
    const nlohmann::json& json_covariance = q.json.at("covariance");
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c)
        EXPECT_EQ(covariance.pose[6 * r + c], json_covariance["pose"][r][c].get<double>());
    }
    EXPECT_EQ(covariance.position_radius95, json_covariance["position_radius95"].get<double>());
    ASSERT_TRUE(covariance.enu_position && covariance.position_radius95_m);
    EXPECT_EQ(*covariance.position_radius95_m,
              json_covariance["position_radius95_m"].get<double>());
    for (int i = 0; i < 9; ++i)
      EXPECT_EQ((*covariance.enu_position)[i], json_covariance["enu_position"][i / 3][i % 3]);
    // The ENU frame is the model's rotated and scaled by the georeference: the radius in metres
    // is the one in model units times the city's scale, the same for every query.
    const double scale = *covariance.position_radius95_m / covariance.position_radius95;
    if (first_scale == 0) first_scale = scale;
    EXPECT_NEAR(scale, first_scale, 1e-6 * first_scale);
    EXPECT_FALSE(covariance.focal_std_px);  // a known camera
  }
}

// What the priors did is cwloc-localize's.
TEST_F(LocalizerApiGeoPriorsTest, PriorsAreCwlocLocalizesBitForBit) {
  for (const LocalizedWithPriors& q : queries_) {
    SCOPED_TRACE(q.name);
    ASSERT_TRUE(q.json["success"].get<bool>()) << q.json.dump();
    ASSERT_TRUE(q.result.success) << q.result.failure_reason;
    ASSERT_TRUE(q.options.position_prior && q.options.gravity);
    const nlohmann::json& position = q.json.at("priors").at("position");
    const std::optional<api::PositionPriorUse>& prior = q.result.priors.position;
    ASSERT_TRUE(prior);
    EXPECT_EQ(prior->latitude_deg, position["latitude_deg"].get<double>());
    EXPECT_EQ(prior->longitude_deg, position["longitude_deg"].get<double>());
    EXPECT_EQ(prior->height_m, position["height_m"].get<double>());
    EXPECT_EQ(prior->radius_m, 50.0);
    EXPECT_EQ(prior->clusters_in_radius, position["clusters_in_radius"].get<uint32_t>());
    EXPECT_GE(prior->clusters_in_radius, 1u);
    const nlohmann::json& gravity = q.json.at("priors").at("gravity");
    ASSERT_TRUE(q.result.priors.gravity && q.result.priors.gravity->error_deg);
    EXPECT_EQ(q.result.priors.gravity->direction,
              (gravity["direction"].get<std::array<double, 3>>()));
    EXPECT_EQ(*q.result.priors.gravity->error_deg, gravity["error_deg"].get<double>());
  }
}

// The C API on the same query and priors gives the C++ API's geo pose, gravity error and
// covariance, and cwloc-localize's record but for the query's name, the times and the priors'
// source.
TEST_F(LocalizerApiGeoPriorsTest, TheCApiGivesTheSameGeoPosesAndRecords) {
  cwloc_localizer* c_localizer = nullptr;
  ASSERT_EQ(cwloc_localizer_open(IndexPath().string().c_str(), 0, &c_localizer), CWLOC_OK);
  for (const LocalizedWithPriors& q : queries_) {
    SCOPED_TRACE(q.name);
    ASSERT_TRUE(q.json["success"].get<bool>()) << q.json.dump();
    ASSERT_TRUE(q.result.success) << q.result.failure_reason;
    ASSERT_TRUE(q.options.position_prior && q.options.gravity);
    ASSERT_TRUE(q.result.geo && q.result.covariance && q.result.priors.gravity);
    const api::PoseCovariance& covariance = *q.result.covariance;
    cwloc_options* c_options = nullptr;
    ASSERT_EQ(cwloc_options_create(&c_options), CWLOC_OK);
    const api::PositionPrior& p = *q.options.position_prior;
    const cwloc_position_prior c_prior = {p.latitude_deg, p.longitude_deg, *p.height_m, p.radius_m};
    ASSERT_EQ(cwloc_options_set_position_prior(c_options, &c_prior), CWLOC_OK);
    ASSERT_EQ(cwloc_options_set_gravity(c_options, q.options.gravity->data()), CWLOC_OK);
    const cwloc_camera c_camera = {q.camera.model.c_str(), q.camera.width,
                                   q.camera.height,        q.camera.params.data(),
                                   q.camera.params.size(), CWLOC_CALIBRATION_KNOWN};
    cwloc_result* c_result = nullptr;
    ASSERT_EQ(cwloc_localize_features(c_localizer, q.features.keypoints.data(),
                                      q.features.descriptors.data(),
                                      static_cast<uint32_t>(q.features.keypoints.size() / 2),
                                      &c_camera, c_options, &c_result),
              CWLOC_OK)
        << cwloc_last_error();
    EXPECT_EQ(CValue(c_result, "geo.latitude_deg"), q.result.geo->latitude_deg);
    EXPECT_EQ(CValue(c_result, "geo.longitude_deg"), q.result.geo->longitude_deg);
    EXPECT_EQ(CValue(c_result, "geo.height_m"), q.result.geo->height_m);
    EXPECT_EQ(CValue(c_result, "geo.heading_deg"), q.result.geo->heading_deg);
    EXPECT_EQ(CValue(c_result, "priors.gravity.error_deg"), *q.result.priors.gravity->error_deg);
    EXPECT_EQ(CValues(c_result, "covariance.pose"), Doubles(covariance.pose));
    EXPECT_EQ(CValues(c_result, "covariance.enu_position"), Doubles(*covariance.enu_position));
    EXPECT_EQ(CValue(c_result, "covariance.position_radius95"), covariance.position_radius95);
    EXPECT_EQ(CValue(c_result, "covariance.position_radius95_m"), *covariance.position_radius95_m);
    // The index has cwloc-index build's default calibration.
    ASSERT_TRUE(covariance.calibration);
    const double c_position_scale = CValue(c_result, "covariance.calibration.position");
    EXPECT_EQ(CValue(c_result, "covariance.calibration.rotation"),
              covariance.calibration->rotation);
    EXPECT_EQ(c_position_scale, covariance.calibration->position);
    EXPECT_GE(c_position_scale, 1.0);
    EXPECT_EQ(q.json["covariance"]["calibration"]["position_scale"], c_position_scale);
    // The record is cwloc-localize's but for the query's name, the times and the priors' source.
    nlohmann::json c_json = nlohmann::json::parse(cwloc_result_json(c_result));
    EXPECT_EQ(c_json["name"], "query");
    EXPECT_EQ(c_json["pose"], q.json["pose"]);
    EXPECT_EQ(c_json["covariance"], q.json["covariance"]);
    EXPECT_EQ(c_json["geo"], q.json["geo"]);
    EXPECT_EQ(c_json["priors"]["gravity"], q.json["priors"]["gravity"]);
    EXPECT_EQ(c_json["priors"]["position"]["source"], "option");  // the tool's came from a file
    EXPECT_EQ(c_json["matches"], q.json["matches"]);
    cwloc_result_destroy(c_result);
    cwloc_options_destroy(c_options);
  }
  cwloc_localizer_close(c_localizer);
}

// Without priors too: the geo pose is the tool's.
TEST_F(LocalizerApiGeoToolsTest, GeoPosesWithoutPriorsAreCwlocLocalizes) {
  const auto cli = LocalizeWithTheTool("");
  const colmap::DatabaseReader db(City() / "database.db");
  for (const auto& [name, camera] : Queries()) {
    SCOPED_TRACE(name);
    const api::Result result = localizer_->Localize(DatabaseFeatures(db, name), camera);
    const nlohmann::json& json = cli.at(name);
    ASSERT_TRUE(result.success) << result.failure_reason;
    ASSERT_TRUE(result.geo);
    EXPECT_EQ(result.geo->latitude_deg, json["geo"]["latitude_deg"].get<double>());
    EXPECT_EQ(result.geo->longitude_deg, json["geo"]["longitude_deg"].get<double>());
    EXPECT_EQ(result.geo->height_m, json["geo"]["height_m"].get<double>());
    EXPECT_EQ(result.geo->heading_deg, json["geo"]["heading_deg"].get<double>());
    EXPECT_FALSE(json.contains("priors"));
    EXPECT_FALSE(result.priors.position);
    EXPECT_FALSE(result.priors.gravity);
  }
}

TEST_F(LocalizerApiGeoToolsTest, APositionPriorFarFromTheModelFailsSayingSo) {
  const colmap::DatabaseReader db(City() / "database.db");
  api::Options options;
  options.position_prior = api::PositionPrior{{47.3779, 8.6403, std::nullopt, 100.0}};  // 7.5 km E
  for (const auto& [name, camera] : Queries()) {
    SCOPED_TRACE(name);
    const api::Result result = localizer_->Localize(DatabaseFeatures(db, name), camera, options);
    EXPECT_FALSE(result.success);
    EXPECT_EQ(result.failure_reason, "no model camera within 100 m of the position prior");
    ASSERT_TRUE(result.priors.position);
    EXPECT_EQ(result.priors.position->clusters_in_radius, 0u);
    EXPECT_FALSE(result.geo);
  }
}

// A phone photo's EXIF GPS (Berlin, ../shared/data/exif_samples) against the Zurich city: with
// use_exif_gps it is the position prior and nothing is that near; a given position prior wins
// over it. The same precedence and numbers as cwloc-localize --use-exif-gps.
TEST_F(LocalizerApiGeoToolsTest, ExifGpsIsThePositionPriorUnlessOneIsGiven) {
  CWLOC_REQUIRE_SHARED_DATA(samples, "exif_samples");
  const std::filesystem::path photo = samples / "berlin_iphone4s" / "01.jpg";
  api::Options options;
  options.max_image_size = 320;  // SIFT on a small copy: the test is about the prior
  options.use_exif_gps = true;
  const api::Result from_exif = localizer_->LocalizePhoto(photo.string(), std::nullopt, options);
  EXPECT_FALSE(from_exif.success);
  EXPECT_EQ(from_exif.failure_reason, "no model camera within 50 m of the position prior");
  const std::optional<api::PositionPriorUse>& exif = from_exif.priors.position;
  ASSERT_TRUE(exif);
  EXPECT_NEAR(exif->latitude_deg, 52.518916667, 1e-9);   // N 52° 31' 8.10"
  EXPECT_NEAR(exif->longitude_deg, 13.400294444, 1e-9);  // E 13° 24' 1.06"
  EXPECT_FALSE(exif->height_m);                          // EXIF altitude: MSL
  EXPECT_EQ(exif->radius_m, 50.0);
  EXPECT_EQ(exif->source, api::PriorSource::kExif);

  const auto run_tool = [&](const std::string& extra) {
    const auto results = *dir_ / "photo.jsonl";
    std::string output;
    test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " --index " +
                         test::Quote(IndexPath()) + " --image " + test::Quote(photo) +
                         " --max-image-size 320 --use-exif-gps -q " + extra + " -o " +
                         test::Quote(results),
                     &output);
    const auto lines = test::ReadJsonLines(results);
    EXPECT_EQ(lines.size(), 1u) << output;
    return lines.empty() ? nlohmann::json() : lines[0];
  };
  const nlohmann::json cli = run_tool("");
  EXPECT_EQ(cli["failure_reason"], from_exif.failure_reason);
  EXPECT_EQ(cli["priors"]["position"]["source"], "exif");
  EXPECT_EQ(cli["priors"]["position"]["latitude_deg"].get<double>(), exif->latitude_deg);
  EXPECT_EQ(cli["priors"]["position"]["longitude_deg"].get<double>(), exif->longitude_deg);

  // A given prior (around the whole city) wins over the EXIF GPS, as --prior-position does.
  options.position_prior = api::PositionPrior{{47.3779, 8.5403, std::nullopt, 1000.0}};
  const api::Result given = localizer_->LocalizePhoto(photo.string(), std::nullopt, options);
  ASSERT_TRUE(given.priors.position);
  EXPECT_EQ(given.priors.position->latitude_deg, 47.3779);
  EXPECT_GT(given.priors.position->clusters_in_radius, 100u);
  const nlohmann::json cli_given = run_tool("--prior-position '47.3779 8.5403 1000'");
  EXPECT_EQ(cli_given["priors"]["position"]["source"], "option");
  EXPECT_EQ(cli_given["priors"]["position"]["clusters_in_radius"].get<uint32_t>(),
            given.priors.position->clusters_in_radius);
  EXPECT_EQ(cli_given["success"].get<bool>(), given.success);
}

// api::Tracker and C's tracker against cwloc-localize --sequence on the first frames of a real
// video (../shared/data/fox_video, skipped without it), with each frame's stored features and
// the camera COLMAP found.
class TrackerApiTest : public testing::Test {
 protected:
  void SetUp() override {
    shared_ = test::BuildSharedDataIndex("fox_video");
    if (!shared_) GTEST_SKIP() << "shared data 'fox_video' not found";
    // In time order, 8 under a sanitizer.
    std::ifstream intrinsics(shared_->data / "queries_with_intrinsics.txt");
    std::ofstream list(dir_.path() / "frames.txt");
    for (std::string line;
         std::getline(intrinsics, line) && frames_.size() < (test::kSanitized ? 8u : 25u);) {
      const size_t space = line.find(' ');
      frames_.emplace_back(line.substr(0, space), line.substr(space + 1));
      list << line << "\n";
    }
  }

  // C's view of a known camera; it points into `camera`, which must outlive it.
  static cwloc_camera KnownCCamera(const api::Camera& camera) {
    return {camera.model.c_str(), camera.width,         camera.height,
            camera.params.data(), camera.params.size(), CWLOC_CALIBRATION_KNOWN};
  }

  // cwloc-localize --sequence with `flags`, `tracker` and a C tracker of its own on the frames,
  // with `motions` (one per frame, or none): C++ gives the CLI's modes, inlier counts and poses
  // bit for bit, C gives C++'s. The C++ results.
  std::vector<api::Result> TrackAsTheCliDoes(
      api::Tracker& tracker, const std::string& flags,
      const std::vector<std::optional<api::Motion>>& motions) {
    std::string output;
    EXPECT_EQ(
        test::RunCommand(test::Quote(test::ToolPath("cwloc-localize")) + " --index " +
                             test::Quote(shared_->index) + " --database " +
                             test::Quote(shared_->data / "database.db") + " --query-list " +
                             test::Quote(dir_.path() / "frames.txt") + " --sequence -q " + flags,
                         &output),
        0)
        << output;
    std::istringstream records(output);
    cwloc_localizer* c_localizer = nullptr;
    EXPECT_EQ(cwloc_localizer_open(shared_->index.c_str(), 0, &c_localizer), CWLOC_OK);
    cwloc_tracker* c_tracker = nullptr;
    EXPECT_EQ(cwloc_tracker_create(c_localizer, nullptr, &c_tracker), CWLOC_OK);
    const colmap::DatabaseReader db(shared_->data / "database.db");
    std::vector<api::Result> results;
    for (size_t i = 0; i < frames_.size(); ++i) {
      SCOPED_TRACE(frames_[i].first);
      std::string line;
      if (!std::getline(records, line)) {
        ADD_FAILURE() << "cwloc-localize wrote " << i << " records";
        break;
      }
      const nlohmann::json cli = nlohmann::json::parse(line);
      const api::Features features = DatabaseFeatures(db, frames_[i].first);
      const api::Camera camera = ParseCamera(frames_[i].second);
      const std::optional<api::Motion> motion = motions.empty() ? std::nullopt : motions[i];
      const api::Result& result =
          results.emplace_back(tracker.Track(features, camera, std::nullopt, motion));
      EXPECT_TRUE(result.success);
      EXPECT_TRUE(result.tracking.has_value());
      if (!result.success || !result.tracking) continue;
      EXPECT_EQ(NameOf(result.tracking->mode), cli["tracking"]["mode"].get<std::string>());
      EXPECT_EQ(result.num_inliers, cli["num_inliers"].get<uint32_t>());
      EXPECT_EQ(result.rotation, (cli["pose"]["qvec"].get<std::array<double, 4>>()));
      EXPECT_EQ(result.translation, (cli["pose"]["tvec"].get<std::array<double, 3>>()));

      const cwloc_camera c_camera = KnownCCamera(camera);
      std::optional<cwloc_motion> c_motion;
      if (motion) {
        c_motion = cwloc_motion{
            {motion->rotation[0], motion->rotation[1], motion->rotation[2], motion->rotation[3]},
            {motion->translation[0], motion->translation[1], motion->translation[2]},
            motion->sigma_rotation_deg,
            motion->sigma_position};
      }
      cwloc_result* c_result = nullptr;
      EXPECT_EQ(
          cwloc_track_features(c_tracker, features.keypoints.data(), features.descriptors.data(),
                               uint32_t(features.keypoints.size() / 2), &c_camera, nullptr,
                               c_motion ? &*c_motion : nullptr, &c_result),
          CWLOC_OK)
          << cwloc_last_error();
      if (c_result == nullptr) continue;
      EXPECT_EQ(CValue(c_result, "tracking.mode"), int(result.tracking->mode));
      EXPECT_EQ(CText(c_result, "tracking.mode"), NameOf(result.tracking->mode));
      const char* predicted_from = nullptr;
      const cwloc_status status =
          cwloc_result_text(c_result, "tracking.predicted_from", &predicted_from);
      if (result.tracking->predicted_from) {
        EXPECT_EQ(status, CWLOC_OK);
        EXPECT_EQ(predicted_from, *result.tracking->predicted_from);
      } else {
        EXPECT_EQ(status, CWLOC_ERROR_NOT_AVAILABLE);
      }
      double error = 0;
      EXPECT_EQ(cwloc_result_value(c_result, "tracking.prediction_error", &error) == CWLOC_OK,
                result.tracking->prediction_error.has_value());
      EXPECT_EQ(CValues(c_result, "rotation"), Doubles(result.rotation));
      EXPECT_EQ(CValues(c_result, "translation"), Doubles(result.translation));
      cwloc_result_destroy(c_result);
    }
    EXPECT_EQ(cwloc_tracker_reset(c_tracker), CWLOC_OK);
    cwloc_tracker_destroy(c_tracker);
    cwloc_localizer_close(c_localizer);
    return results;
  }

  std::optional<test::SharedDataIndex> shared_;
  const test::TempDir dir_;
  std::vector<std::pair<std::string, std::string>> frames_;  // name, camera
};

TEST_F(TrackerApiTest, TracksAVideoAsCwlocLocalizeSequenceDoes) {
  const api::Localizer localizer = api::Localizer::Open(shared_->index.string());
  api::Tracker tracker(localizer);
  const std::vector<api::Result> results = TrackAsTheCliDoes(tracker, "", {});
  ASSERT_EQ(results.size(), frames_.size());
  int tracked = 0;
  for (const api::Result& result : results)
    tracked += result.tracking && result.tracking->mode == api::TrackingMode::kTracked;
  EXPECT_GE(tracked, 3);

  // A query localized alone has no tracking to report.
  const colmap::DatabaseReader db(shared_->data / "database.db");
  const api::Features features = DatabaseFeatures(db, frames_[0].first);
  const api::Camera camera = ParseCamera(frames_[0].second);
  const cwloc_camera c_camera = KnownCCamera(camera);
  cwloc_localizer* c_localizer = nullptr;
  ASSERT_EQ(cwloc_localizer_open(shared_->index.c_str(), 0, &c_localizer), CWLOC_OK);
  cwloc_result* alone = nullptr;
  ASSERT_EQ(
      cwloc_localize_features(c_localizer, features.keypoints.data(), features.descriptors.data(),
                              uint32_t(features.keypoints.size() / 2), &c_camera, nullptr, &alone),
      CWLOC_OK);
  double mode = 0;
  EXPECT_EQ(cwloc_result_value(alone, "tracking.mode", &mode), CWLOC_ERROR_NOT_AVAILABLE);
  EXPECT_STREQ(cwloc_last_error(), "'tracking' is absent (A frame of a sequence)");
  cwloc_result_destroy(alone);
  cwloc_localizer_close(c_localizer);

  tracker.Reset();
  const api::Result after_reset =
      tracker.Track(DatabaseFeatures(db, frames_[1].first), ParseCamera(frames_[1].second));
  EXPECT_EQ(after_reset.tracking->mode, api::TrackingMode::kRelocalized);
  EXPECT_FALSE(after_reset.tracking->predicted_from);
}

// With each frame's true motion (from COLMAP's poses) and its sigmas, in --motion's file and as
// api::Motion and cwloc_motion: the same poses everywhere.
TEST_F(TrackerApiTest, AMotionPredictsAsCwlocLocalizeMotionDoes) {
  const auto truth = test::ReadGroundTruth(shared_->data / "queries_gt.txt");
  std::ofstream file(dir_.path() / "motion.txt");
  file.precision(17);
  std::vector<std::optional<api::Motion>> motions(1);
  for (size_t i = 1; i < frames_.size(); ++i) {
    const test::CameraPose& from = truth.at(frames_[i - 1].first).pose;
    const test::CameraPose& to = truth.at(frames_[i].first).pose;
    const Eigen::Quaterniond q = to.rotation * from.rotation.conjugate();
    const Eigen::Vector3d t = to.translation - q * from.translation;
    file << frames_[i].first << " " << q.w() << " " << q.x() << " " << q.y() << " " << q.z() << " "
         << t.x() << " " << t.y() << " " << t.z() << " 0.5 0.05\n";
    motions.push_back(api::Motion{{q.w(), q.x(), q.y(), q.z()}, {t.x(), t.y(), t.z()}, 0.5, 0.05});
  }
  file.close();
  const api::Localizer localizer = api::Localizer::Open(shared_->index.string());
  api::Tracker tracker(localizer);
  EXPECT_EQ(
      TrackAsTheCliDoes(tracker, "--motion " + test::Quote(dir_.path() / "motion.txt"), motions)
          .size(),
      frames_.size());

  // A motion that is no rotation is the caller's mistake.
  const colmap::DatabaseReader db(shared_->data / "database.db");
  try {
    tracker.Track(DatabaseFeatures(db, frames_[0].first), ParseCamera(frames_[0].second),
                  std::nullopt, api::Motion{{2, 0, 0, 0}, {0, 0, 0}});
    ADD_FAILURE() << "expected an error";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "motion: the quaternion (w, x, y, z) has length 2, not 1");
  }
  // And a negative sigma.
  try {
    tracker.Track(DatabaseFeatures(db, frames_[0].first), ParseCamera(frames_[0].second),
                  std::nullopt, api::Motion{{1, 0, 0, 0}, {0, 0, 0}, -1.0, 0.0});
    ADD_FAILURE() << "expected an error";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "motion: the sigmas are finite and at least 0 (0: not known)");
  }
  // So is a time that is no number of seconds.
  try {
    tracker.Track(DatabaseFeatures(db, frames_[0].first), ParseCamera(frames_[0].second),
                  std::numeric_limits<double>::quiet_NaN());
    ADD_FAILURE() << "expected an error";
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), api::ErrorCode::kInvalidArgument);
    EXPECT_STREQ(e.what(), "timestamp: expected a finite number of seconds");
  }
}

}  // namespace
}  // namespace cwloc
