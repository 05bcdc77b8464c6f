#include "localizer/localizer.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <unordered_map>

#include "format/camera/camera_models.h"
#include "format/base/error.h"
#include "localizer/cluster_wise_ratio.h"
#include "localizer/exhaustive_matching.h"
#include "localizer/forward_matching.h"
#include "localizer/pose/absolute_pose.h"

namespace cwloc {
namespace {

using Clock = std::chrono::steady_clock;

double Seconds(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// One 2D-3D pair per query feature: the match with the smallest descriptor distance (a feature
// matched to several 3D points would count twice in RANSAC's inlier tally otherwise).
std::vector<FeatureMatch> UniqueCorrespondences(const Index& index, std::vector<FeatureMatch> matches) {
  std::sort(matches.begin(), matches.end(), [](const FeatureMatch& a, const FeatureMatch& b) {
    return a.feature != b.feature ? a.feature < b.feature : a.distance < b.distance;
  });
  std::vector<FeatureMatch> unique;
  for (const FeatureMatch& match : matches) {
    // Views come from range-checked searches; their point is checked here, where it is read.
    if (match.view >= index.num_views() || index.view_points()[match.view] >= index.points().size()) continue;
    if (!unique.empty() && unique.back().feature == match.feature) continue;
    unique.push_back(match);
  }
  return unique;
}

// Images ranked by their votes: forward matches plus back-matches (location recognition).
std::vector<RankedImage> RankImages(const Index& index, std::span<const FeatureMatch> forward,
                                    std::span<const FeatureMatch> back, uint32_t count) {
  std::unordered_map<uint32_t, uint32_t> votes;
  for (const auto* matches : {&forward, &back}) {
    for (const FeatureMatch& match : *matches) {
      const uint32_t image = index.ImageOfView(match.view);
      if (image != UINT32_MAX) ++votes[image];
    }
  }
  std::vector<std::pair<uint32_t, uint32_t>> ranked(votes.begin(), votes.end());
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) {
    return a.second != b.second ? a.second > b.second : a.first < b.first;
  });
  std::vector<RankedImage> out;
  for (size_t i = 0; i < ranked.size() && i < count; ++i) {
    const IndexImage& image = index.images()[ranked[i].first];
    out.push_back({image.image_id, std::string(index.ImageName(image)), ranked[i].second});
  }
  return out;
}

void CheckQueryCamera(const Query& query) {
  if (query.camera.width == 0 || query.camera.height == 0) {
    throw InputError("query '" + query.name + "': camera has no image size");
  }
  if (!query.camera.focal_known) return;
  const auto model = FindCameraModel(static_cast<int32_t>(query.camera.model_id));
  if (!model || !model->can_project) throw InputError("query '" + query.name + "': unsupported camera model");
  if (query.camera.params.size() != static_cast<size_t>(model->num_params)) {
    throw InputError("query '" + query.name + "': " + std::string(model->name) + " takes " +
                     std::to_string(model->num_params) + " parameters, got " +
                     std::to_string(query.camera.params.size()));
  }
}

// LO-RANSAC with the minimal solver the camera calls for: P3P with a known focal length, P4Pf
// without. *used counts the correspondences that could be normalized.
AbsolutePoseResult EstimateQueryPose(const Index& index, const Query& query,
                                     std::span<const FeatureMatch> correspondences, const LocalizerOptions& options,
                                     bool refine, uint32_t* used) {
  std::vector<Eigen::Vector2d> points2D;
  std::vector<Eigen::Vector3d> points3D;
  points2D.reserve(correspondences.size());
  points3D.reserve(correspondences.size());
  const QueryCamera& camera = query.camera;
  for (const FeatureMatch& match : correspondences) {
    const std::array<double, 2> pixel = {query.keypoints[2 * match.feature], query.keypoints[2 * match.feature + 1]};
    Eigen::Vector2d point2D;
    if (camera.focal_known) {
      std::array<double, 2> normalized;
      if (!PixelToNormalized(camera.model_id, camera.params, pixel, &normalized)) continue;
      point2D = {normalized[0], normalized[1]};
    } else {
      point2D = {pixel[0] - camera.width / 2.0, pixel[1] - camera.height / 2.0};
    }
    const IndexPoint& point = index.points()[index.view_points()[match.view]];
    points2D.push_back(point2D);
    points3D.emplace_back(point.xyz[0], point.xyz[1], point.xyz[2]);
  }
  *used = static_cast<uint32_t>(points2D.size());

  AbsolutePoseOptions pose_options;
  pose_options.max_error_px = options.max_error_px;
  pose_options.min_inliers = options.min_inliers;
  pose_options.max_iterations = options.max_ransac_iterations;
  pose_options.confidence = options.ransac_confidence;
  pose_options.seed = options.seed;
  pose_options.refine = refine;
  if (camera.focal_known) {
    return EstimateAbsolutePose(points2D, points3D, MeanFocalLength(camera.model_id, camera.params), pose_options);
  }
  pose_options.image_diagonal_px = std::hypot(double(camera.width), double(camera.height));
  return EstimateAbsolutePoseUnknownFocal(points2D, points3D, pose_options);
}

}  // namespace

