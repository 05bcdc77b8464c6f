// cwloc-synth --geo: the model frame is a similarity of the world, georef.txt's positions are the
// camera centres with the requested noise and exactly the requested outliers, queries_geo.txt
// holds the true centres, the query priors are exactly as far off as asked, and without --geo
// nothing changes. Everything is checked from the written files, through cwloc_geo.
#include "tools/synth/city_geo.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numbers>
#include <set>
#include <sstream>

#include "base/angles.h"
#include "base/error.h"
#include "camera/camera_models.h"
#include "colmap/reconstruction_io.h"
#include "geo/georeference.h"
#include "tests/test_util.h"
#include "tools/synth/city_scene.h"
#include "tools/synth/scene_writer.h"
#include "tools/synth/synth_options.h"

namespace cwloc::synth {
namespace {

namespace fs = std::filesystem;
using testing::HasSubstr;

const Geodetic kSydney{-33.8568, 151.2153, 25};

std::string ReadBytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The lines of a text that are neither blank nor '#' comments, split into fields.
std::vector<std::vector<std::string>> Records(const std::string& text) {
  std::vector<std::vector<std::string>> records;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    records.emplace_back();
    for (std::string field; fields >> field;) records.back().push_back(field);
  }
  return records;
}

Geodetic GeodeticOf(const std::vector<std::string>& fields, size_t first) {
  return {std::stod(fields.at(first)), std::stod(fields.at(first + 1)),
          std::stod(fields.at(first + 2))};
}

// NAME LAT LON HEIGHT lines.
std::map<std::string, Geodetic> ReadPositions(const std::string& text) {
  std::map<std::string, Geodetic> positions;
  for (const auto& fields : Records(text)) {
    EXPECT_EQ(fields.size(), 4u) << fields[0];
    positions[fields[0]] = GeodeticOf(fields, 1);
  }
  return positions;
}

// scale_to_metres.txt (X_enu = s R X_model + t) and the --geo origin: the true georeference.
Georeference ReadGeoreference(const std::string& text, const Geodetic& origin) {
  Georeference g;
  g.origin = origin;
  Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
  for (const auto& fields : Records(text)) {
    if (fields[0] == "scale") g.scale = std::stod(fields.at(1));
    if (fields[0] == "R") {
      for (int k = 0; k < 9; ++k) r(k / 3, k % 3) = std::stod(fields.at(size_t(k + 1)));
    }
    if (fields[0] == "t") {
      for (int k = 0; k < 3; ++k) g.translation[k] = std::stod(fields.at(size_t(k + 1)));
    }
  }
  EXPECT_NEAR((r * r.transpose() - Eigen::Matrix3d::Identity()).norm(), 0, 1e-12);
  EXPECT_NEAR(r.determinant(), 1, 1e-12);
  g.rotation = Eigen::Quaterniond(r);
  return g;
}

struct Pose {
  Eigen::Quaterniond rotation;  // cam_from_model
  Eigen::Vector3d translation;
  Eigen::Vector3d Centre() const { return -(rotation.inverse() * translation); }
};

std::map<std::string, Pose> ReadPoses(const std::string& text) {
  std::map<std::string, Pose> poses;
  for (const auto& f : Records(text)) {
    Pose& pose = poses[f.at(0)];
    pose.rotation = Eigen::Quaterniond(std::stod(f.at(1)), std::stod(f.at(2)), std::stod(f.at(3)),
                                       std::stod(f.at(4)));
    pose.translation = {std::stod(f.at(5)), std::stod(f.at(6)), std::stod(f.at(7))};
  }
  return poses;
}

Pose PoseOf(const colmap::Rigid3d& rigid) {
  const auto& q = rigid.rotation;
  const auto& t = rigid.translation;
  return {Eigen::Quaterniond(q[0], q[1], q[2], q[3]), Eigen::Vector3d(t[0], t[1], t[2])};
}

double AngleDeg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b)) / kDegree;
}

