#include "indexer/covariance_calibration.h"

#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "base/chi_square.h"
#include "base/parallel_for.h"
#include "base/progress.h"
#include "camera/camera_models.h"
#include "format/index.h"
#include "geo/index_georeference.h"
#include "localizer/localizer.h"
#include "localizer/pose/refine_pose.h"

namespace cwloc {
namespace {

constexpr std::array<Calibration, 3> kModes = {Calibration::kKnown, Calibration::kFocalPrior,
                                               Calibration::kUnknown};

// Normalised squared errors e^T S^-1 e of a localized sample's rotation and centre.
struct SampleError {
  double rotation = 0;
  double position = 0;
  bool wrong = false;  // a gross failure, which no covariance describes
};

// Row k of `samples` images evenly spread over `num_images`.
std::vector<uint32_t> SampledImages(size_t num_images, uint32_t samples) {
  const size_t n = std::min<size_t>(num_images, samples);
  std::vector<uint32_t> rows(n);
  for (size_t k = 0; k < n; ++k)
    rows[k] = static_cast<uint32_t>((2 * k + 1) * num_images / (2 * n));
  return rows;
}

// The folds' work files, next to the output (so a killed build's are removed by the next
// writer of that output: RemoveDeadWritersTemporaries), removed on every way out.
class ScratchFolder {
 public:
  explicit ScratchFolder(const std::filesystem::path& output)
      : path_(output.string() + ".tmp-" + std::to_string(::getpid()) + "-calibration") {
    std::filesystem::create_directories(path_);
  }
  ~ScratchFolder() {
    std::error_code ignored;
    std::filesystem::remove_all(path_, ignored);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

QueryCamera SampleCamera(const IndexCamera& camera, Calibration mode) {
  const std::vector<double> params(camera.params, camera.params + camera.num_params);
  const auto model = static_cast<CameraModelId>(camera.model_id);
  switch (mode) {
    case Calibration::kKnown:
      return {model,  camera.width,        camera.height,
              params, Calibration::kKnown, IntrinsicsSource::kDatabase};
    case Calibration::kFocalPrior:
      return FocalPriorCamera(MeanFocalLength(model, params), camera.width, camera.height,
                              IntrinsicsSource::kDatabase);
    case Calibration::kUnknown:
      break;
  }
  return UnknownFocalCamera(camera.width, camera.height, IntrinsicsSource::kDatabase);
}

// The left-out image's own features, as a query reads them from the database.
Query SampleQuery(const ModelViews& views, const IndexImage& image,
                  const colmap::DatabaseReader& database) {
  Query query;
  query.name = std::string(views.ImageName(image));
  query.source = database.path().string() + ": image '" + query.name + "'";
  colmap::ImageFeatures features = database.ReadFeatures(image.image_id);
  query.keypoints = colmap::KeypointPositions(features.keypoints);
  query.descriptors = std::move(features.descriptors.data);
  return query;
}

std::optional<SampleError> NormalisedError(const LocalizationResult& result,
                                           const IndexImage& truth) {
  if (!result.success || !result.covariance) return std::nullopt;
  const auto quaternion = [](const double* q) {
    return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  };
  const Eigen::Matrix3d true_rotation = quaternion(truth.cam_from_world_rotation);
  const Eigen::Matrix3d rotation = quaternion(result.rotation.data());
  // world_from_cam_estimate = exp([theta]x) world_from_cam_true (refine_pose.h).
  const Eigen::AngleAxisd turn(rotation.transpose() * true_rotation);
  const Eigen::Vector3d theta = turn.angle() * turn.axis();
  if (turn.angle() > kCalibrationWrongPoseDeg * M_PI / 180.0) return SampleError{0, 0, true};
  const Eigen::Vector3d offset = Eigen::Vector3d(result.center.data()) - CameraCenterOf(truth);
  const Eigen::Matrix<double, 6, 6> pose = PoseBlock(*result.covariance);
  const Eigen::LDLT<Eigen::Matrix3d> rotation_block(pose.topLeftCorner<3, 3>());
  const Eigen::LDLT<Eigen::Matrix3d> position_block(pose.bottomRightCorner<3, 3>());
  if (rotation_block.info() != Eigen::Success || position_block.info() != Eigen::Success)
    return std::nullopt;
  return SampleError{theta.dot(rotation_block.solve(theta)),
                     offset.dot(position_block.solve(offset))};
}

// The scale that puts a new query's error inside the 95 % region as often as the samples say:
// a new value falls below the k-th smallest of n samples with probability k / (n + 1), for any
// distribution, so k = ceil(0.95 (n + 1)), at most n (the largest: n / (n + 1) for n < 19).
// Over chi2(3)'s 95 % quantile, at least 1.
double Scale(std::vector<double> squared_errors) {
  std::sort(squared_errors.begin(), squared_errors.end());
  const size_t n = squared_errors.size();
  const size_t k = std::min(n, static_cast<size_t>(std::ceil(0.95 * double(n + 1))));
  return std::max(1.0, squared_errors[k - 1] / kChiSquare3Dof95);
}

double Median(std::vector<double> values) {
  std::sort(values.begin(), values.end());
  const size_t n = values.size();
  return n % 2 == 1 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
}

}  // namespace

CovarianceCalibration CalibrateCovariance(const ModelViews& views,
                                          const std::string& clustering_method,
                                          const colmap::DatabaseReader& database,
                                          const IndexBuildOptions& options) {
  const std::vector<uint32_t> samples =
      SampledImages(views.images.size(), options.calibration_samples);
  const size_t fold_size =
      std::max<size_t>({1, static_cast<size_t>(kCalibrationFoldShare * double(views.images.size())),
                        (samples.size() + kCalibrationMaxFolds - 1) / kCalibrationMaxFolds});
  const size_t num_folds = (samples.size() + fold_size - 1) / fold_size;
  const int threads = ResolveThreads(options.threads);
  const bool coded = options.code_bytes != 0;

  IndexBuildOptions fold_options = options;
  fold_options.calibration_samples = 0;
  std::array<std::vector<SampleError>, kModes.size()> errors;
  std::array<uint32_t, kModes.size()> wrong{};
  std::mutex errors_mutex;
  const ScratchFolder scratch(options.output_path);
  Progress progress("covariance calibration", samples.size());
  for (size_t fold = 0; fold < num_folds; ++fold) {
    // Sample k goes to fold k % num_folds: a fold's images lie apart, as queries do.
    std::vector<bool> left_out(views.images.size(), false);
    std::vector<uint32_t> fold_images;
    for (size_t k = fold; k < samples.size(); k += num_folds) {
      left_out[samples[k]] = true;
      fold_images.push_back(samples[k]);
    }
    ModelViews rest = WithoutImages(views, left_out);
    if (rest.num_views() == 0 || (coded && rest.points.size() < DescriptorCodes::kCentroids)) {
      progress.Advance(fold_images.size());
      continue;
    }
    const std::filesystem::path fold_path = scratch.path() / "fold.cwl";
    {
      const Progress::Silence quiet;
      Clustering clustering{{}, 0, clustering_method};
      for (const IndexImage& image : rest.images) {
        clustering.cluster_of_image.push_back(image.cluster);
        clustering.num_clusters = std::max(clustering.num_clusters, image.cluster + 1);
      }
      const CovisibilityGraph graph =
          BuildCovisibilityGraph(rest.images, rest.points, rest.tracks, rest.view_points, threads);
      IndexBuildReport ignored;
      WriteIndexOfViews(std::move(rest), clustering, graph, fold_options, nullptr, nullptr, {},
                        fold_path, &ignored);
    }
    const Index index = Index::Open(fold_path);
    const Localizer localizer(index);
    const LocalizerOptions localizer_options;
    std::vector<Query> queries;  // read here: the database reader is not thread-safe
    for (const uint32_t row : fold_images)
      queries.push_back(SampleQuery(views, views.images[row], database));
    ParallelFor(fold_images.size() * kModes.size(), threads, [&](size_t item) {
      const IndexImage& image = views.images[fold_images[item / kModes.size()]];
      const size_t mode = item % kModes.size();
      Query query = queries[item / kModes.size()];
      query.camera = SampleCamera(views.cameras[image.camera_index], kModes[mode]);
      const std::optional<SampleError> error =
          NormalisedError(localizer.Localize(query, localizer_options), image);
      std::lock_guard lock(errors_mutex);
      if (error && error->wrong) ++wrong[mode];
      if (error && !error->wrong) errors[mode].push_back(*error);
      if (mode + 1 == kModes.size()) progress.Advance();
    });
  }
  progress.Finish();

  CovarianceCalibration calibration;
  IndexCovarianceCalibration& section = calibration.section;
  section.sampled = static_cast<uint32_t>(samples.size());
  nlohmann::ordered_json modes;
  for (size_t mode = 0; mode < kModes.size(); ++mode) {
    const std::vector<SampleError>& mode_errors = errors[mode];
    section.localized[mode] = static_cast<uint32_t>(mode_errors.size());
    nlohmann::ordered_json entry = {{"localized", mode_errors.size()}, {"wrong", wrong[mode]}};
    if (mode_errors.size() >= kCalibrationMinLocalized) {
      std::vector<double> rotation, position;
      for (const SampleError& error : mode_errors) {
        rotation.push_back(error.rotation);
        position.push_back(error.position);
      }
      section.rotation_scale[mode] = static_cast<float>(Scale(rotation));
      section.position_scale[mode] = static_cast<float>(Scale(position));
      entry["rotation_scale"] = section.rotation_scale[mode];
      entry["position_scale"] = section.position_scale[mode];
      entry["median_rotation_d2"] = Median(rotation);
      entry["median_position_d2"] = Median(position);
    }
    modes[std::string(NameOf(kModes[mode]))] = std::move(entry);
  }
  calibration.manifest = {{"method", "leave-one-out"},
                          {"sampled_images", samples.size()},
                          {"folds", num_folds},
                          {"modes", std::move(modes)}};
  return calibration;
}

}  // namespace cwloc
