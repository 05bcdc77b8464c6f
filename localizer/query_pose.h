#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/index.h"
#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/pose/absolute_pose.h"
#include "localizer/query.h"

namespace cwloc {

// One 2D-3D pair per query feature: the match with the smallest descriptor distance, the lower
// view on a tie (a feature matched to several 3D points would count twice in RANSAC's inlier
// tally otherwise). Matches whose view or point is out of range (a corrupt index) are dropped.
std::vector<FeatureMatch> UniqueCorrespondences(const Index& index,
                                                std::vector<FeatureMatch> matches);

struct QueryPose {
  AbsolutePoseResult pose;
  // The correspondences that could be normalized and went into RANSAC, in RANSAC's order:
  // pose.inliers[i] refers to correspondences[used[i]].
  std::vector<uint32_t> used;
};

// The pose stage: LO-RANSAC with the minimal solver the camera calls for, then, with
// options.pose.refine, the final refinement (absolute_pose.h). A known camera undistorts the
// keypoints with its model and P3P holds its focal length. An uncalibrated camera
// (Calibration::kFocalPrior, kUnknown) is a SIMPLE_RADIAL with its principal point at
// QueryCamera::ImageCenter: RANSAC runs P3P with the prior focal length (the camera's mean focal)
// or P4Pf, and the refinement estimates the focal length and the radial distortion with the pose.
// RANSAC is seeded with options.seed; the context brings the query's deadlines and gravity
// prior (its seed and image diagonal are set here).
QueryPose EstimateQueryPose(const Index& index, const Query& query,
                            std::span<const FeatureMatch> correspondences,
                            const LocalizerOptions& options, PoseContext context = {});

}  // namespace cwloc
