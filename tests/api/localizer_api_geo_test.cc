// The C++ API on the georeferenced golden index (tests/data/golden/index-1.1.cwl, every build):
// geo poses near the generator's true WGS84 positions and attitudes, the index's origin, the
// position and gravity priors and what they did, and every bad prior an api::Error with the
// pipeline's message.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

#include "cwloc/cwloc.hpp"
#include "tests/api/api_test_util.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

struct Wgs84 {
  double latitude_deg = 0, longitude_deg = 0, height_m = 0;
};

// queries_geo.txt: "NAME LAT LON HEIGHT", the generator's exact camera centres.
std::map<std::string, Wgs84> ReadQueriesGeo(const std::filesystem::path& path) {
  std::map<std::string, Wgs84> out;
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    Wgs84 g;
    fields >> name >> g.latitude_deg >> g.longitude_deg >> g.height_m;
    out[name] = g;
  }
  return out;
}

// scale_to_metres.txt's "R r00 r01 ... r22": the rotation from the model to ENU metres at the
// city centre (cwloc-synth --geo).
Eigen::Matrix3d ReadModelToEnuRotation(const std::filesystem::path& path) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string key;
    Eigen::Matrix3d r;
    if (fields >> key && key == "R") {
      for (int i = 0; i < 9; ++i) fields >> r(i / 3, i % 3);
      return r;
    }
  }
  throw std::runtime_error(path.string() + ": no 'R ...' line");
}

// East, north, up of `to` seen from `from`, to first order in the offset: the WGS84 ellipsoid's
// radii of curvature at `from`, and the earth's curvature for up. Within a millimetre over the
// city's 100 m.
Eigen::Vector3d EnuOffset(const Wgs84& from, const Wgs84& to) {
  constexpr double kA = 6378137.0, kF = 1 / 298.257223563, kE2 = kF * (2 - kF);
  const double phi = from.latitude_deg * M_PI / 180;
  const double w = 1 - kE2 * std::sin(phi) * std::sin(phi);
  const double n = kA / std::sqrt(w);                    // prime vertical
  const double m = kA * (1 - kE2) / (w * std::sqrt(w));  // meridian
  const double east =
      (to.longitude_deg - from.longitude_deg) * M_PI / 180 * (n + from.height_m) * std::cos(phi);
  const double north = (to.latitude_deg - from.latitude_deg) * M_PI / 180 * (m + from.height_m);
  const double up = to.height_m - from.height_m - (east * east + north * north) / (2 * n);
  return {east, north, up};
}

double AngleDeg(double a, double b) {  // the difference of two angles, in [0, 180]
  return std::abs(std::remainder(a - b, 360.0));
}

class LocalizerApiGeoTest : public testing::Test {
 protected:
  void SetUp() override {
    truth_ = test::ReadGroundTruth(GeoQueryDir() / "queries_gt.txt");
    geo_truth_ = ReadQueriesGeo(GeoQueryDir() / "queries_geo.txt");
    model_to_enu_ = ReadModelToEnuRotation(GeoQueryDir() / "scale_to_metres.txt");
    ASSERT_EQ(truth_.size(), 4u);
    ASSERT_EQ(geo_truth_.size(), 4u);
  }

  api::Result LocalizeQuery(const std::string& name,
                            const api::Options& options = api::Options()) const {
    return localizer_.Localize(ReadQueryFeatures(GeoQueryDir(), name),
                               ParseCamera(truth_.at(name).camera), options);
  }

  // The direction gravity pulls in the true camera's frame (x right, y down, z forward): what a
  // perfect accelerometer gives, negated.
  std::array<double, 3> TrueGravity(const std::string& name) const {
    const Eigen::Vector3d g =
        truth_.at(name).pose.rotation * (model_to_enu_.transpose() * -Eigen::Vector3d::UnitZ());
    return {g.x(), g.y(), g.z()};
  }

  const api::Localizer localizer_ = api::Localizer::Open(GeoIndex().string());
  std::map<std::string, test::GroundTruthQuery> truth_;
  std::map<std::string, Wgs84> geo_truth_;
  Eigen::Matrix3d model_to_enu_;
};

TEST_F(LocalizerApiGeoTest, InfoSaysWhetherTheIndexIsGeoreferencedAndWhere) {
  const api::IndexInfo info = localizer_.Info();
  EXPECT_EQ(info.format_version, "1.1");
  EXPECT_TRUE(info.georeferenced);
  // The fit's ENU origin: the geodetic centroid of its 23 inlier GPS positions.
  EXPECT_EQ(info.origin_latitude_deg, 47.37790629466928);
  EXPECT_EQ(info.origin_longitude_deg, 8.5402978132254059);
  EXPECT_EQ(info.origin_height_m, 456.42555247826095);

  const api::IndexInfo plain = api::Localizer::Open(GoldenIndex().string()).Info();
  EXPECT_FALSE(plain.georeferenced);
  EXPECT_EQ(plain.origin_latitude_deg, 0.0);
  EXPECT_EQ(plain.origin_longitude_deg, 0.0);
  EXPECT_EQ(plain.origin_height_m, 0.0);
}

