#include "geo/georeference_fit.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include "base/error.h"
#include "tests/geo/geo_test_util.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using test::Uniform;

void ExpectInputError(const std::function<void()>& f, const std::string& message) {
  try {
    f();
    ADD_FAILURE() << "no InputError; expected: " << message;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

// A random georeferencing problem: cameras over a few square kilometres, their positions from
// the true georeference with Gaussian noise (sigma per axis, per camera), some wild outliers.
struct Problem {
  Georeference truth;
  std::vector<Eigen::Vector3d> centers;
  std::vector<GeoObservation> observations;
  std::vector<char> wild;
  std::vector<double> sigmas;
  std::vector<double> noise_m;  // |offset| of each observation from its true position
  std::vector<Geodetic> true_positions;
};

Problem MakeProblem(const Geodetic& origin, int n, double outlier_fraction,
                    const std::function<double(int)>& sigma_of, bool write_sigma) {
  Problem p;
  p.truth.origin = origin;
  p.truth.scale = std::pow(10.0, Uniform(-2, 2));
  p.truth.rotation = test::RandomRotation();
  p.truth.translation = Eigen::Vector3d{Uniform(-100, 100), Uniform(-100, 100), Uniform(-10, 10)};
  const GeoFrame frame(p.truth);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d enu{Uniform(-1500, 1500), Uniform(-1000, 1000), Uniform(-20, 40)};
    p.centers.push_back(p.truth.EnuToModel(enu));
    const double sigma = sigma_of(i);
    const bool wild = i < std::lround(outlier_fraction * n);
    Eigen::Vector3d offset;
    if (wild) {
      offset = test::RandomUnitVector();
      offset *= Uniform(100, 1000);
    } else {
      offset = Eigen::Vector3d{test::Normal(sigma), test::Normal(sigma), test::Normal(sigma)};
    }
    GeoObservation o;
    o.image_name = "image" + std::to_string(i) + ".jpg";
    o.position = frame.EnuToGeodetic(enu + offset);
    o.sigma_m = write_sigma ? sigma : 0;
    p.observations.push_back(o);
    p.wild.push_back(wild);
    p.sigmas.push_back(sigma);
    p.noise_m.push_back(offset.norm());
    p.true_positions.push_back(frame.EnuToGeodetic(enu));
  }
  return p;
}

// The largest distance, in metres, between where the fit and the truth put the cameras.
double MaxCameraError(const Problem& p, const Georeference& fitted) {
  const GeoFrame fit(fitted);
  double worst = 0;
  for (size_t i = 0; i < p.centers.size(); ++i) {
    const Eigen::Vector3d truth = fit.GeodeticToEnu(p.true_positions[i]);
    worst = std::max(worst, (truth - fitted.ModelToEnu(p.centers[i])).norm());
  }
  return worst;
}

// The RMS distance, in metres, between where the fit and the truth put the cameras.
double RmsCameraError(const Problem& p, const Georeference& fitted) {
  const GeoFrame fit(fitted);
  double sum = 0;
  for (size_t i = 0; i < p.centers.size(); ++i) {
    sum += (fit.GeodeticToEnu(p.true_positions[i]) - fitted.ModelToEnu(p.centers[i])).squaredNorm();
  }
  return std::sqrt(sum / static_cast<double>(p.centers.size()));
}

// The rotation ECEF from model of a georeference (not the local ENU at a camera, which near a
// pole turns with the camera's position).
Eigen::Matrix3d EcefFromModel(const Georeference& g) {
  return test::EnuFromEcef(g.origin.latitude_deg, g.origin.longitude_deg).transpose() *
         g.rotation.toRotationMatrix();
}

double RotationErrorRad(const Georeference& fitted, const Georeference& truth) {
  return test::AngleBetween(EcefFromModel(fitted), EcefFromModel(truth));
}

// Expected RMS of the 3D residual of m inliers with per-axis noise sigma after fitting a
// 7-parameter similarity: sigma * sqrt(3 - 7 / m).
double ExpectedRms(double sigma, int m) { return sigma * std::sqrt(3.0 - 7.0 / m); }

void CheckFit(const Problem& p, const GeoFitResult& fit, const char* name) {
  const size_t n = p.observations.size();
  ASSERT_EQ(fit.inliers.size(), n);
  ASSERT_EQ(fit.residuals_m.size(), n);
  int wild = 0, wild_flagged = 0, good_rejected = 0;
  double sum_squares = 0;
  for (size_t i = 0; i < n; ++i) {
    if (p.wild[i]) {
      ++wild;
      wild_flagged += !fit.inliers[i];
      EXPECT_GT(fit.residuals_m[i], 50) << i;
    } else {
      good_rejected += !fit.inliers[i];
      // The default inlier threshold is 3.5 sigmas; well within it, always an inlier.
      if (p.noise_m[i] < 2.5 * p.sigmas[i]) {
        EXPECT_TRUE(fit.inliers[i])
            << i << ": noise " << p.noise_m[i] << " m, residual " << fit.residuals_m[i];
      }
    }
    if (fit.inliers[i]) sum_squares += fit.residuals_m[i] * fit.residuals_m[i];
  }
  EXPECT_EQ(wild_flagged, wild) << name << ": every wild outlier flagged";
  EXPECT_LE(good_rejected, static_cast<int>(n) / 25) << name;
  EXPECT_EQ(fit.num_inliers, std::count(fit.inliers.begin(), fit.inliers.end(), 1));
  EXPECT_NEAR(fit.rms_residual_m, std::sqrt(sum_squares / fit.num_inliers), 1e-9);
  // The origin is the inliers' geodetic centroid: their mean ENU position is straight above it.
  const GeoFrame frame(fit.georeference);
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  double mean_height = 0;
  for (size_t i = 0; i < n; ++i) {
    if (!fit.inliers[i]) continue;
    mean += frame.GeodeticToEnu(p.observations[i].position);
    mean_height += p.observations[i].position.height_m;
  }
  mean /= fit.num_inliers;
  EXPECT_LT(mean.head<2>().norm(), 1e-6) << name;
  EXPECT_NEAR(fit.georeference.origin.height_m, mean_height / fit.num_inliers, 1e-6);
  std::cout << name << ": " << wild << " wild outliers flagged, " << good_rejected
            << " good ones rejected, rms " << fit.rms_residual_m << " m, scale error "
            << std::abs(fit.georeference.scale / p.truth.scale - 1) << ", camera error max "
            << MaxCameraError(p, fit.georeference) << " m, rotation error "
            << test::Degrees(RotationErrorRad(fit.georeference, p.truth)) << " deg\n";
}

TEST(FitGeoreferenceTest, RandomProblemsWithWildOutliers) {
  const Geodetic origins[] = {{52.52, 13.40, 40},  {-33.9, 151.2, 10},   {0.0, 179.99, 0},
                              {89.99, 20.0, 2800}, {-89.995, -60, 2835}, {35.0, -120.0, 1500}};
  int seed = 0;
  for (const Geodetic& origin : origins) {
    const std::string name = "origin " + std::to_string(origin.latitude_deg) + ", " +
                             std::to_string(origin.longitude_deg);
    SCOPED_TRACE(name);
    const double sigma = 3;
    const Problem p = MakeProblem(
        origin, 300, 0.1, [&](int) { return sigma; }, false);
    GeoFitOptions options;
    options.default_sigma_m = sigma;
    options.seed = ++seed;
    const GeoFitResult fit = FitGeoreference(p.centers, p.observations, options);
    CheckFit(p, fit, name.c_str());
    const double expected = ExpectedRms(sigma, fit.num_inliers);
    EXPECT_NEAR(fit.rms_residual_m / expected, 1, 0.15);
    EXPECT_NEAR(fit.georeference.scale / p.truth.scale, 1, 2e-3);
    // Statistical errors here: about 0.5 m at the cameras, 4e-4 rad, 2e-4 in scale.
    EXPECT_LT(MaxCameraError(p, fit.georeference), 3.0);
    EXPECT_LT(RotationErrorRad(fit.georeference, p.truth), 2e-3);
  }
}

TEST(FitGeoreferenceTest, PerImageSigmasWeighTheFit) {
  // Half the photos 1 m, half 10 m; the file's sigmas against one sigma for all.
  const auto sigma_of = [](int i) { return i % 2 ? 1.0 : 10.0; };
  const Problem p = MakeProblem({48.14, 11.58, 520}, 300, 0.1, sigma_of, true);
  GeoFitOptions options;
  options.seed = 5;
  const GeoFitResult weighted = FitGeoreference(p.centers, p.observations, options);
  CheckFit(p, weighted, "per-image sigmas");
  // Normalized residuals: RMS of |r| / sigma over the inliers near sqrt(3 - 7/m).
  double sum = 0;
  for (size_t i = 0; i < p.observations.size(); ++i) {
    if (weighted.inliers[i]) sum += std::pow(weighted.residuals_m[i] / sigma_of(int(i)), 2);
  }
  const double normalized_rms = std::sqrt(sum / weighted.num_inliers);
  EXPECT_NEAR(normalized_rms / ExpectedRms(1, weighted.num_inliers), 1, 0.15);

  std::vector<GeoObservation> unweighted_observations = p.observations;
  for (GeoObservation& o : unweighted_observations) o.sigma_m = 0;
  options.default_sigma_m = 10;
  const GeoFitResult unweighted = FitGeoreference(p.centers, unweighted_observations, options);
  const double weighted_error = RmsCameraError(p, weighted.georeference);
  const double unweighted_error = RmsCameraError(p, unweighted.georeference);
  std::cout << "camera error rms: weighted " << weighted_error << " m, one sigma "
            << unweighted_error << " m\n";
  // Typically 0.2 times (an effective sigma of 1.4 m against 7.1 m); over 300 seeds at most 0.86.
  EXPECT_LT(weighted_error, unweighted_error);
  EXPECT_LT(weighted_error, 0.5);
}

// The final similarity is the minimum of sum over the inliers of |residual|^2 / sigma^2: no
// small change of scale, rotation or translation lowers it.
TEST(FitGeoreferenceTest, TheFitMinimizesTheWeightedSquaredResiduals) {
  const auto sigma_of = [](int i) { return 1.0 + i % 7; };
  const Problem p = MakeProblem({46.2, 6.15, 375}, 200, 0.1, sigma_of, true);
  const GeoFitResult fit = FitGeoreference(p.centers, p.observations);
  const GeoFrame frame(fit.georeference);
  std::vector<Eigen::Vector3d> observed;
  for (const GeoObservation& o : p.observations)
    observed.push_back(frame.GeodeticToEnu(o.position));
  const auto cost = [&](const Georeference& g) {
    double sum = 0;
    for (size_t i = 0; i < p.centers.size(); ++i) {
      if (fit.inliers[i])
        sum +=
            (g.ModelToEnu(p.centers[i]) - observed[i]).squaredNorm() / (p.sigmas[i] * p.sigmas[i]);
    }
    return sum;
  };
  const double best = cost(fit.georeference);
  for (int k = 0; k < 14; ++k) {
    Georeference g = fit.georeference;
    const double sign = k % 2 ? 1 : -1;
    if (k < 2) {
      g.scale *= 1 + sign * 1e-4;
    } else if (k < 8) {
      g.rotation = Eigen::AngleAxisd(sign * 1e-5, Eigen::Vector3d::Unit((k - 2) / 2)) * g.rotation;
    } else {
      g.translation[(k - 8) / 2] += sign * 0.01;
    }
    EXPECT_GT(cost(g), best) << k;
  }
}

TEST(FitGeoreferenceTest, ExactDataGivesTheSimilarity) {
  const Problem p = MakeProblem(
      {-12.05, -77.04, 150}, 20, 0, [](int) { return 0.0; }, false);
  const GeoFitResult fit = FitGeoreference(p.centers, p.observations);
  EXPECT_EQ(fit.num_inliers, 20);
  EXPECT_LT(fit.rms_residual_m, 1e-6);
  EXPECT_NEAR(fit.georeference.scale / p.truth.scale, 1, 1e-9);
  EXPECT_LT(MaxCameraError(p, fit.georeference), 1e-6);
  EXPECT_LT(RotationErrorRad(fit.georeference, p.truth), 1e-9);
}

TEST(FitGeoreferenceTest, TheSameSeedGivesTheSameFit) {
  const Problem p = MakeProblem(
      {40.4, -3.7, 650}, 100, 0.2, [](int) { return 3.0; }, false);
  GeoFitOptions options;
  options.seed = 42;
  const GeoFitResult a = FitGeoreference(p.centers, p.observations, options);
  const GeoFitResult b = FitGeoreference(p.centers, p.observations, options);
  EXPECT_EQ(a.inliers, b.inliers);
  EXPECT_EQ(a.residuals_m, b.residuals_m);
  EXPECT_EQ(a.georeference.translation, b.georeference.translation);
}

// Models already in metres of a geographic frame: the fit finds scale 1 and the frame.
TEST(FitGeoreferenceTest, EcefAndEnuModelFrames) {
  const Geodetic origin{45.76, 4.84, 170};
  const GeoFrame enu_frame(GeoreferenceFromEnuModel(origin));
  std::vector<Eigen::Vector3d> ecef_centers, enu_centers;
  std::vector<GeoObservation> observations;
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d enu{Uniform(-800, 800), Uniform(-800, 800), Uniform(0, 30)};
    const Geodetic position = enu_frame.EnuToGeodetic(enu);
    enu_centers.push_back(enu);
    ecef_centers.push_back(test::Ecef(position));
    GeoObservation o;
    o.image_name = std::to_string(i);
    const Eigen::Vector3d noise{test::Normal(2), test::Normal(2), test::Normal(2)};
    o.position = enu_frame.EnuToGeodetic(enu + noise);
    observations.push_back(o);
  }
  GeoFitOptions options;
  options.default_sigma_m = 2;
  for (const bool ecef : {true, false}) {
    SCOPED_TRACE(ecef ? "ECEF" : "ENU");
    const auto& centers = ecef ? ecef_centers : enu_centers;
    const GeoFitResult fit = FitGeoreference(centers, observations, options);
    EXPECT_GE(fit.num_inliers, 95);
    EXPECT_NEAR(fit.georeference.scale, 1, 2e-3);
    EXPECT_NEAR(fit.rms_residual_m / ExpectedRms(2, fit.num_inliers), 1, 0.15);
    const Georeference reference =
        ecef ? GeoreferenceFromEcefModel(origin) : GeoreferenceFromEnuModel(origin);
    const GeoFrame fitted(fit.georeference), known(reference);
    for (size_t i = 0; i < centers.size(); ++i) {
      const Eigen::Vector3d a = fitted.GeodeticToEnu(fitted.ModelToGeodetic(centers[i]));
      const Eigen::Vector3d b = fitted.GeodeticToEnu(known.ModelToGeodetic(centers[i]));
      EXPECT_LT((a - b).norm(), 3.0) << i;
    }
    EXPECT_LT(RotationErrorRad(fit.georeference, reference), 3e-3);
  }
}