// The world point at the city centre on the ground: ENU = world - this (docs/synth.md).
Eigen::Vector3d EnuOrigin(const CityScene& scene) {
  return {scene.layout().width() / 2, scene.layout().depth() / 2, 0};
}

SynthKnobs SmallKnobs() {
  SynthKnobs knobs;
  knobs.seed = 7;
  knobs.blocks = 1;
  knobs.features_per_image = 300;
  knobs.queries = 6;
  knobs.camera_spacing = 5;
  knobs.motifs = 24;
  knobs.threads = 2;
  return knobs;
}

// The command that made tests/data/golden/index-1.0-queries (tests/data/README.md).
SynthKnobs GoldenKnobs() {
  SynthKnobs knobs;
  knobs.seed = 1;
  knobs.blocks = 1;
  knobs.features_per_image = 150;
  knobs.camera_spacing = 8;
  knobs.queries = 4;
  knobs.motifs = 24;
  return knobs;
}

void WriteCity(const CityScene& scene, const GeoOptions& geo, const fs::path& out) {
  SceneWriter writer(out, false);
  writer.Write(scene, {.text = false, .threads = 2, .command_line = "test", .geo = geo});
  writer.Commit("{}\n");
}

// A small city written with --geo at Sydney: exact GPS, priors 10 m and 1 degree off.
class GeoCityTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir;
    SynthKnobs knobs = SmallKnobs();
    knobs.geo = "-33.8568 151.2153 25";
    knobs.gps_noise = 0;
    knobs.prior_position_error = 10;
    knobs.prior_gravity_error = 1;
    geo_ = new GeoOptions(MakeGeoOptions(knobs));
    scene_ = new CityScene(CityScene::Generate(MakeSceneOptions(knobs)));
    WriteCity(*scene_, *geo_, out());
  }
  static void TearDownTestSuite() {
    delete scene_;
    delete geo_;
    delete dir_;
  }
  static fs::path out() { return *dir_ / "city"; }
  static std::string File(const std::string& name) { return ReadBytes(out() / name); }
  static Georeference TrueGeoreference() {
    return ReadGeoreference(File("scale_to_metres.txt"), *geo_->origin);
  }

  static test::TempDir* dir_;
  static GeoOptions* geo_;
  static CityScene* scene_;
};
test::TempDir* GeoCityTest::dir_ = nullptr;
GeoOptions* GeoCityTest::geo_ = nullptr;
CityScene* GeoCityTest::scene_ = nullptr;

TEST_F(GeoCityTest, ZeroNoiseGeorefPositionsAreTheCameraCentres) {
  const CityScene& scene = *scene_;
  const Georeference georeference = TrueGeoreference();
  const GeoFrame globe(georeference);
  const auto records = Records(File("georef.txt"));
  ASSERT_EQ(records.size(), scene.num_mapping_images());
  EXPECT_EQ(File("georef_outliers.txt"), "");
  const colmap::Reconstruction rec = colmap::ReadReconstruction(out() / "mapping_model" / "bin");
  ASSERT_EQ(rec.images.size(), records.size());
  double worst_world = 0, worst_model = 0;
  for (size_t i = 0; i < records.size(); ++i) {
    const SceneImage& image = scene.images()[i];
    ASSERT_EQ(records[i].size(), 4u);
    ASSERT_EQ(records[i][0], image.name);
    const Eigen::Vector3d enu = globe.GeodeticToEnu(GeodeticOf(records[i], 1));
    // Back to the world frame: the generator's own camera centre.
    worst_world = std::max(worst_world, (enu + EnuOrigin(scene) - image.pose.centre).norm());
    // Through the model similarity: the written model's camera centre.
    const Eigen::Vector3d model_centre =
        PoseOf(rec.images.at(image.image_id).cam_from_world).Centre();
    worst_model = std::max(worst_model, (georeference.ModelToEnu(model_centre) - enu).norm());
  }
  EXPECT_LT(worst_world, 1e-3);
  EXPECT_LT(worst_model, 1e-3);
}

