#include "geo/georeference_fit.h"

#include <Eigen/SVD>
#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string_view>
#include <unordered_map>

#include "base/bounded_file.h"
#include "base/error.h"
#include "base/option_value.h"
#include "robust/ransac.h"

namespace cwloc {
namespace {

constexpr char kExpectedFields[] = "(expected IMAGE_NAME LAT LON HEIGHT [SIGMA_M])";

// A point set is collinear when its second principal spread is below this fraction of the
// first (singular values of the centred coordinates).
constexpr double kCollinearRatio = 1e-6;
// Camera centres coincide when their RMS spread is below this fraction of their largest
// coordinate magnitude (SfM units have no scale of their own); positions when it is below
// kCoincidentPositionsM metres.
constexpr double kCoincidentCentresRatio = 1e-9;
constexpr double kCoincidentPositionsM = 1e-3;
// Least squares and re-scoring alternate until the inlier set is stable, at most this often.
constexpr int kMaxRefinementRounds = 10;

bool IsSpace(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f' || c == '\n';
}

std::string Shorten(std::string_view s) {
  return s.size() <= 40 ? std::string(s) : std::string(s.substr(0, 40)) + "...";
}

std::vector<std::string_view> SplitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && IsSpace(line[i])) ++i;
    const size_t begin = i;
    while (i < line.size() && !IsSpace(line[i])) ++i;
    if (i > begin) fields.push_back(line.substr(begin, i - begin));
  }
  return fields;
}