// "i<index>" (appended, not "i" + ..., which trips GCC 12's -Wrestrict false positive).
std::string Name(size_t i) {
  std::string name = "i";
  name += std::to_string(i);
  return name;
}

std::vector<GeoObservation> ObservationsAt(const std::vector<Eigen::Vector3d>& enu) {
  const GeoFrame frame(GeoreferenceFromEnuModel({30, 30, 0}));
  std::vector<GeoObservation> observations;
  for (size_t i = 0; i < enu.size(); ++i) {
    observations.push_back({Name(i), frame.EnuToGeodetic(enu[i]), 0});
  }
  return observations;
}

TEST(FitGeoreferenceTest, Errors) {
  const std::vector<Eigen::Vector3d> good_centers = {
      {0, 0, 0}, {10, 0, 0}, {0, 10, 0}, {10, 10, 1}, {5, 3, 2}};
  const auto good_positions = ObservationsAt(good_centers);

  ExpectInputError(
      [&] {
        FitGeoreference(std::span(good_centers).first(2), std::span(good_positions).first(2));
      },
      "georeference fit: 2 observations, at least 3 are needed");
  ExpectInputError([&] { FitGeoreference({}, {}); },
                   "georeference fit: 0 observations, at least 3 are needed");

  const std::vector<Eigen::Vector3d> same(5, Eigen::Vector3d(1e4, 2e4, 3));
  ExpectInputError([&] { FitGeoreference(same, good_positions); },
                   "georeference fit: the 5 camera centres coincide");
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i < 5; ++i) line.emplace_back(1e4 + i, 2e4 + 2 * i, 3 - i);
  ExpectInputError([&] { FitGeoreference(line, good_positions); },
                   "georeference fit: the 5 camera centres are collinear");

  ExpectInputError([&] { FitGeoreference(good_centers, ObservationsAt(same)); },
                   "georeference fit: the 5 observed positions coincide");
  // A straight line in ECEF is straight in every ENU frame.
  {
    const GeoFrame ecef(GeoreferenceFromEcefModel({30, 30, 0}));
    const Eigen::Vector3d start = test::Ecef({30, 30, 0}), step(3, -7, 11);
    std::vector<GeoObservation> on_a_line;
    for (int i = 0; i < 5; ++i) {
      on_a_line.push_back({Name(i), ecef.ModelToGeodetic(start + i * step), 0});
    }
    ExpectInputError([&] { FitGeoreference(good_centers, on_a_line); },
                     "georeference fit: the 5 observed positions are collinear");
  }

  // Shapes no similarity relates, with 1 cm sigmas: no three observations agree.
  {
    const std::vector<Eigen::Vector3d> centers = {
        {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {3, 1, 0}};
    const auto positions =
        ObservationsAt({{0, 0, 0}, {100, 30, 0}, {-80, 500, 3}, {20, -700, 60}, {-300, 0, 9}});
    GeoFitOptions options;
    options.default_sigma_m = 0.01;
    ExpectInputError([&] { FitGeoreference(centers, positions, options); },
                     "georeference fit: 0 of 5 observations are inliers, at least 3 are needed");
  }

  // Centres +-x, +-y and 0; positions a, a, b, b, c: the cross-covariance is exactly zero.
  {
    const std::vector<Eigen::Vector3d> centers = {
        {1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 0}};
    const Eigen::Vector3d a(0, 0, 0), b(50, 0, 0), c(0, 40, 0);
    GeoFitOptions options;
    options.default_sigma_m = 1e5;
    ExpectInputError(
        [&] {
          FitGeoreference(centers, ObservationsAt({a, a, b, b, c}), options);
        },
        "georeference fit: the fitted scale 0 is not a positive number");
  }

  {
    auto bad = good_positions;
    bad[3].position.latitude_deg = 100;
    ExpectInputError([&] { FitGeoreference(good_centers, bad); },
                     "georeference fit: image 'i3': latitude 100 is outside [-90, 90]");
    bad = good_positions;
    bad[1].sigma_m = INFINITY;
    ExpectInputError([&] { FitGeoreference(good_centers, bad); },
                     "georeference fit: image 'i1': sigma inf is not finite");
    auto centers = good_centers;
    centers[4].y() = NAN;
    ExpectInputError([&] { FitGeoreference(centers, good_positions); },
                     "georeference fit: image 'i4': the camera centre is not finite");
  }
  {
    GeoFitOptions options;
    options.default_sigma_m = 0;
    ExpectInputError([&] { FitGeoreference(good_centers, good_positions, options); },
                     "georeference fit: default_sigma_m 0 is out of range");
    options = {};
    options.confidence = 1;
    ExpectInputError([&] { FitGeoreference(good_centers, good_positions, options); },
                     "georeference fit: confidence 1 is out of range");
    options = {};
    options.inlier_sigmas = -1;
    ExpectInputError([&] { FitGeoreference(good_centers, good_positions, options); },
                     "georeference fit: inlier_sigmas -1 is out of range");
    options = {};
    options.max_iterations = 0;
    ExpectInputError([&] { FitGeoreference(good_centers, good_positions, options); },
                     "georeference fit: max_iterations 0 is out of range");
  }
  EXPECT_THROW(FitGeoreference(good_centers, std::span(good_positions).first(4)),
               std::invalid_argument);
}