TEST_F(GeoCityTest, TheModelIsARandomSimilarityOfTheWorld) {
  const CityScene& scene = *scene_;
  const Georeference georeference = TrueGeoreference();
  // Not the world frame: rotated, scaled to a few units, moved a few units.
  const double extent = std::max(scene.layout().width(), scene.layout().depth());
  const double span = extent / georeference.scale;  // model units across the larger side
  EXPECT_GE(span, kModelMinSpan);
  EXPECT_LE(span, kModelMaxSpan);
  EXPECT_GT(Eigen::AngleAxisd(georeference.rotation).angle(), 1 * kDegree);
  const Eigen::Vector3d city_centre_model = georeference.EnuToModel(Eigen::Vector3d::Zero());
  EXPECT_LE(city_centre_model.cwiseAbs().maxCoeff(), kModelTranslationRange);

  // The written points are the scene's (noisy) points through the similarity.
  const colmap::Reconstruction rec = colmap::ReadReconstruction(out() / "mapping_model" / "bin");
  double worst = 0;
  for (uint32_t p = 0; p < scene.points().size(); ++p) {
    const point3D_t id = scene.Point3DId(p);
    if (id == kInvalidPoint3DId) continue;
    const auto& xyz = rec.points3D.at(id).xyz;
    const Eigen::Vector3d enu = georeference.ModelToEnu({xyz[0], xyz[1], xyz[2]});
    worst = std::max(worst, (enu + EnuOrigin(scene) - scene.ModelXyz(p)).norm());
  }
  EXPECT_LT(worst, 1e-6);

  // Mapping and query poses: the model points still project onto the keypoints.
  const colmap::Camera& camera = rec.cameras.at(1);
  auto reprojection = [&](const Pose& pose, const SceneFeature& f, const std::array<double, 3>& x) {
    const Eigen::Vector3d c = pose.rotation * Eigen::Vector3d(x[0], x[1], x[2]) + pose.translation;
    std::array<double, 2> pixel{};
    EXPECT_TRUE(ProjectToPixel(camera.model_id, camera.params, {c.x(), c.y(), c.z()}, &pixel));
    return std::hypot(pixel[0] - f.x, pixel[1] - f.y);
  };
  const auto query_poses = ReadPoses(File("queries_gt.txt"));
  ASSERT_EQ(query_poses.size(), scene.counts().queries);
  std::vector<double> errors;
  for (const SceneImage& image : scene.images()) {
    const Pose pose = image.query ? query_poses.at(image.name)
                                  : PoseOf(rec.images.at(image.image_id).cam_from_world);
    // The camera looks the same way: cam_from_model = cam_from_world * world_from_model.
    const Eigen::Matrix3d cam_from_world =
        pose.rotation.toRotationMatrix() * georeference.rotation.toRotationMatrix().transpose();
    EXPECT_LT((cam_from_world - image.pose.cam_from_world_rotation).norm(), 1e-12) << image.name;
    for (const SceneFeature& f : image.features) {
      if (f.point == kNoPoint || scene.Point3DId(f.point) == kInvalidPoint3DId) continue;
      errors.push_back(reprojection(pose, f, rec.points3D.at(scene.Point3DId(f.point)).xyz));
    }
  }
  ASSERT_GT(errors.size(), 1000u);
  std::sort(errors.begin(), errors.end());
  EXPECT_LT(errors[errors.size() / 2], 1.5);
  EXPECT_LT(errors[errors.size() * 99 / 100], 3.0);
}