// A finite decimal number taking the whole token (a leading '+' allowed); nullopt otherwise.
std::optional<double> ParseNumber(std::string_view token) {
  if (token.size() > 1 && token[0] == '+' && token[1] != '-') token.remove_prefix(1);
  double value = 0;
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  if (result.ec != std::errc() || result.ptr != token.data() + token.size() ||
      !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

// The 3D similarity enu = scale * rotation * model + translation.
struct Similarity {
  double scale = 1;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d operator()(const Eigen::Vector3d& x) const {
    return scale * (rotation * x) + translation;
  }
};

// Weighted Umeyama (1991): the similarity minimizing sum w_i |y_i - (s R x_i + t)|^2 over the
// given indices, in closed form. With weighted centroids and the weighted cross-covariance
// C = U D V^T of the centred points, R = U S V^T where S = diag(1, 1, det(U V^T)) keeps R a
// rotation (no reflection), s = trace(D S) / (weighted variance of x), t = mean_y - s R mean_x.
Similarity WeightedUmeyama(std::span<const Eigen::Vector3d> x, std::span<const Eigen::Vector3d> y,
                           std::span<const double> w, std::span<const size_t> indices) {
  double total = 0;
  Eigen::Vector3d mean_x = Eigen::Vector3d::Zero(), mean_y = Eigen::Vector3d::Zero();
  for (size_t i : indices) {
    total += w[i];
    mean_x += w[i] * x[i];
    mean_y += w[i] * y[i];
  }
  mean_x /= total;
  mean_y /= total;
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  double variance_x = 0;
  for (size_t i : indices) {
    const Eigen::Vector3d dx = x[i] - mean_x, dy = y[i] - mean_y;
    covariance += w[i] * dy * dx.transpose();
    variance_x += w[i] * dx.squaredNorm();
  }
  covariance /= total;
  variance_x /= total;

  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(covariance,
                                              Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Vector3d s(1, 1, 1);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0) s.z() = -1;
  Similarity result;
  result.rotation = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  result.scale = svd.singularValues().dot(s) / variance_x;
  result.translation = mean_y - result.scale * (result.rotation * mean_x);
  return result;
}

enum class Degeneracy { kNone, kCoincident, kCollinear };

// Whether the points at `indices` coincide or lie on a line: singular values of the centred
// coordinates (RMS spread below `coincident_spread`; second below kCollinearRatio of the first),
// as the square roots of the 3 x 3 scatter matrix's: its squared ratios stay far above double
// precision, and an SVD of the N x 3 matrix instantiates Eigen's QR preconditioners, which
// took this file 80 s of every build's compile time.
Degeneracy Classify(std::span<const Eigen::Vector3d> points, std::span<const size_t> indices,
                    double coincident_spread) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (size_t i : indices) mean += points[i];
  mean /= static_cast<double>(indices.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (size_t i : indices) scatter += (points[i] - mean) * (points[i] - mean).transpose();
  const Eigen::Vector3d singular =
      Eigen::JacobiSVD<Eigen::Matrix3d>(scatter).singularValues().cwiseSqrt();
  if (!(singular[0] / std::sqrt(static_cast<double>(indices.size())) > coincident_spread)) {
    return Degeneracy::kCoincident;
  }
  if (!(singular[1] > kCollinearRatio * singular[0])) return Degeneracy::kCollinear;
  return Degeneracy::kNone;
}

double CoincidentCentresSpread(std::span<const Eigen::Vector3d> centres,
                               std::span<const size_t> indices) {
  double magnitude = 0;
  for (size_t i : indices) magnitude = std::max(magnitude, centres[i].lpNorm<Eigen::Infinity>());
  return kCoincidentCentresRatio * magnitude;
}

// Throws when the centres or the positions at `indices` are degenerate; `what` names the set
// ("5 camera centres", "camera centres of the 4 inliers").
void CheckNotDegenerate(std::span<const Eigen::Vector3d> centres,
                        std::span<const Eigen::Vector3d> positions, std::span<const size_t> indices,
                        const std::string& centres_name, const std::string& positions_name) {
  const auto fail = [](const std::string& name, Degeneracy degeneracy) {
    throw InputError("georeference fit: the " + name +
                     (degeneracy == Degeneracy::kCoincident ? " coincide" : " are collinear"));
  };
  const Degeneracy c = Classify(centres, indices, CoincidentCentresSpread(centres, indices));
  if (c != Degeneracy::kNone) fail(centres_name, c);
  const Degeneracy p = Classify(positions, indices, kCoincidentPositionsM);
  if (p != Degeneracy::kNone) fail(positions_name, p);
}

// Lat/lon of the mean ECEF position (robust across the antimeridian and at the poles), and the
// mean height.
Geodetic GeodeticCentroid(std::span<const GeoObservation> observations,
                          std::span<const size_t> indices) {
  const GeographicLib::Geocentric& earth = GeographicLib::Geocentric::WGS84();
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double height = 0;
  for (size_t i : indices) {
    const Geodetic& g = observations[i].position;
    Eigen::Vector3d ecef = Eigen::Vector3d::Zero();
    earth.Forward(g.latitude_deg, g.longitude_deg, g.height_m, ecef.x(), ecef.y(), ecef.z());
    sum += ecef;
    height += g.height_m;
  }
  const double n = static_cast<double>(indices.size());
  const Eigen::Vector3d mean = sum / n;
  Geodetic centroid;
  double ignored_height = 0;
  earth.Reverse(mean.x(), mean.y(), mean.z(), centroid.latitude_deg, centroid.longitude_deg,
                ignored_height);
  centroid.height_m = height / n;
  return centroid;
}

bool Plausible(const Similarity& model) {
  return std::isfinite(model.scale) && model.scale > 0 && model.rotation.allFinite() &&
         model.translation.allFinite();
}

// The fit as a RANSAC problem (robust/ransac.h): a similarity from each non-degenerate
// 3-sample of camera centres and positions, scored by the MSAC cost of the residuals in sigmas.
// No local optimisation inside RANSAC: the weighted least squares on the inliers follows it.
class SimilarityEstimator {
 public:
  using Model = Similarity;
  static constexpr size_t kSampleSize = 3;

  SimilarityEstimator(std::span<const Eigen::Vector3d> centres,
                      std::span<const Eigen::Vector3d> positions, std::span<const double> weight,
                      std::span<const double> sigma, double threshold)
      : centres_(centres),
        positions_(positions),
        weight_(weight),
        sigma_(sigma),
        threshold_(threshold) {}

  size_t NumData() const { return centres_.size(); }

  void GenerateModels(std::span<const uint32_t> sample, std::vector<Similarity>* models) const {
    const std::array<size_t, 3> indices = {sample[0], sample[1], sample[2]};
    if (Classify(centres_, indices, CoincidentCentresSpread(centres_, indices)) !=
            Degeneracy::kNone ||
        Classify(positions_, indices, kCoincidentPositionsM) != Degeneracy::kNone) {
      return;
    }
    const Similarity model = WeightedUmeyama(centres_, positions_, weight_, indices);
    if (Plausible(model)) models->push_back(model);
  }

  // The MSAC cost: residuals in sigmas, squared and truncated at the threshold; inliers are the
  // residuals within it. A handful of observations: scored in full whatever the bound.
  double Score(const Similarity& model, uint32_t* num_inliers, double /*bound*/) const {
    double cost = 0;
    *num_inliers = 0;
    for (size_t i = 0; i < centres_.size(); ++i) {
      const double r = Residual(model, i);
      if (r <= threshold_) ++*num_inliers;
      cost += std::min(r * r, threshold_ * threshold_);
    }
    return cost;
  }

  // Per observation: whether it is an inlier of `model`.
  void FlagInliers(const Similarity& model, std::vector<char>* inliers) const {
    for (size_t i = 0; i < centres_.size(); ++i) (*inliers)[i] = Residual(model, i) <= threshold_;
  }

  void Refine(Similarity*) const {}  // never called: RansacOptions::max_refinements = 0

 private:
  double Residual(const Similarity& model, size_t i) const {
    return (model(centres_[i]) - positions_[i]).norm() / sigma_[i];
  }

  std::span<const Eigen::Vector3d> centres_, positions_;
  std::span<const double> weight_, sigma_;
  double threshold_;
};

static_assert(RansacEstimator<SimilarityEstimator>);

// Throws InputError for an option out of its range.
void CheckFitOptions(const GeoFitOptions& options) {
  const auto check_option = [](bool ok, const char* option, double value) {
    if (!ok) {
      throw InputError(std::string("georeference fit: ") + option + " " + NumberText(value) +
                       " is out of range");
    }
  };
  check_option(std::isfinite(options.default_sigma_m) && options.default_sigma_m > 0,
               "default_sigma_m", options.default_sigma_m);
  check_option(std::isfinite(options.inlier_sigmas) && options.inlier_sigmas > 0, "inlier_sigmas",
               options.inlier_sigmas);
  check_option(options.max_iterations >= 1, "max_iterations", options.max_iterations);
  check_option(options.confidence > 0 && options.confidence < 1, "confidence", options.confidence);
}

// Weighted least squares on the inliers, re-scored, until the inlier set is stable (or
// kMaxRefinementRounds): the last fit, and in `fitted` the inliers it was fitted to.
Similarity FitToInliers(std::span<const Eigen::Vector3d> model_centers,
                        std::span<const Eigen::Vector3d> positions, std::span<const double> weight,
                        const SimilarityEstimator& estimator, std::vector<char> inliers,
                        std::vector<char>* fitted) {
  const size_t n = inliers.size();
  const std::string count = std::to_string(n);
  Similarity model;
  for (int round = 0; round < kMaxRefinementRounds; ++round) {
    *fitted = inliers;
    std::vector<size_t> indices;
    for (size_t i = 0; i < n; ++i) {
      if ((*fitted)[i]) indices.push_back(i);
    }
    if (indices.size() < 3) {
      throw InputError("georeference fit: " + std::to_string(indices.size()) + " of " + count +
                       " observations are inliers, at least 3 are needed");
    }
    const std::string inlier_count = std::to_string(indices.size());
    CheckNotDegenerate(model_centers, positions, indices,
                       "camera centres of the " + inlier_count + " inliers",
                       "observed positions of the " + inlier_count + " inliers");
    model = WeightedUmeyama(model_centers, positions, weight, indices);
    if (!std::isfinite(model.scale) || !(model.scale > 0)) {
      throw InputError("georeference fit: the fitted scale " + NumberText(model.scale) +
                       " is not a positive number");
    }
    estimator.FlagInliers(model, &inliers);
    if (inliers == *fitted) break;
  }
  return model;
}

}  // namespace

std::vector<GeoObservation> ReadGeorefFile(const std::filesystem::path& path) {
  const std::string name = path.string();
  CheckInputFile(path, kGeorefFile);  // /dev/zero and the like, before streaming starts
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot open");
  std::vector<GeoObservation> observations;
  std::unordered_map<std::string, size_t> line_of_name;
  std::string line;
  size_t line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    const std::string where = name + ":" + std::to_string(line_number) + ": ";
    const std::vector<std::string_view> fields = SplitFields(line);
    if (fields.empty() || fields[0].front() == '#') continue;
    static constexpr const char* kNames[] = {"IMAGE_NAME", "LAT", "LON", "HEIGHT", "SIGMA_M"};
    if (fields.size() < 4) {
      throw InputError(where + "missing field " + kNames[fields.size()] + " " + kExpectedFields);
    }
    if (fields.size() > 5) {
      throw InputError(where + "extra field '" + Shorten(fields[5]) + "' " + kExpectedFields);
    }
    double values[4] = {0, 0, 0, 0};
    for (size_t f = 1; f < fields.size(); ++f) {
      const auto value = ParseNumber(fields[f]);
      if (!value) {
        throw InputError(where + kNames[f] + ": expected a finite number, found '" +
                         Shorten(fields[f]) + "'");
      }
      values[f - 1] = *value;
    }
    GeoObservation observation;
    observation.image_name = std::string(fields[0]);
    observation.position = {values[0], values[1], values[2]};
    if (values[0] < -90 || values[0] > 90) {
      throw InputError(where + "LAT: " + std::string(fields[1]) + " is outside [-90, 90]");
    }
    if (values[1] < -180 || values[1] >= 360) {
      throw InputError(where + "LON: " + std::string(fields[2]) + " is outside [-180, 360)");
    }
    if (fields.size() == 5) {
      if (!(values[3] > 0)) {
        throw InputError(where + "SIGMA_M: " + std::string(fields[4]) + " is not positive");
      }
      observation.sigma_m = values[3];
    }
    const auto [it, inserted] = line_of_name.emplace(observation.image_name, line_number);
    if (!inserted) {
      throw InputError(where + "duplicate IMAGE_NAME '" + Shorten(observation.image_name) +
                       "' (also on line " + std::to_string(it->second) + ")");
    }
    observations.push_back(std::move(observation));
  }
  if (in.bad()) throw InputError(name + ": read error after line " + std::to_string(line_number));
  if (observations.empty()) {
    throw InputError(name + ": no observations " + std::string(kExpectedFields));
  }
  return observations;
}