class ReadGeorefFileTest : public testing::Test {
 protected:
  std::filesystem::path Write(const std::string& text) {
    const auto path = dir_ / "georef.txt";
    std::ofstream(path) << text;
    return path;
  }
  void ExpectError(const std::string& text, const std::string& message) {
    const auto path = Write(text);
    ExpectInputError([&] { ReadGeorefFile(path); }, path.string() + message);
  }
  test::TempDir dir_;
};

TEST_F(ReadGeorefFileTest, ReadsLinesCommentsAndSigmas) {
  const auto path = Write(
      "# IMAGE_NAME LAT LON HEIGHT [SIGMA_M]\n"
      "\n"
      "a.jpg 52.518916667 13.400294444 27\n"
      "  sub/b.jpg\t-33.5 +151.25 -12.5e1 2.5  \r\n"
      "   # indented comment\n"
      "c.png 90 359.5 0 0.1");  // no final newline
  const auto observations = ReadGeorefFile(path);
  ASSERT_EQ(observations.size(), 3u);
  EXPECT_EQ(observations[0].image_name, "a.jpg");
  EXPECT_EQ(observations[0].position.latitude_deg, 52.518916667);
  EXPECT_EQ(observations[0].position.longitude_deg, 13.400294444);
  EXPECT_EQ(observations[0].position.height_m, 27);
  EXPECT_EQ(observations[0].sigma_m, 0);
  EXPECT_EQ(observations[1].image_name, "sub/b.jpg");
  EXPECT_EQ(observations[1].position.latitude_deg, -33.5);
  EXPECT_EQ(observations[1].position.longitude_deg, 151.25);
  EXPECT_EQ(observations[1].position.height_m, -125);
  EXPECT_EQ(observations[1].sigma_m, 2.5);
  EXPECT_EQ(observations[2].image_name, "c.png");
  EXPECT_EQ(observations[2].position.longitude_deg, 359.5);
  EXPECT_EQ(observations[2].sigma_m, 0.1);
}