TEST_F(GeoCityTest, QueriesGeoHoldsTheTrueCentres) {
  const CityScene& scene = *scene_;
  const Georeference georeference = TrueGeoreference();
  const GeoFrame globe(georeference);
  const auto truth = ReadPositions(File("queries_geo.txt"));
  const auto poses = ReadPoses(File("queries_gt.txt"));
  ASSERT_EQ(truth.size(), scene.counts().queries);
  for (size_t i = scene.num_mapping_images(); i < scene.images().size(); ++i) {
    const SceneImage& image = scene.images()[i];
    const Geodetic& g = truth.at(image.name);
    const Eigen::Vector3d enu = globe.GeodeticToEnu(g);
    EXPECT_LT((enu + EnuOrigin(scene) - image.pose.centre).norm(), 1e-3) << image.name;
    EXPECT_LT(
        (globe.GeodeticToModel(g) - poses.at(image.name).Centre()).norm() * georeference.scale,
        1e-3)
        << image.name;
    // Street level, near the origin.
    EXPECT_NEAR(g.height_m, kSydney.height_m + 1.6, 1.0);
    EXPECT_NEAR(g.latitude_deg, kSydney.latitude_deg, 0.01);
  }
}

TEST_F(GeoCityTest, QueryPriorsAreExactlyAsFarOffAsRequested) {
  const CityScene& scene = *scene_;
  const Georeference georeference = TrueGeoreference();
  const GeoFrame globe(georeference);
  const auto truth = ReadPositions(File("queries_geo.txt"));
  const auto poses = ReadPoses(File("queries_gt.txt"));
  std::map<std::string, std::vector<std::string>> position, gravity;
  for (const auto& fields : Records(File("query_priors.txt"))) {
    ASSERT_GE(fields.size(), 2u);
    auto& target = fields[1] == "position" ? position : gravity;
    ASSERT_TRUE(fields[1] == "position" || fields[1] == "gravity") << fields[1];
    ASSERT_TRUE(target.emplace(fields[0], fields).second) << "duplicate " << fields[0];
  }
  ASSERT_EQ(position.size(), scene.counts().queries);
  ASSERT_EQ(gravity.size(), scene.counts().queries);
  std::vector<double> headings;
  for (const auto& [name, fields] : position) {
    ASSERT_EQ(fields.size(), 6u);
    EXPECT_EQ(std::stod(fields[5]), 50);  // --prior-radius default
    // Exactly 10 m off, in the camera's own horizontal plane.
    const GeoFrame here(GeoreferenceFromEnuModel(truth.at(name)));
    const Eigen::Vector3d offset = here.GeodeticToEnu(GeodeticOf(fields, 2));
    EXPECT_NEAR(offset.head<2>().norm(), 10, 1e-5) << name;
    EXPECT_NEAR(offset.z(), 0, 1e-4) << name;
    headings.push_back(std::atan2(offset.y(), offset.x()));
  }
  std::sort(headings.begin(), headings.end());
  EXPECT_GT(headings.back() - headings.front(), 0.5) << "the directions are random";
  for (const auto& [name, fields] : gravity) {
    ASSERT_EQ(fields.size(), 5u);
    const Eigen::Vector3d g(std::stod(fields[2]), std::stod(fields[3]), std::stod(fields[4]));
    EXPECT_NEAR(g.norm(), 1, 1e-12);
    // True gravity from the ground-truth pose: the local down at the camera, in its frame.
    const Pose& pose = poses.at(name);
    const Eigen::Vector3d true_gravity = pose.rotation * globe.GravityInModel(pose.Centre());
    EXPECT_NEAR(AngleDeg(g, true_gravity), 1.0, 1e-7) << name;
    // Which is the world's down (0, 0, -1) up to the turn of the vertical across the city.
    const SceneImage& image =
        *std::find_if(scene.images().begin(), scene.images().end(),
                      [&, name = name](const SceneImage& i) { return i.name == name; });
    const double distance = (image.pose.centre - EnuOrigin(scene)).head<2>().norm();
    const Eigen::Vector3d world_down =
        image.pose.cam_from_world_rotation * -Eigen::Vector3d::UnitZ();
    EXPECT_LT(AngleDeg(true_gravity, world_down), distance / 6.3e6 / kDegree + 1e-9) << name;
  }
}