GeoFitResult FitGeoreference(std::span<const Eigen::Vector3d> model_centers,
                             std::span<const GeoObservation> observations,
                             const GeoFitOptions& options) {
  if (model_centers.size() != observations.size()) {
    throw std::invalid_argument("FitGeoreference: " + std::to_string(model_centers.size()) +
                                " camera centres for " + std::to_string(observations.size()) +
                                " observations");
  }
  CheckFitOptions(options);

  const size_t n = observations.size();
  if (n < 3) {
    throw InputError("georeference fit: " + std::to_string(n) +
                     " observations, at least 3 are needed");
  }
  std::vector<double> sigma(n), weight(n);
  for (size_t i = 0; i < n; ++i) {
    const GeoObservation& o = observations[i];
    const std::string what = "georeference fit: image '" + o.image_name + "'";
    if (!model_centers[i].allFinite()) throw InputError(what + ": the camera centre is not finite");
    ValidateGeodetic(o.position, what);
    if (std::isnan(o.sigma_m) || std::isinf(o.sigma_m)) {
      throw InputError(what + ": sigma " + NumberText(o.sigma_m) + " is not finite");
    }
    sigma[i] = o.sigma_m > 0 ? o.sigma_m : options.default_sigma_m;
    weight[i] = 1 / (sigma[i] * sigma[i]);
  }

  std::vector<size_t> all(n);
  for (size_t i = 0; i < n; ++i) all[i] = i;
  const std::string count = std::to_string(n);

  // The positions in metres east, north and up of their geodetic centroid.
  const Geodetic first_origin = GeodeticCentroid(observations, all);
  const GeographicLib::LocalCartesian first_enu(first_origin.latitude_deg,
                                                first_origin.longitude_deg, first_origin.height_m,
                                                GeographicLib::Geocentric::WGS84());
  std::vector<Eigen::Vector3d> positions(n, Eigen::Vector3d::Zero());
  for (size_t i = 0; i < n; ++i) {
    const Geodetic& g = observations[i].position;
    first_enu.Forward(g.latitude_deg, g.longitude_deg, g.height_m, positions[i].x(),
                      positions[i].y(), positions[i].z());
  }
  CheckNotDegenerate(model_centers, positions, all, count + " camera centres",
                     count + " observed positions");

  // RANSAC over 3-point samples, adaptive in the number of iterations.
  const SimilarityEstimator estimator(model_centers, positions, weight, sigma,
                                      options.inlier_sigmas);
  RansacOptions ransac;
  ransac.min_iterations = 0;
  ransac.max_iterations = static_cast<uint32_t>(options.max_iterations);
  ransac.confidence = options.confidence;
  ransac.max_refinements = 0;
  Similarity best;
  std::vector<char> inliers(n, 0);
  if (std::isfinite(Ransac(estimator, ransac, RansacRun{options.seed, {}}, &best).score))
    estimator.FlagInliers(best, &inliers);

  std::vector<char> fitted;
  const Similarity model =
      FitToInliers(model_centers, positions, weight, estimator, std::move(inliers), &fitted);

  // The ENU origin moves to the inliers' geodetic centroid: y2 = M y1 + p, with M the rotation
  // from the first ENU frame to the final one and p the first origin in the final frame.
  std::vector<size_t> inlier_indices;
  for (size_t i = 0; i < n; ++i) {
    if (fitted[i]) inlier_indices.push_back(i);
  }
  GeoFitResult result;
  result.georeference.origin = GeodeticCentroid(observations, inlier_indices);
  const Geodetic& o2 = result.georeference.origin;
  const GeographicLib::LocalCartesian final_enu(o2.latitude_deg, o2.longitude_deg, o2.height_m,
                                                GeographicLib::Geocentric::WGS84());
  std::vector<double> m(9);
  Eigen::Vector3d p = Eigen::Vector3d::Zero();
  final_enu.Forward(first_origin.latitude_deg, first_origin.longitude_deg, first_origin.height_m,
                    p.x(), p.y(), p.z(), m);
  Eigen::Matrix3d final_from_first;
  final_from_first << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  result.georeference.scale = model.scale;
  result.georeference.rotation = Eigen::Quaterniond(final_from_first * model.rotation).normalized();
  result.georeference.translation = final_from_first * model.translation + p;

  result.inliers = fitted;
  result.residuals_m.resize(n);
  double sum_squares = 0;
  for (size_t i = 0; i < n; ++i) {
    const Geodetic& g = observations[i].position;
    Eigen::Vector3d y = Eigen::Vector3d::Zero();
    final_enu.Forward(g.latitude_deg, g.longitude_deg, g.height_m, y.x(), y.y(), y.z());
    result.residuals_m[i] = (result.georeference.ModelToEnu(model_centers[i]) - y).norm();
    if (fitted[i]) sum_squares += result.residuals_m[i] * result.residuals_m[i];
  }
  result.num_inliers = static_cast<int>(inlier_indices.size());
  result.rms_residual_m = std::sqrt(sum_squares / static_cast<double>(result.num_inliers));
  return result;
}

}  // namespace cwloc