TEST_F(ReadGeorefFileTest, ErrorsNameTheFileTheLineAndTheField) {
  ExpectError("a.jpg 52.5 x13.4 27\n", ":1: LON: expected a finite number, found 'x13.4'");
  ExpectError("# c\na.jpg 52.5 13.4 27m\n", ":2: HEIGHT: expected a finite number, found '27m'");
  ExpectError("a.jpg nan 13.4 27\n", ":1: LAT: expected a finite number, found 'nan'");
  ExpectError("a.jpg 52.5 13.4 27 inf\n", ":1: SIGMA_M: expected a finite number, found 'inf'");
  ExpectError("a.jpg 52.5 13.4\n",
              ":1: missing field HEIGHT (expected IMAGE_NAME LAT LON HEIGHT [SIGMA_M])");
  ExpectError("a.jpg\n", ":1: missing field LAT (expected IMAGE_NAME LAT LON HEIGHT [SIGMA_M])");
  ExpectError("a.jpg 52.5 13.4 27 3 extra\n",
              ":1: extra field 'extra' (expected IMAGE_NAME LAT LON HEIGHT [SIGMA_M])");
  ExpectError("a.jpg 90.5 13.4 27\n", ":1: LAT: 90.5 is outside [-90, 90]");
  ExpectError("a.jpg -91 13.4 27\n", ":1: LAT: -91 is outside [-90, 90]");
  ExpectError("a.jpg 52.5 360 27\n", ":1: LON: 360 is outside [-180, 360)");
  ExpectError("a.jpg 52.5 -180.1 27\n", ":1: LON: -180.1 is outside [-180, 360)");
  ExpectError("a.jpg 52.5 13.4 27 0\n", ":1: SIGMA_M: 0 is not positive");
  ExpectError("a.jpg 52.5 13.4 27 -2\n", ":1: SIGMA_M: -2 is not positive");
  ExpectError("a.jpg 52.5 13.4 27\nb.jpg 1 2 3\n\na.jpg 52.5 13.4 28\n",
              ":4: duplicate IMAGE_NAME 'a.jpg' (also on line 1)");
  ExpectError("", ": no observations (expected IMAGE_NAME LAT LON HEIGHT [SIGMA_M])");
  ExpectError("# only a comment\n\n",
              ": no observations (expected IMAGE_NAME LAT LON HEIGHT [SIGMA_M])");
}

TEST_F(ReadGeorefFileTest, MissingFile) {
  const auto path = dir_ / "absent.txt";
  ExpectInputError([&] { ReadGeorefFile(path); }, path.string() + ": cannot open");
}

}  // namespace
}  // namespace cwloc