TEST_F(GeoCityTest, ZeroPriorErrorsGiveTheTruth) {
  const CityScene& scene = *scene_;
  GeoOptions geo = *geo_;
  geo.prior_position_error = 0;
  geo.prior_gravity_error_deg = 0;
  const ModelFrame frame = MakeModelFrame(scene, geo);
  const GeoFiles files = MakeGeoFiles(scene, geo, frame);
  const Georeference georeference = ReadGeoreference(files.scale_to_metres, *geo.origin);
  const GeoFrame globe(georeference);
  const auto truth = ReadPositions(files.queries_geo);
  for (const auto& fields : Records(files.query_priors)) {
    const std::string& name = fields[0];
    const SceneImage& image =
        *std::find_if(scene.images().begin(), scene.images().end(),
                      [&, name = name](const SceneImage& i) { return i.name == name; });
    if (fields[1] == "position") {
      const Eigen::Vector3d enu = globe.GeodeticToEnu(GeodeticOf(fields, 2));
      EXPECT_LT((enu - globe.GeodeticToEnu(truth.at(name))).norm(), 1e-5) << name;
    } else {
      const Eigen::Vector3d g(std::stod(fields[2]), std::stod(fields[3]), std::stod(fields[4]));
      const Eigen::Vector3d model_centre = frame.ModelFromWorld(image.pose.centre);
      const Eigen::Matrix3d cam_from_model =
          image.pose.cam_from_world_rotation * frame.rotation.transpose();
      EXPECT_LT((g - cam_from_model * globe.GravityInModel(model_centre)).norm(), 1e-12) << name;
    }
  }
}

// A city of a few hundred mapping images, for the statistics of GPS noise and outliers.
class GeoStatisticsTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    SynthKnobs knobs;
    knobs.seed = 3;
    knobs.blocks = 4;
    knobs.features_per_image = 100;
    knobs.camera_spacing = 3;
    knobs.queries = 0;
    knobs.threads = 2;
    scene_ = new CityScene(CityScene::Generate(MakeSceneOptions(knobs)));
  }
  static void TearDownTestSuite() { delete scene_; }

  // GPS position minus true centre in the ENU frame at the origin, per mapping image.
  static std::vector<Eigen::Vector3d> GpsErrors(const GeoOptions& geo, std::string* outliers) {
    const ModelFrame frame = MakeModelFrame(*scene_, geo);
    const GeoFiles files = MakeGeoFiles(*scene_, geo, frame);
    *outliers = files.georef_outliers;
    const GeoFrame globe(frame.EnuFromModel(*geo.origin));
    const auto records = Records(files.georef);
    EXPECT_EQ(records.size(), scene_->num_mapping_images());
    std::vector<Eigen::Vector3d> errors;
    for (size_t i = 0; i < records.size(); ++i) {
      const Eigen::Vector3d enu = globe.GeodeticToEnu(GeodeticOf(records[i], 1));
      errors.push_back(enu + EnuOrigin(*scene_) - scene_->images()[i].pose.centre);
    }
    return errors;
  }
  static GeoOptions Geo() {
    GeoOptions geo;
    geo.origin = Geodetic{47.3769, 8.5417, 408};
    return geo;
  }

  static CityScene* scene_;
};
CityScene* GeoStatisticsTest::scene_ = nullptr;

TEST_F(GeoStatisticsTest, GpsNoiseHasTheRequestedSpread) {
  for (double sigma : {3.0, 10.0}) {
    GeoOptions geo = Geo();
    geo.gps_noise = sigma;
    std::string outliers;
    const auto errors = GpsErrors(geo, &outliers);
    ASSERT_GE(errors.size(), 300u);
    EXPECT_EQ(outliers, "");
    for (int axis = 0; axis < 3; ++axis) {
      double sum = 0, sum2 = 0;
      for (const auto& e : errors) sum += e[axis], sum2 += e[axis] * e[axis];
      const double n = double(errors.size());
      const double mean = sum / n, std = std::sqrt(sum2 / n - mean * mean);
      // Over ~500 images the empirical sigma is within 3% (1 sigma) of the true one.
      EXPECT_NEAR(std, sigma, 0.12 * sigma) << "axis " << axis;
      EXPECT_NEAR(mean, 0, 0.25 * sigma) << "axis " << axis;
    }
  }
}

