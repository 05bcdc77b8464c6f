#pragma once

#include <nlohmann/json.hpp>

#include "colmap/database.h"
#include "format/index_sections.h"
#include "indexer/index_builder.h"
#include "indexer/model_views.h"

namespace cwloc {

// The pose covariance knows the keypoints' noise only; on real captures the SfM points' own
// errors and the ground truth's make it too small by a factor that differs between models and
// between calibration modes. The build measures that factor on the model itself: sampled model
// images are left out (WithoutImages, as `colmap image_deleter` takes queries out of a full
// model), the rest is indexed as the build indexes the whole, and each left-out image is
// localized from its own database features, once per calibration mode (its model camera
// known; its focal length as a prior; only its size), and compared with its SfM pose. Per mode
// and per block (rotation, centre), the scale is an order statistic of the normalised squared
// errors e^T S^-1 e (the one a new query stays below with probability 0.95, or the largest)
// over chi2(3)'s 95 % quantile, at least 1 (docs/algorithm.md, "Pose uncertainty").
struct CovarianceCalibration {
  IndexCovarianceCalibration section{};
  nlohmann::ordered_json manifest;  // the manifest's "covariance_calibration" object
};

// A fold leaves out up to this share of the model's images (at least one), so that what a
// left-out image is localized against is nearly the model a query meets; a small model's
// samples are spread over at most kCalibrationMaxFolds folds (each is an index build).
inline constexpr double kCalibrationFoldShare = 0.05;
inline constexpr size_t kCalibrationMaxFolds = 10;
// A mode's scales are stored only when at least this many of its samples localized.
inline constexpr uint32_t kCalibrationMinLocalized = 5;
// A sample localized this far from its SfM orientation is a wrong pose, counted apart: no
// covariance describes a gross failure, and one would set the scale alone.
inline constexpr double kCalibrationWrongPoseDeg = 5.0;

// options.calibration_samples images, evenly spread over the model's, in folds of at most
// kCalibrationFoldShare of the images; each fold's index is written next to
// options.output_path and removed. Throws InputError for a database that lacks a sampled
// image's features.
// `views` hold the model's clusters, made by `clustering_method`; a fold keeps them.
CovarianceCalibration CalibrateCovariance(const ModelViews& views,
                                          const std::string& clustering_method,
                                          const colmap::DatabaseReader& database,
                                          const IndexBuildOptions& options);

}  // namespace cwloc
