#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "camera/camera_models.h"
#include "localizer/matching.h"
#include "localizer/query.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// A first pose of the query (from its forward matches) that guided back-matching uses: a
// model view is compared only with the query features within `radius_px` of where the view's
// 3D point projects, as Active Search restricts its search (docs/algorithm.md, section 3).
struct PoseHypothesis {
  CameraPose pose;  // cam_from_world
  // The query camera as the hypothesis has it: the known model, or SIMPLE_RADIAL (f, cx, cy, k)
  // with the focal length and distortion estimated.
  CameraModelId model_id = CameraModelId::kSimplePinhole;
  std::vector<double> params;
};

// The median depth of the index's `points` (rows) in the camera `pose` (cam_from_world), rows
// out of range left out; nothing when none is left.
std::optional<double> MedianPointDepth(const Index& index, std::span<const uint32_t> points,
                                       const CameraPose& pose);

// The query's features on a grid of radius-sized cells, to find those near a pixel fast.
class PoseGuide {
 public:
  PoseGuide(const Query& query, PoseHypothesis hypothesis, double radius_px);

  // The view's nearest query feature in descriptor space among those near its projection, when
  // it lies within the radius and passes the 1-ratio test against the second nearest (both
  // drawn from a window of at least the radius that holds ~8 features at the query's mean
  // density; with fewer than two there, nothing passes). Empty when the point projects outside
  // the image or behind the camera.
  std::optional<FeatureMatch> Match(const Index& index, uint32_t view, double ratio);

 private:
  const Query& query_;
  PoseHypothesis hypothesis_;
  Eigen::Matrix3d rotation_;
  double radius_px_;
  double reach_px_ = 0;  // the competitors' window
  double cell_px_ = 0;
  uint32_t columns_ = 0;
  uint32_t rows_ = 0;
  std::vector<uint32_t> cell_start_;  // features of cell c: features_[cell_start_[c] .. [c+1])
  std::vector<uint32_t> features_;
  std::vector<float> feature_xy_;     // features_[i]'s keypoint at 2 i, 2 i + 1: read in order
  std::vector<uint32_t> candidates_;  // scratch, one slot per feature
  std::vector<uint32_t> distances_;
  uint8_t decoded_[128];  // a coded index's view descriptor
};

}  // namespace cwloc