TEST_F(GeoStatisticsTest, OutliersAreExactlyTheRoundedShareAndFarOff) {
  const size_t n = scene_->num_mapping_images();
  std::set<std::string> previous;
  for (double share : {0.1, 0.25, 0.33, 0.5}) {
    GeoOptions geo = Geo();
    geo.gps_outliers = share;
    std::string listed;
    const auto errors = GpsErrors(geo, &listed);
    std::set<std::string> outliers;
    std::istringstream in(listed);
    for (std::string name; std::getline(in, name);) EXPECT_TRUE(outliers.insert(name).second);
    EXPECT_EQ(outliers.size(), size_t(std::lround(share * double(n)))) << share;
    EXPECT_EQ(NumGpsOutliers(geo, n), outliers.size());
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d& e = errors[i];
      if (outliers.count(scene_->images()[i].name)) {
        EXPECT_GE(e.head<2>().norm(), 100 - 1e-3) << scene_->images()[i].name;
        EXPECT_LE(e.head<2>().norm(), 1000 + 1e-3) << scene_->images()[i].name;
        EXPECT_LE(std::abs(e.z()), 50 + 1e-3) << scene_->images()[i].name;
      } else {
        EXPECT_LT(e.norm(), 30) << scene_->images()[i].name << " (noise sigma 3 m)";
      }
    }
    // A larger share keeps the smaller share's outliers (docs/synth.md).
    EXPECT_NE(outliers, previous);
    EXPECT_TRUE(std::includes(outliers.begin(), outliers.end(), previous.begin(), previous.end()));
    previous = outliers;
  }
}

TEST_F(GeoStatisticsTest, EachKnobChangesOnlyItsOwnNumbers) {
  const GeoOptions base = Geo();
  const GeoFiles a = MakeGeoFiles(*scene_, base, MakeModelFrame(*scene_, base));
  GeoOptions other = base;
  other.gps_noise = 7;
  other.gps_outliers = 0.2;
  other.prior_position_error = 30;
  other.prior_gravity_error_deg = 5;
  const ModelFrame frame = MakeModelFrame(*scene_, other);
  const ModelFrame base_frame = MakeModelFrame(*scene_, base);
  EXPECT_EQ(frame.scale, base_frame.scale);
  EXPECT_EQ(frame.rotation, base_frame.rotation);
  EXPECT_EQ(frame.translation, base_frame.translation);
  const GeoFiles b = MakeGeoFiles(*scene_, other, frame);
  EXPECT_EQ(a.scale_to_metres, b.scale_to_metres);
  EXPECT_EQ(a.queries_geo, b.queries_geo);
  EXPECT_NE(a.georef, b.georef);
  // Same seed and knobs: the same files.
  const GeoFiles c = MakeGeoFiles(*scene_, other, frame);
  EXPECT_EQ(b.georef, c.georef);
  EXPECT_EQ(b.georef_outliers, c.georef_outliers);
  EXPECT_EQ(b.query_priors, c.query_priors);
}

