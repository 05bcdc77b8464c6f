#include "localizer/localizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <unordered_map>

#include "base/error.h"
#include "base/stopwatch.h"
#include "camera/camera_models.h"
#include "localizer/back_matching.h"
#include "localizer/exhaustive_matching.h"
#include "localizer/forward_matching.h"
#include "localizer/query_pose.h"

namespace cwloc {
namespace {

// Each stage's deadline under a latency budget: the share of the budget by which it stops.
// Forward matching gets half (at city scale it is most of a query; on real photos it stops at
// N_F well before), guided back-matching and its hypothesis a quarter, RANSAC until 90 %, and
// the refinement (a few ms on thousands of inliers) starts only before 90 %.
struct StageDeadlines {
  Deadline forward, back, ransac, refine;

  static StageDeadlines For(Deadline::Clock::time_point start, double budget_ms) {
    if (!(budget_ms > 0)) return {};
    const double budget = budget_ms * 1e-3;
    return {Deadline::After(start, 0.5 * budget), Deadline::After(start, 0.75 * budget),
            Deadline::After(start, 0.9 * budget), Deadline::After(start, 0.9 * budget)};
  }
};

// What a matcher hands to the pose stage, and what it did on the way.
struct MatcherOutput {
  std::vector<FeatureMatch> forward;          // forward matches: votes for location recognition
  std::vector<FeatureMatch> back;             // back-matches: votes too
  std::vector<FeatureMatch> correspondences;  // unique 2D-3D pairs for the pose stage
  std::string failure_reason;                 // set when the matcher left nothing to fit
  ForwardMatchingStats forward_stats;
  uint32_t back_matched_clusters = 0;
  double seconds_query_tree = 0;
  double seconds_back_matching = 0;
  double seconds_pose = 0;   // pose estimation a matcher ran to choose its correspondences
  double seconds_guide = 0;  // the pose hypothesis of guided back-matching
  bool guided = false;
  bool back_stopped_by_deadline = false;
  BackStop back_stop = BackStop::kNotRun;
  // The cluster-wise matcher's back-matching, to continue it (PinPose).
  std::unique_ptr<PoseGuide> guide;
  std::unique_ptr<BackMatcher> back_matcher;
};

// The parameters of an uncalibrated query camera as the pose stage estimated it: SIMPLE_RADIAL
// (f, cx, cy, k) with the principal point at the image centre.
std::vector<double> EstimatedCameraParams(const QueryCamera& camera,
                                          const AbsolutePoseResult& pose) {
  const std::array<double, 2> center = camera.ImageCenter();
  return {pose.focal_length_px, center[0], center[1], pose.radial_distortion};
}

// Guided back-matching's hypothesis: the pose stage on the forward matches.
std::optional<PoseHypothesis> FitPoseHypothesis(const Index& index, const Query& query,
                                                std::span<const FeatureMatch> forward,
                                                const LocalizerOptions& options,
                                                const Deadline& stop) {
  const std::vector<FeatureMatch> correspondences =
      UniqueCorrespondences(index, {forward.begin(), forward.end()});
  if (correspondences.size() < size_t(options.pose.min_inliers)) return std::nullopt;
  PoseContext context;
  context.ransac.deadline = stop;
  context.refine_deadline = stop;
  const QueryPose fit = EstimateQueryPose(index, query, correspondences, options, context);
  if (!fit.pose.success) return std::nullopt;
  PoseHypothesis hypothesis;
  hypothesis.pose = fit.pose.pose;
  if (query.camera.FocalKnown()) {
    hypothesis.model_id = query.camera.model_id;
    hypothesis.params = query.camera.params;
  } else {
    hypothesis.model_id = CameraModelId::kSimpleRadial;
    hypothesis.params = EstimatedCameraParams(query.camera, fit.pose);
  }
  return hypothesis;
}

// The back-matcher's matches so far become the pose stage's correspondences.
void TakeBackMatches(const Index& index, MatcherOutput* out) {
  const BackMatchingResult& back = out->back_matcher->result();
  out->back_stopped_by_deadline = back.stopped_by_deadline;
  out->back_stop = back.stop;
  out->back = back.matches;
  out->back_matched_clusters = static_cast<uint32_t>(back.visited.size());
  out->seconds_query_tree = back.seconds_query_tree;
  out->seconds_back_matching = back.seconds_matching + out->seconds_guide;
  std::vector<FeatureMatch> pairs = out->back;
  if (back.stopped_by_deadline) {
    // Cut short by the budget: the forward matches join the pose stage's correspondences, so
    // that a query cut before its back-matches can still be localized (the anytime reading).
    pairs.insert(pairs.end(), out->forward.begin(), out->forward.end());
  }
  out->correspondences = UniqueCorrespondences(index, std::move(pairs));
}

// The paper: forward matching, then back-matching; the pose is fit to the back-matches.
MatcherOutput MatchClusterWise(const Index& index, const ClusterMembers& clusters,
                               const Query& query, const LocalizerOptions& options,
                               ClusterMask allowed, const StageDeadlines& deadlines) {
  MatcherOutput out;
  KdForestSearcher searcher(index.kd_forest());
  out.forward =
      MatchForward(index, query, options, searcher, &out.forward_stats, allowed, deadlines.forward);
  const Stopwatch guide_time;
  const bool guided = options.back_matching == BackMatching::kGuided ||
                      (options.back_matching == BackMatching::kAuto && query.camera.FocalKnown());
  if (guided) {
    if (std::optional<PoseHypothesis> hypothesis =
            FitPoseHypothesis(index, query, out.forward, options, deadlines.back))
      out.guide =
          std::make_unique<PoseGuide>(query, std::move(*hypothesis), options.guide_radius_px);
  }
  out.seconds_guide = guide_time.Seconds();
  out.guided = out.guide != nullptr;
  out.back_matcher = std::make_unique<BackMatcher>(index, clusters, query, out.forward, options,
                                                   BackMatchingRatio(options, query.camera),
                                                   allowed, out.guide.get(), deadlines.back);
  out.back_matcher->Run(BackMatchingTarget(options, query.camera));
  TakeBackMatches(index, &out);
  return out;
}

// Votes for the clusters of the `count` model images whose cameras are nearest the predicted
// one, the nearest with most: a view of each image voting as a forward match would.
std::vector<FeatureMatch> NearestImageVotes(const Index& index, const FramePrediction& prediction,
                                            uint32_t count) {
  const CameraPose& pose = prediction.hypothesis.pose;
  const std::optional<double> median = MedianPointDepth(index, prediction.seen_points, pose);
  if (!median) return {};
  const double depth = std::max(*median, 1e-9);
  const Eigen::Vector3d center = pose.Center();
  const Eigen::Vector3d axis = pose.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  std::vector<std::pair<double, uint32_t>> nearest;  // (distance, image)
  for (uint32_t i = 0; i < index.images().size(); ++i) {
    const IndexImage& image = index.images()[i];
    if (image.num_views == 0) continue;
    const auto& q = image.cam_from_world_rotation;
    const auto& t = image.cam_from_world_translation;
    const CameraPose other(Eigen::Quaterniond(q[0], q[1], q[2], q[3]),
                           Eigen::Vector3d(t[0], t[1], t[2]));
    const Eigen::Vector3d other_axis = other.rotation.conjugate() * Eigen::Vector3d::UnitZ();
    nearest.push_back({(other.Center() - center).norm() / depth + (1.0 - axis.dot(other_axis)), i});
  }
  const size_t kept = std::min<size_t>(count, nearest.size());
  std::partial_sort(nearest.begin(), nearest.begin() + kept, nearest.end());
  std::vector<FeatureMatch> votes;
  for (size_t rank = 0; rank < kept; ++rank) {
    const IndexImage& image = index.images()[nearest[rank].second];
    for (size_t v = rank; v < kept; ++v) votes.push_back({0, image.first_view, 0.0f});
  }
  return votes;
}

// A predicted frame: guided back-matching from the clusters that saw the previous frame's
// inliers, each of their views voting as a forward match would.
MatcherOutput MatchPredicted(const Index& index, const ClusterMembers& clusters, const Query& query,
                             const LocalizerOptions& options, ClusterMask allowed,
                             const FramePrediction& prediction, const StageDeadlines& deadlines) {
  MatcherOutput out;
  const Stopwatch guide_time;
  if (!prediction.views.empty()) {
    PoseGuide guide(query, prediction.hypothesis, prediction.radius_px);
    for (const uint32_t view : prediction.views) {
      if (const std::optional<FeatureMatch> match = guide.Match(index, view, options.ratio))
        out.back.push_back(*match);
    }
    out.guided = true;
    out.seconds_back_matching = guide_time.Seconds();
    out.correspondences = UniqueCorrespondences(index, out.back);
    return out;
  }
  std::vector<FeatureMatch> votes;
  if (prediction.nearest_images_first) {
    votes = NearestImageVotes(index, prediction, options.max_back_clusters);
  } else {
    for (const uint32_t point : prediction.seen_points) {
      if (point >= index.num_points()) continue;
      for (const uint32_t view : index.TrackOf(point)) votes.push_back({0, view, 0.0f});
    }
  }
  out.guide = std::make_unique<PoseGuide>(query, prediction.hypothesis, prediction.radius_px);
  out.guided = true;
  out.seconds_guide = guide_time.Seconds();
  // A frame near its prediction keeps the paper's ratio test, whatever its camera.
  out.back_matcher =
      std::make_unique<BackMatcher>(index, clusters, query, votes, options, options.ratio, allowed,
                                    out.guide.get(), deadlines.back);
  out.back_matcher->Run(std::max(options.back_matches, prediction.min_back_matches));
  TakeBackMatches(index, &out);
  return out;
}

// The diagnostic baseline: the pose is fit to the global 1-ratio matches.
MatcherOutput MatchGlobally(const Index& index, const Query& query, const LocalizerOptions& options,
                            ClusterMask allowed, const StageDeadlines& deadlines) {
  MatcherOutput out;
  KdForestSearcher searcher(index.kd_forest());
  out.forward = MatchGlobalRatio(index, query, options, searcher, &out.forward_stats, allowed,
                                 deadlines.forward);
  out.correspondences = UniqueCorrespondences(index, out.forward);
  return out;
}

// Table 1's gold standard: unrefined RANSAC in every cluster that could reach min_inliers;
// the pose is fit to the matches of the cluster with the most inliers.
MatcherOutput MatchClusterExhaustive(const Index& index, const ClusterMembers& clusters,
                                     const Query& query, const LocalizerOptions& options,
                                     ClusterMask allowed) {
  MatcherOutput out;
  const std::vector<ClusterMatches> per_cluster =
      MatchEachClusterExhaustively(index, clusters, query, options.ratio, &out.forward_stats);
  const Stopwatch selection;
  const std::vector<FeatureMatch>* best = nullptr;
  int best_inliers = 0;
  LocalizerOptions unrefined = options;
  unrefined.pose.refine = false;
  for (const ClusterMatches& cluster : per_cluster) {
    if (!ClusterAllowed(allowed, cluster.cluster)) continue;
    out.forward.insert(out.forward.end(), cluster.matches.begin(), cluster.matches.end());
    if (cluster.matches.size() < static_cast<size_t>(options.pose.min_inliers)) continue;
    const QueryPose candidate = EstimateQueryPose(index, query, cluster.matches, unrefined);
    if (candidate.pose.success && candidate.pose.num_inliers > best_inliers) {
      best_inliers = candidate.pose.num_inliers;
      best = &cluster.matches;
    }
  }
  out.seconds_pose = selection.Seconds();
  if (best != nullptr) {
    out.correspondences = UniqueCorrespondences(index, *best);
  } else {
    out.failure_reason = "no cluster gave " + std::to_string(options.pose.min_inliers) + " inliers";
  }
  return out;
}

// How far the camera's position is known: the covariance's 95 % radius; 0 without one.
double PositionUncertainty(const AbsolutePoseResult& pose) {
  return pose.covariance ? pose.covariance->position_radius95 : 0.0;
}

// Back-matching until the pose is pinned. An estimated focal length trades off against the
// camera's depth, and the first N_B back-matches can leave that trade open (the model images
// back-matched first see the scene from one side). For an unknown focal length, or a prior the
// correspondences leave weakly constrained (refine_pose.h), the back-matching continues where
// it stopped, to twice its matches (at most options.max_back_matches), and the pose is
// estimated again on the larger set, while each step shrinks the position's uncertainty by at
// least options.pinned_shrink. A pose estimate that fails keeps the last one that localized and
// its correspondences (the back-match counts and image votes then include the larger set).
void PinPose(const Index& index, const Query& query, const LocalizerOptions& options,
             const PoseContext& context, MatcherOutput* matched, QueryPose* fit) {
  if (matched->back_matcher == nullptr || !fit->pose.success || !fit->pose.focal_depth) return;
  if (query.camera.calibration != Calibration::kUnknown &&
      !WeaklyConstrained(*fit->pose.focal_depth, fit->pose.focal_length_px))
    return;
  double uncertainty = PositionUncertainty(fit->pose);
  while (matched->back_stop == BackStop::kTarget && uncertainty > 0) {
    const size_t before = matched->back_matcher->result().matches.size();
    if (before >= options.max_back_matches) {
      matched->back_stop = BackStop::kBound;
      break;
    }
    matched->back_matcher->Run(static_cast<uint32_t>(
        std::min<size_t>(options.max_back_matches, std::max<size_t>(2 * before, 1))));
    if (matched->back_matcher->result().matches.size() == before) break;  // nothing left to see
    std::vector<FeatureMatch> previous = std::move(matched->correspondences);
    TakeBackMatches(index, matched);
    QueryPose more = EstimateQueryPose(index, query, matched->correspondences, options, context);
    if (!more.pose.success) {
      matched->correspondences = std::move(previous);
      break;
    }
    const double now = PositionUncertainty(more.pose);
    *fit = std::move(more);
    if (!(now > 0 && now < (1.0 - options.pinned_shrink) * uncertainty)) {
      if (matched->back_stop == BackStop::kTarget) matched->back_stop = BackStop::kPinned;
      break;
    }
    uncertainty = now;
  }
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

// The one check of a query, whatever it was read from.
// The matcher the options name, on the clusters `allowed` (all when empty).
MatcherOutput RunMatcher(const Index& index, const ClusterMembers& clusters, const Query& query,
                         const LocalizerOptions& options, ClusterMask allowed,
                         const StageDeadlines& deadlines) {
  switch (options.matcher) {
    case Matcher::kClusterWise:
      return MatchClusterWise(index, clusters, query, options, allowed, deadlines);
    case Matcher::kGlobalRatio:
      return MatchGlobally(index, query, options, allowed, deadlines);
    case Matcher::kClusterExhaustive:
      return MatchClusterExhaustive(index, clusters, query, options, allowed);
  }
  throw std::logic_error("unknown matcher");
}

// What matching found and took, into the result: its counts, ranked images and stage times.
void ReportMatching(const Index& index, const Query& query, const MatcherOutput& matched,
                    const LocalizerOptions& options, LocalizationResult* result) {
  result->num_features = query.NumFeatures();
  result->features_searched = matched.forward_stats.features_searched;
  result->forward_matches = static_cast<uint32_t>(matched.forward.size());
  result->back_matches = static_cast<uint32_t>(matched.back.size());
  result->back_matched_clusters = matched.back_matched_clusters;
  result->back_stop = matched.back_stop;
  result->guided = matched.guided;
  result->correspondences = static_cast<uint32_t>(matched.correspondences.size());
  result->ranked_images = RankImages(index, matched.forward, matched.back, options.ranked_images);
  result->times.forward_knn = matched.forward_stats.seconds_knn;
  result->times.ratio_test = matched.forward_stats.seconds_ratio_test;
  result->times.query_tree = matched.seconds_query_tree;
  result->times.back_matching = matched.seconds_back_matching;
}

// Which distortion model a localized query was fitted with, and why.
Distortion DistortionOf(const LocalizationResult& result, const AbsolutePoseResult& pose) {
  Distortion out;
  out.model = result.camera.model;
  if (!result.camera.focal_estimated) {
    out.fit = DistortionFit::kGiven;
    out.why = "the camera was known: its own model and parameters, held fixed";
    return out;
  }
  if (!pose.refined) {
    out.fit = DistortionFit::kHeldAtZero;
    out.k = 0.0;
    out.why =
        "the focal length was estimated without the final refinement (--no-refine, a latency "
        "budget, or a refined camera that was not sane), so k stayed 0";
    return out;
  }
  out.fit = DistortionFit::kEstimated;
  out.k = result.camera.params.back();
  out.why =
      "the camera was not known: one radial term k was refined with the focal length, as "
      "COLMAP's registrator refines a camera that no registered image has refined";
  if (result.covariance && pose.distortion_std) {
    out.k_std = *pose.distortion_std;
    out.k_significant = std::abs(*out.k) >= 2.0 * *out.k_std;
    out.why += *out.k_significant
                   ? "; the data constrain it (|k| is at least 2 standard deviations)"
                   : "; the data hardly constrain it (|k| is under 2 standard deviations)";
  }
  return out;
}

// The pose stage's answer, into the result: the pose, its inliers, the camera as estimated, the
// covariance and, on a georeferenced index, the pose on the globe; or why there is none.
void ReportPose(const Index& index, const std::optional<IndexGeo>& geo, const Query& query,
                const MatcherOutput& matched, const QueryPose& fit, LocalizationResult* result) {
  const AbsolutePoseResult& pose = fit.pose;
  result->num_inliers = static_cast<uint32_t>(pose.num_inliers);
  result->inlier_ratio =
      fit.used.empty() ? 0.0 : double(pose.num_inliers) / double(fit.used.size());
  result->ransac_iterations = pose.stats.iterations;
  result->success = pose.success;
  if (!pose.success) {
    result->failure_reason = pose.failure_reason;
    return;
  }
  const Pose p = PoseOf(pose.pose);
  result->rotation = p.rotation;
  result->translation = p.translation;
  result->center = p.center;
  const Eigen::Vector3d center = pose.pose.Center();
  if (geo) result->geo = geo->PoseOnGlobe(pose.pose.rotation, center);
  result->covariance = pose.covariance;
  if (result->covariance)
    ReportCovariance(index, geo, query.camera.calibration, center, &*result->covariance);
  for (size_t i = 0; i < pose.inliers.size(); ++i) {
    if (!pose.inliers[i]) continue;
    const FeatureMatch& match = matched.correspondences[fit.used[i]];
    const uint32_t point = index.view_points()[match.view];
    result->inliers.push_back(
        {match.feature,
         {query.keypoints[2 * match.feature], query.keypoints[2 * match.feature + 1]},
         point,
         index.PointXyz(point),
         match.view});
  }
  if (!query.camera.FocalKnown()) {
    result->camera.focal_estimated = true;
    result->camera.model = std::string(CameraModelName(CameraModelId::kSimpleRadial));
    result->camera.params = EstimatedCameraParams(query.camera, pose);
    result->focal_depth = pose.focal_depth;
  }
  result->camera.distortion = DistortionOf(*result, pose);
}

void ValidateQuery(const Query& query) {
  const std::string source = query.Source();
  if (query.descriptors.size() != size_t{query.NumFeatures()} * 128) {
    throw InputError(source + ": keypoint and descriptor counts differ");
  }
  if (query.NumFeatures() == 0) throw InputError(source + ": the query has no features");
  if (query.camera.width == 0 || query.camera.height == 0)
    throw InputError(source + ": camera has no image size");
  // An unknown camera has only its size; a focal prior's model gives the focal length.
  if (query.camera.calibration == Calibration::kUnknown) return;
  const auto model = FindCameraModel(static_cast<int32_t>(query.camera.model_id));
  if (!model) {
    throw InputError(source + ": unknown camera model id " +
                     std::to_string(static_cast<int32_t>(query.camera.model_id)));
  }
  if (!model->can_project) {
    throw InputError(source + ": camera model " + std::string(model->name) +
                     " cannot be used to localize");
  }
  if (query.camera.params.size() != static_cast<size_t>(model->num_params)) {
    throw InputError(source + ": " + std::string(model->name) + " takes " +
                     std::to_string(model->num_params) + " parameters, got " +
                     std::to_string(query.camera.params.size()));
  }
}

}  // namespace

void ReportCovariance(const Index& index, const std::optional<IndexGeo>& geo, Calibration mode,
                      const Eigen::Vector3d& center, PoseCovariance* covariance) {
  const IndexCovarianceCalibration* calibration = index.covariance_calibration();
  const auto m = static_cast<size_t>(mode);
  if (calibration != nullptr && calibration->position_scale[m] > 0 &&
      calibration->rotation_scale[m] > 0) {
    const CovarianceScales& scales = covariance->calibration.emplace(
        CovarianceScales{calibration->rotation_scale[m], calibration->position_scale[m]});
    Eigen::Matrix<double, 6, 1> root;
    root << Eigen::Vector3d::Constant(std::sqrt(scales.rotation)),
        Eigen::Vector3d::Constant(std::sqrt(scales.position));
    const Eigen::Matrix<double, 6, 6> block = PoseBlock(*covariance);
    PoseBlock(*covariance) = root.asDiagonal() * block * root.asDiagonal();
  }
  covariance->position_radius95 = Radius95(PositionBlock(*covariance));
  if (geo) {
    const Eigen::Matrix3d enu = geo->LocalEnuCovariance(center, PositionBlock(*covariance));
    Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(
        covariance->enu_position.emplace().data()) = enu;
    covariance->position_radius95_m = Radius95(enu);
  }
}

Pose PoseOf(const CameraPose& pose) {
  const Eigen::Quaterniond& q = pose.rotation;
  const Eigen::Vector3d& t = pose.translation;
  const Eigen::Vector3d c = pose.Center();
  Pose out;
  out.rotation = {q.w(), q.x(), q.y(), q.z()};
  out.translation = {t.x(), t.y(), t.z()};
  out.center = {c.x(), c.y(), c.z()};
  return out;
}

Localizer::Localizer(const Index& index)
    : index_(index), clusters_(index), geo_(IndexGeo::Of(index)) {}

void Localizer::ValidatePriors(const Query& query) const {
  const std::string source = query.Source();
  if (const auto& prior = query.position_prior) {
    if (!(std::abs(prior->latitude_deg) <= 90) || !std::isfinite(prior->longitude_deg) ||
        !std::isfinite(prior->height_m.value_or(0.0))) {
      throw InputError(source + ": position prior " + std::to_string(prior->latitude_deg) + ", " +
                       std::to_string(prior->longitude_deg) +
                       " is not a latitude in [-90, 90] and a longitude");
    }
    if (!(prior->radius_m > 0) || !std::isfinite(prior->radius_m))
      throw InputError(source + ": position prior radius must be a positive number of metres");
  }
  if (const auto& g = query.gravity) {
    const double norm = std::sqrt(g->at(0) * g->at(0) + g->at(1) * g->at(1) + g->at(2) * g->at(2));
    if (!std::isfinite(norm) || norm < 1e-9)
      throw InputError(source + ": gravity prior must be a finite, non-zero vector");
  }
  if ((query.position_prior || query.gravity) && !geo_) {
    throw InputError(source + ": a position or gravity prior needs a georeferenced index (" +
                     index_.file().path().string() + " is not; see cwloc-index build --georef)");
  }
}

LocalizationResult Localizer::Localize(const Query& query, const LocalizerOptions& options,
                                       const FramePrediction* prediction,
                                       std::vector<FeatureMatch>* correspondences) const {
  const Stopwatch total;
  const StageDeadlines deadlines = StageDeadlines::For(Deadline::Clock::now(), options.budget_ms);
  ValidateQuery(query);
  ValidatePriors(query);

  // The position prior's region: only clusters with a camera within its radius.
  PriorsUsed priors;
  std::vector<char> allowed;
  std::string prior_region;
  if (query.position_prior) {
    allowed = geo_->ClustersNear(*query.position_prior, clusters_);
    PositionPriorUse& used = priors.position.emplace();
    static_cast<PositionPrior&>(used) = *query.position_prior;
    used.clusters_in_radius =
        static_cast<uint32_t>(std::count(allowed.begin(), allowed.end(), char{1}));
    char radius[32];
    std::snprintf(radius, sizeof(radius), "%g", query.position_prior->radius_m);
    prior_region = std::string(radius) + " m of the position prior";
  }

  MatcherOutput matched;
  if (priors.position && priors.position->clusters_in_radius == 0) {
    matched.failure_reason = "no model camera within " + prior_region;
  } else {
    matched =
        prediction != nullptr
            ? MatchPredicted(index_, clusters_, query, options, allowed, *prediction, deadlines)
            : RunMatcher(index_, clusters_, query, options, allowed, deadlines);
    if (query.position_prior && matched.correspondences.empty() && matched.failure_reason.empty())
      matched.failure_reason = "no match to a model camera within " + prior_region;
  }

  PoseContext pose_context;
  pose_context.ransac.deadline = deadlines.ransac;
  pose_context.refine_deadline = deadlines.refine;
  if (query.gravity) {
    // The gravity prior: the model's down direction where the query is thought to be.
    GravityPrior prior;
    prior.in_camera = {(*query.gravity)[0], (*query.gravity)[1], (*query.gravity)[2]};
    prior.in_world = geo_->GravityInModel(query.position_prior);
    prior.sigma_deg = options.prior_gravity_sigma_deg;
    pose_context.gravity = prior;
    priors.gravity.emplace().direction = *query.gravity;
  }

  const Stopwatch pose_time;
  QueryPose fit;
  if (matched.failure_reason.empty() && !options.estimate_pose) {
    fit.pose.failure_reason = "matched only: the pose stage was not run";
  } else if (matched.failure_reason.empty()) {
    fit = EstimateQueryPose(index_, query, matched.correspondences, options, pose_context);
    PinPose(index_, query, options, pose_context, &matched, &fit);
  } else {
    fit.pose.failure_reason = matched.failure_reason;
  }

  LocalizationResult result;
  result.name = query.name;
  static_cast<CameraUsed&>(result.camera) = CameraUsedOf(query.camera);
  result.photo = query.photo;
  ReportMatching(index_, query, matched, options, &result);
  ReportPose(index_, geo_, query, matched, fit, &result);
  if (correspondences != nullptr) *correspondences = matched.correspondences;
  if (priors.gravity && fit.pose.success) priors.gravity->error_deg = fit.pose.gravity_angle_deg;
  result.priors = std::move(priors);
  if (options.budget_ms > 0) {
    Budget& budget = result.budget.emplace();
    budget.ms = options.budget_ms;
    const auto cut = [&](bool was_cut, const char* stage) {
      if (was_cut) budget.cut.push_back(stage);
    };
    cut(matched.forward_stats.stopped_by_deadline, "forward");
    cut(matched.back_stopped_by_deadline, "back_matching");
    cut(fit.pose.stats.stopped_by_deadline, "ransac");
    cut(fit.pose.refinement_skipped, "refinement");
  }
  result.times.pose = matched.seconds_pose + pose_time.Seconds();
  result.times.extraction = query.extraction_seconds;
  result.times.total = total.Seconds() + result.times.extraction;
  return result;
}

}  // namespace cwloc
