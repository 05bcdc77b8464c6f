#pragma once

#include <optional>

#include "format/index.h"
#include "localizer/geo_priors.h"
#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/pose_guide.h"
#include "localizer/query.h"
#include "results/localization_result.h"

namespace cwloc {

// A frame whose pose is predicted from the frames before it (tracker.h). Localize then matches
// the frame only near where the model's points project under the prediction (guided
// back-matching, no forward matching), first in the clusters that see `seen_points`, the
// previous frame's inlier points, and fits the pose to those matches as usual.
struct FramePrediction {
  PoseHypothesis hypothesis;
  std::vector<uint32_t> seen_points;  // rows of the index's points
  double radius_px = 0;               // query features this near a projection compete
  // Instead, first the clusters of the model images whose cameras are nearest the predicted
  // one (centres over the median depth of `seen_points`, and viewing directions).
  bool nearest_images_first = false;
  // Or only these views, each matched once (no clusters, no votes).
  std::vector<uint32_t> views;
  // Back-matching goes on to the next cluster until it has at least this many matches (when
  // more than LocalizerOptions::back_matches).
  uint32_t min_back_matches = 0;
};

// Localizes queries against one index. Construction is O(images); Localize is const and
// thread-safe, so one Localizer serves every thread of a batch.
class Localizer {
 public:
  explicit Localizer(const Index& index);

  // The pipeline: the query is checked, the matcher yields 2D-3D correspondences, the pose
  // stage fits them. Throws InputError naming the query for one that cannot be processed at
  // all (no features, an unusable camera); a query that simply fails to localize returns
  // success = false with the reason.
  // With a prediction, the frame is matched near it instead (FramePrediction). With
  // `correspondences`, what the pose stage was given goes there too: for a rig, which fits one
  // pose to its images', and for tools that fit them with another estimator
  // (bench/cross_estimation.sh).
  LocalizationResult Localize(const Query& query, const LocalizerOptions& options,
                              const FramePrediction* prediction = nullptr,
                              std::vector<FeatureMatch>* correspondences = nullptr) const;

  // The part of Localize's check that concerns the query's priors: a latitude in [-90, 90], a
  // finite longitude and height, a positive radius, a non-zero gravity, and a georeferenced
  // index for either. Throws InputError naming the query. (The API calls it first, so that a
  // bad prior is the caller's argument rather than a bad query.)
  void ValidatePriors(const Query& query) const;

  const Index& index() const { return index_; }
  // Set when the index is georeferenced.
  const std::optional<IndexGeo>& geo() const { return geo_; }

 private:
  const Index& index_;
  ClusterMembers clusters_;
  std::optional<IndexGeo> geo_;
};

// A pose stage's covariance as a result reports it: widened by the index's calibration for the
// query's calibration mode (PCAL: the rotation block by its rotation scale, the centre block by
// its position scale, the cross terms by the root of both; `calibration` says by how much, or is
// empty when the index has none for the mode), its 95 % radius, and on a georeferenced index the
// centre's block in metres east-north-up at the camera.
void ReportCovariance(const Index& index, const std::optional<IndexGeo>& geo, Calibration mode,
                      const Eigen::Vector3d& center, PoseCovariance* covariance);

// A pose's parts as results report them.
Pose PoseOf(const CameraPose& pose);

}  // namespace cwloc