// Without --geo the output is what it always was; --geo changes only the model frame's files.
TEST(SynthGeoOutputTest, WithoutGeoTheGoldenFilesAreReproducedAndGeoChangesOnlyTheModelFrame) {
  test::TempDir dir;
  const CityScene scene = CityScene::Generate(MakeSceneOptions(GoldenKnobs()));
  WriteCity(scene, {}, dir / "plain");
  SynthKnobs knobs = GoldenKnobs();
  knobs.geo = "48.137154 11.576124 520";
  knobs.gps_outliers = 0.1;
  knobs.prior_position_error = 10;
  knobs.prior_gravity_error = 1;
  WriteCity(scene, MakeGeoOptions(knobs), dir / "geo");

  // tests/data/README.md: these were written by cwloc-synth at commit 42010ac. A deliberate
  // change of the generator updates them and that README.
  const fs::path golden = test::SourceDir() / "tests" / "data" / "golden" / "index-1.0-queries";
  for (const char* file : {"queries_gt.txt", "scale_to_metres.txt"}) {
    EXPECT_TRUE(ReadBytes(dir / "plain" / file) == ReadBytes(golden / file)) << file;
  }
  for (const char* file :
       {"georef.txt", "georef_outliers.txt", "queries_geo.txt", "query_priors.txt"}) {
    EXPECT_FALSE(fs::exists(dir / "plain" / file)) << file;
    EXPECT_TRUE(fs::exists(dir / "geo" / file)) << file;
  }
  for (const char* file :
       {"database.db", "query_list.txt", "queries_with_intrinsics.txt", "queries_gt_points.txt",
        "queries_gt_matches.txt", "mapping_model/bin/cameras.bin"}) {
    const std::string a = ReadBytes(dir / "plain" / file), b = ReadBytes(dir / "geo" / file);
    EXPECT_FALSE(a.empty()) << file;
    EXPECT_TRUE(a == b) << file << " changed with --geo";
  }
  for (const char* file : {"queries_gt.txt", "scale_to_metres.txt", "mapping_model/bin/images.bin",
                           "mapping_model/bin/points3D.bin"}) {
    EXPECT_FALSE(ReadBytes(dir / "plain" / file) == ReadBytes(dir / "geo" / file)) << file;
  }
  // The same images, observations and tracks, only moved.
  const colmap::Reconstruction plain =
      colmap::ReadReconstruction(dir / "plain" / "mapping_model" / "bin");
  const colmap::Reconstruction geo =
      colmap::ReadReconstruction(dir / "geo" / "mapping_model" / "bin");
  ASSERT_EQ(plain.images.size(), geo.images.size());
  for (const auto& [id, image] : plain.images) {
    EXPECT_EQ(image.name, geo.images.at(id).name);
    EXPECT_EQ(image.points2D, geo.images.at(id).points2D);
  }
  ASSERT_EQ(plain.points3D.size(), geo.points3D.size());
  for (const auto& [id, point] : plain.points3D) {
    EXPECT_EQ(point.track, geo.points3D.at(id).track);
    EXPECT_NEAR(point.error, geo.points3D.at(id).error, 1e-9);
  }
}