TEST_F(LocalizerApiGeoTest, OptionsStartWithoutPriorsAtTheToolDefaults) {
  const api::Options options;
  EXPECT_FALSE(options.position_prior);
  EXPECT_FALSE(options.gravity);
  EXPECT_EQ(options.prior_gravity_sigma_deg, 1.0);  // --prior-gravity-sigma 1
  EXPECT_FALSE(options.use_exif_gps);
  EXPECT_EQ(options.exif_gps_radius_m, 50.0);  // --exif-gps-radius 50
}

// Each query on the globe: near its true position (the georeference is fit to 26 GPS positions
// with 3 m noise, so it is itself about a metre off), its ENU position the same point seen from
// the index's origin, and heading, pitch and roll those of the true camera.
TEST_F(LocalizerApiGeoTest, GeoPosesAreNearTheTruePositionsAndAttitudes) {
  const api::IndexInfo info = localizer_.Info();
  const Wgs84 origin{info.origin_latitude_deg, info.origin_longitude_deg, info.origin_height_m};
  for (const auto& [name, truth] : truth_) {
    SCOPED_TRACE(name);
    const api::Result result = LocalizeQuery(name);
    ASSERT_TRUE(result.success) << result.failure_reason;
    ASSERT_TRUE(result.geo);
    const api::GeoPose& geo = *result.geo;
    const Wgs84 found{geo.latitude_deg, geo.longitude_deg, geo.height_m};
    // Measured: 1.51 to 1.67 m; the ENU position agrees to 0.3 mm.
    EXPECT_LT(EnuOffset(geo_truth_.at(name), found).norm(), 2.5);
    EXPECT_LT(
        (EnuOffset(origin, found) - Eigen::Vector3d(geo.enu[0], geo.enu[1], geo.enu[2])).norm(),
        0.001);

    // The true camera's axes in ENU (at the city centre; 60 m away the frames differ by 5e-4°).
    const Eigen::Matrix3d enu_from_cam =
        model_to_enu_ * truth.pose.rotation.conjugate().toRotationMatrix();
    const Eigen::Vector3d forward = enu_from_cam.col(2), right = enu_from_cam.col(0),
                          down = enu_from_cam.col(1);
    const double heading = std::atan2(forward.x(), forward.y()) * 180 / M_PI;
    const double pitch = std::asin(forward.z()) * 180 / M_PI;
    const double roll = std::atan2(-right.z(), -down.z()) * 180 / M_PI;
    // Measured: heading 0.14 to 0.54°, pitch 0.42 to 1.17°, roll 0.32 to 1.17° off (the fit's
    // tilt).
    EXPECT_LT(AngleDeg(geo.heading_deg, heading), 1.5);
    EXPECT_LT(std::abs(geo.pitch_deg - pitch), 2.5);
    EXPECT_LT(AngleDeg(geo.roll_deg, roll), 2.5);
    EXPECT_GE(geo.heading_deg, 0.0);
    EXPECT_LT(geo.heading_deg, 360.0);

    EXPECT_FALSE(result.priors.position);
    EXPECT_FALSE(result.priors.gravity);
  }
}

// A horizontal GPS fix.
api::PositionPrior Prior(double latitude_deg, double longitude_deg, double radius_m) {
  api::PositionPrior prior;
  prior.latitude_deg = latitude_deg;
  prior.longitude_deg = longitude_deg;
  prior.radius_m = radius_m;
  return prior;
}

// A GPS fix at the true position and the true gravity: the query localizes among the clusters
// near the fix, and the result says what the priors did.
TEST_F(LocalizerApiGeoTest, PriorsAreUsedAndEchoed) {
  const std::map<std::string, uint32_t> clusters_within_50m = {{"query_00001.jpg", 3},
                                                               {"query_00002.jpg", 3},
                                                               {"query_00003.jpg", 3},
                                                               {"query_00004.jpg", 2}};
  for (const auto& [name, truth] : geo_truth_) {
    SCOPED_TRACE(name);
    api::Options options;
    options.position_prior = Prior(truth.latitude_deg, truth.longitude_deg, 50.0);
    options.gravity = TrueGravity(name);
    const api::Result result = LocalizeQuery(name, options);
    ASSERT_TRUE(result.success) << result.failure_reason;
    ASSERT_TRUE(result.geo);
    EXPECT_LT(EnuOffset(truth,
                        {result.geo->latitude_deg, result.geo->longitude_deg, result.geo->height_m})
                  .norm(),
              2.5);
    const std::optional<api::PositionPriorUse>& prior = result.priors.position;
    ASSERT_TRUE(prior);
    EXPECT_EQ(prior->latitude_deg, truth.latitude_deg);
    EXPECT_EQ(prior->longitude_deg, truth.longitude_deg);
    EXPECT_FALSE(prior->height_m);
    EXPECT_EQ(prior->radius_m, 50.0);
    EXPECT_EQ(prior->source, api::PriorSource::kOption);
    EXPECT_EQ(prior->clusters_in_radius, clusters_within_50m.at(name));
    ASSERT_TRUE(result.priors.gravity);
    EXPECT_EQ(result.priors.gravity->direction, options.gravity);
    // The true gravity against the georeference's: the fit tilts the model by about 1.2°
    // (measured 1.18 to 1.22°, with and without the pose stage's use of the prior).
    const std::optional<double>& error_deg = result.priors.gravity->error_deg;
    ASSERT_TRUE(error_deg);
    EXPECT_GT(*error_deg, 0.0);
    EXPECT_LT(*error_deg, 2.0);
  }
}