void ValidateLocalizerOptions(const LocalizerOptions& o) {
  auto require = [](bool ok, const std::string& message) {
    if (!ok) throw InputError(message);
  };
  require(o.k >= 1 && o.k <= 63, "--k " + std::to_string(o.k) + ": expected 1 to 63");
  require(o.checks >= 1, "--checks must be at least 1");
  require(o.ratio > 0 && o.ratio <= 1, "--ratio " + std::to_string(o.ratio) + ": expected a value in (0, 1]");
  require(o.forward_matches >= 1, "--nf must be at least 1");
  require(o.max_back_images >= 1, "--max-back-images must be at least 1");
  require(o.query_tree_checks >= 1, "--query-checks must be at least 1");
  require(o.min_inliers >= 4, "--min-inliers " + std::to_string(o.min_inliers) + ": expected at least 4");
  require(o.max_error_px > 0 && std::isfinite(o.max_error_px), "--max-error must be a positive number of pixels");
  require(o.max_ransac_iterations >= 1, "--max-ransac-iterations must be at least 1");
  require(o.ransac_confidence > 0 && o.ransac_confidence < 1, "--ransac-confidence: expected a value in (0, 1)");
}

Localizer::Localizer(const Index& index) : index_(index), clusters_(index) {}

LocalizationResult Localizer::Localize(const Query& query, const LocalizerOptions& options) const {
  const auto start = Clock::now();
  CheckQueryCamera(query);
  if (query.descriptors.size() != size_t{query.NumFeatures()} * 128) {
    throw InputError("query '" + query.name + "': keypoint and descriptor counts differ");
  }
  LocalizationResult result;
  result.name = query.name;
  result.camera = query.camera;
  result.num_features = query.NumFeatures();
  if (query.NumFeatures() == 0) throw InputError("query '" + query.name + "' has no features");

  std::mt19937_64 rng(options.seed);
  KdForestSearcher searcher(index_.kd_forest());
  ForwardMatchingStats forward_stats;
  std::vector<FeatureMatch> forward;
  std::vector<FeatureMatch> back;
  std::vector<ClusterMatches> exhaustive;
  if (options.matcher == Matcher::kClusterWise) {
    forward = MatchForward(index_, query, options, rng, searcher, &forward_stats);
    const BackMatchingResult back_result = MatchBack(index_, clusters_, query, forward, options);
    back = back_result.matches;
    result.back_matched_images = static_cast<uint32_t>(back_result.visited.size());
    result.times.query_tree = back_result.seconds_query_tree;
    result.times.back_matching = back_result.seconds_matching;
  } else if (options.matcher == Matcher::kGlobalRatio) {
    forward = MatchGlobalRatio(index_, query, options, searcher, &forward_stats);
  } else {
    exhaustive = MatchEachClusterExhaustively(index_, clusters_, query, options.ratio, &forward_stats);
    for (const ClusterMatches& cluster : exhaustive) {
      forward.insert(forward.end(), cluster.matches.begin(), cluster.matches.end());
    }
  }
  result.times.forward_knn = forward_stats.seconds_knn;
  result.times.ratio_test = forward_stats.seconds_ratio_test;
  result.features_searched = forward_stats.features_searched;
  result.forward_matches = static_cast<uint32_t>(forward.size());
  result.back_matches = static_cast<uint32_t>(back.size());
  result.ranked_images = RankImages(index_, forward, back, options.ranked_images);

  // The paper fits the pose to the back-matches; the global-ratio baseline to its matches; the
  // exhaustive matcher to one cluster's matches, chosen below.
  std::vector<FeatureMatch> correspondences;
  if (options.matcher != Matcher::kClusterExhaustive) {
    correspondences = UniqueCorrespondences(index_, options.matcher == Matcher::kClusterWise ? back : forward);
  }

  const auto pose_start = Clock::now();
  AbsolutePoseResult pose;
  uint32_t pose_inputs = 0;
  if (options.matcher == Matcher::kClusterExhaustive) {
    // Table 1's gold standard: RANSAC in every cluster that could reach min_inliers; the
    // cluster with the most inliers wins, and only its pose is refined.
    const std::vector<FeatureMatch>* best = nullptr;
    int best_inliers = 0;
    for (const ClusterMatches& cluster : exhaustive) {
      if (cluster.matches.size() < options.min_inliers) continue;
      uint32_t used = 0;
      const AbsolutePoseResult candidate = EstimateQueryPose(index_, query, cluster.matches, options, false, &used);
      if (candidate.success && candidate.num_inliers > best_inliers) {
        best_inliers = candidate.num_inliers;
        best = &cluster.matches;
      }
    }
    if (best != nullptr) {
      correspondences = *best;
      pose = EstimateQueryPose(index_, query, correspondences, options, options.refine, &pose_inputs);
    } else {
      pose.failure_reason = "no cluster gave " + std::to_string(options.min_inliers) + " inliers";
    }
  } else {
    pose = EstimateQueryPose(index_, query, correspondences, options, options.refine, &pose_inputs);
  }
  result.correspondences = static_cast<uint32_t>(correspondences.size());
  result.times.pose = Seconds(pose_start);
  const QueryCamera& camera = query.camera;
  const double cx = camera.width / 2.0, cy = camera.height / 2.0;

  result.num_inliers = static_cast<uint32_t>(pose.num_inliers);
  result.inlier_ratio = pose_inputs == 0 ? 0.0 : double(pose.num_inliers) / double(pose_inputs);
  result.ransac_iterations = pose.stats.iterations;
  result.success = pose.success;
  if (pose.success) {
    const CameraPose& p = pose.pose;
    result.rotation = {p.rotation.w(), p.rotation.x(), p.rotation.y(), p.rotation.z()};
    result.translation = {p.translation.x(), p.translation.y(), p.translation.z()};
    const Eigen::Vector3d center = p.Center();
    result.center = {center.x(), center.y(), center.z()};
    if (!camera.focal_known) {
      result.focal_estimated = true;
      result.camera.params = {pose.focal_length_px, cx, cy};
    }
  } else {
    result.failure_reason = pose.failure_reason;
  }
  result.times.total = Seconds(start);
  return result;
}

}  // namespace cwloc