TEST(SynthOptionsTest, GeoKnobsGiveExactMessages) {
  auto with = [](auto set) {
    SynthKnobs knobs;
    knobs.geo = "48.137154 11.576124 520";
    set(knobs);
    try {
      MakeGeoOptions(knobs);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(with([](SynthKnobs&) {}), "(no error)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.geo = "48.1 11.5"; }),
            "--geo must be \"LAT LON HEIGHT\" (WGS84 degrees and metres above the ellipsoid; got "
            "'48.1 11.5')");
  EXPECT_EQ(with([](SynthKnobs& k) { k.geo = "48.1 11.5 5m"; }),
            "--geo must be \"LAT LON HEIGHT\" (WGS84 degrees and metres above the ellipsoid; got "
            "'48.1 11.5 5m')");
  EXPECT_EQ(with([](SynthKnobs& k) { k.geo = "48.1 11.5 5 7"; }),
            "--geo must be \"LAT LON HEIGHT\" (WGS84 degrees and metres above the ellipsoid; got "
            "'48.1 11.5 5 7')");
  EXPECT_EQ(with([](SynthKnobs& k) { k.geo = "91 11.5 5"; }),
            "--geo latitude must be in [-90, 90] degrees (got 91)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.geo = "48 -181 5"; }),
            "--geo longitude must be in [-180, 180] degrees (got -181)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.geo = "48 11 -2000"; }),
            "--geo height must be in [-1000, 10000] metres (got -2000)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.gps_noise = -1; }),
            "--gps-noise must be in [0, 1000] metres (got -1)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.gps_outliers = 0.6; }),
            "--gps-outliers must be in [0, 0.5] (got 0.6)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.prior_position_error = -3; }),
            "--prior-position-error must be in [0, 10000] metres (got -3)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.prior_radius = 0; }),
            "--prior-radius must be in (0, 100000] metres (got 0)");
  EXPECT_EQ(with([](SynthKnobs& k) { k.prior_gravity_error = 200; }),
            "--prior-gravity-error must be in [0, 180] degrees (got 200)");
  EXPECT_EQ(with([](SynthKnobs& k) {
              k.geo.reset();
              k.prior_radius = 20;
            }),
            "--prior-radius needs --geo (it changes only the files --geo writes)");
  // The defaults, in one place (city_geo.h).
  SynthKnobs knobs;
  knobs.geo = "-33.8568 151.2153 25";
  const GeoOptions geo = MakeGeoOptions(knobs);
  ASSERT_TRUE(geo.origin.has_value());
  EXPECT_EQ(geo.origin->latitude_deg, kSydney.latitude_deg);
  EXPECT_EQ(geo.origin->longitude_deg, kSydney.longitude_deg);
  EXPECT_EQ(geo.origin->height_m, kSydney.height_m);
  EXPECT_EQ(geo.gps_noise, 3);
  EXPECT_EQ(geo.gps_outliers, 0);
  EXPECT_EQ(geo.prior_position_error, 0);
  EXPECT_EQ(geo.prior_radius, 50);
  EXPECT_EQ(geo.prior_gravity_error_deg, 0);
  EXPECT_FALSE(MakeGeoOptions(SynthKnobs{}).origin.has_value());
}

TEST(SynthGeoCliTest, GeoRunWritesTheFilesAndItsSummaryValidates) {
  if (!fs::exists(test::ToolPath("cwloc-synth"))) GTEST_SKIP() << "cwloc-synth is not built";
  test::TempDir dir;
  const fs::path out = dir / "c";
  const std::string tool = test::ToolPath("cwloc-synth").string();
  std::string output;
  ASSERT_EQ(test::RunCommand(tool + " -o " + out.string() +
                                 " --blocks 1 --features-per-image 200 --queries 3"
                                 " --camera-spacing 8 --geo '-33.8568 151.2153 25'"
                                 " --gps-outliers 0.1 --prior-gravity-error 2 --json </dev/null",
                             &output),
            0)
      << output;
  const auto summary = nlohmann::json::parse(output);
  EXPECT_EQ(summary["geo"]["origin"]["latitude_deg"], -33.8568);
  EXPECT_EQ(summary["geo"]["prior_gravity_error_deg"], 2.0);
  const size_t images = summary["counts"]["mapping_images"];
  EXPECT_EQ(summary["geo"]["gps_outlier_images"], std::lround(0.1 * double(images)));
  std::string validation;
  EXPECT_EQ(test::ValidateJson("synth-summary.schema.json", out / "stats.json", false, &validation),
            0)
      << validation;
  for (const char* file :
       {"georef.txt", "georef_outliers.txt", "queries_geo.txt", "query_priors.txt"}) {
    EXPECT_TRUE(fs::exists(out / file)) << file;
  }
  EXPECT_THAT(ReadBytes(out / "README.txt"), HasSubstr("ON THE GLOBE (--geo)"));

  EXPECT_EQ(test::RunCommand(
                tool + " -o " + (dir / "d").string() + " --gps-outliers 0.1 </dev/null", &output),
            2);
  EXPECT_EQ(output,
            "cwloc-synth: error: --gps-outliers needs --geo (it changes only the files "
            "--geo writes)\n");
  EXPECT_FALSE(fs::exists(dir / "d"));
}

}  // namespace
}  // namespace cwloc::synth