TEST_F(LocalizerApiGeoTest, APositionPriorFarFromTheModelFailsSayingSo) {
  api::Options options;
  options.position_prior = Prior(47.3779, 8.6403, 100.0);  // 7.5 km E
  options.gravity = TrueGravity("query_00001.jpg");
  const api::Result result = LocalizeQuery("query_00001.jpg", options);
  EXPECT_FALSE(result.success);
  EXPECT_EQ(result.failure_reason, "no model camera within 100 m of the position prior");
  ASSERT_TRUE(result.priors.position);
  EXPECT_EQ(result.priors.position->clusters_in_radius, 0u);
  EXPECT_EQ(result.correspondences, 0u);
  EXPECT_FALSE(result.geo);
  ASSERT_TRUE(result.priors.gravity);
  EXPECT_FALSE(result.priors.gravity->error_deg);
}

TEST_F(LocalizerApiGeoTest, BadPriorsAreInvalidArgumentsWithThePipelinesMessage) {
  const api::Features features = ReadQueryFeatures(GeoQueryDir(), "query_00001.jpg");
  const api::Camera camera = ParseCamera(truth_.at("query_00001.jpg").camera);
  const auto expect = [&](const api::Options& options, const std::string& message) {
    ExpectError([&] { localizer_.Localize(features, camera, options); },
                api::ErrorCode::kInvalidArgument, message);
  };
  api::Options options;
  options.position_prior = Prior(91.0, 8.5403, 50.0);
  expect(options,
         "features: position prior 91.000000, 8.540300 is not a latitude in [-90, 90] "
         "and a longitude");
  options.position_prior = api::PositionPrior{{47.3779, 8.5403, NAN, 50.0}};
  expect(options,
         "features: position prior 47.377900, 8.540300 is not a latitude in [-90, 90] "
         "and a longitude");
  options.position_prior = api::PositionPrior{{47.3779, 8.5403, 455.0, 0.0}};
  expect(options, "features: position prior radius must be a positive number of metres");
  options.position_prior = api::PositionPrior{{47.3779, 8.5403, 455.0, -5.0}};
  expect(options, "features: position prior radius must be a positive number of metres");

  options = api::Options();
  options.gravity = std::array<double, 3>{0, 0, 0};
  expect(options, "features: gravity prior must be a finite, non-zero vector");
  options.gravity = std::array<double, 3>{0, INFINITY, 0};
  expect(options, "features: gravity prior must be a finite, non-zero vector");

  options = api::Options();
  options.prior_gravity_sigma_deg = 0;
  expect(options, "--prior-gravity-sigma 0: expected degrees in (0, 90]");
  options = api::Options();
  options.exif_gps_radius_m = 0;
  expect(options, "--exif-gps-radius 0: expected a number of metres > 0");

  // Priors need an index on the globe; the golden 1.0 index (the same city) is not.
  const api::Localizer plain = api::Localizer::Open(GoldenIndex().string());
  const api::Features plain_features = ReadQueryFeatures(QueryDir(), "query_00001.jpg");
  const std::string not_georeferenced =
      "features: a position or gravity prior needs a georeferenced index (" +
      GoldenIndex().string() + " is not; see cwloc-index build --georef)";
  options = api::Options();
  options.position_prior = Prior(47.3779, 8.5403, 50.0);
  ExpectError([&] { plain.Localize(plain_features, camera, options); },
              api::ErrorCode::kInvalidArgument, not_georeferenced);
  options = api::Options();
  options.gravity = std::array<double, 3>{0, 1, 0};
  ExpectError([&] { plain.Localize(plain_features, camera, options); },
              api::ErrorCode::kInvalidArgument, not_georeferenced);
  // Without priors it localizes, with no geo pose; use_exif_gps means nothing for features.
  options = api::Options();
  options.use_exif_gps = true;
  const api::Result result = plain.Localize(plain_features, camera, options);
  EXPECT_TRUE(result.success) << result.failure_reason;
  EXPECT_FALSE(result.geo);
  EXPECT_FALSE(result.priors.position);
}

}  // namespace
}  // namespace cwloc
