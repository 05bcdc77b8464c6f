#include "localizer/tracker.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

#include "base/angles.h"
#include "base/option_value.h"
#include "base/stopwatch.h"

namespace cwloc {
namespace {

// Matching rounds around the pose of the round before, at most (the first around the rough
// pose), and the change of pose below which the matches would be the same: about 2 pixels at a
// focal length of 1000 pixels.
constexpr int kMaxMatchingRounds = 3;
constexpr double kStillDeg = 0.1;
constexpr double kStillDepthShare = 0.002;
// The last step is repeated at most this many times over (a frame after a gap in the stream):
// beyond, the prediction is a guess and the last pose alone does as well.
constexpr double kMaxStepScale = 4.0;
// A frame no prediction tracks is tried once more with the rough round's window this many
// times wider: a prediction further off than the window, as after a sudden turn (ORB-SLAM's
// motion-model tracking widens its window the same way).
constexpr double kWiderWindow = 2.0;
// A matching round goes on to the next nearest model image until it has at least this share of
// the last frame's inliers: the nearest camera may look elsewhere (herz_jesu_p25's photos are
// two passes along the facade; frame 0009's nearest camera is from the other pass and gave it
// half the inliers and 12x the error it has alone, bench/sequence_benchmark.sh).
constexpr double kMinShareOfLastInliers = 0.5;

CameraPose CameraPoseOf(const LocalizationResult& result) {
  const auto& q = result.rotation;
  const auto& t = result.translation;
  return {Eigen::Quaterniond(q[0], q[1], q[2], q[3]), Eigen::Vector3d(t[0], t[1], t[2])};
}

double RotationAngleDeg(const CameraPose& a, const CameraPose& b) {
  return a.rotation.angularDistance(b.rotation) / kDegree;
}

std::vector<uint32_t> InlierPoints(const LocalizationResult& result) {
  std::vector<uint32_t> points;
  points.reserve(result.inliers.size());
  for (const Inlier& inlier : result.inliers) points.push_back(inlier.point);
  return points;
}

// How far the prediction put the frame's inliers from their keypoints, pixels: the median over
// at most kSampledInliers of them, evenly spread.
double PredictionErrorPx(const Index& index, const Query& frame, const LocalizationResult& result,
                         const CameraPose& predicted) {
  constexpr size_t kSampledInliers = 200;
  const std::vector<Inlier>& inliers = result.inliers;
  const size_t step = std::max<size_t>(1, inliers.size() / kSampledInliers);
  const CameraModelId model = ModelIdOf(result.camera);
  std::vector<double> errors;
  for (size_t i = 0; i < inliers.size(); i += step) {
    const std::array<double, 3> xyz = index.PointXyz(inliers[i].point);
    const Eigen::Vector3d in_camera = predicted.Apply(Eigen::Vector3d(xyz[0], xyz[1], xyz[2]));
    std::array<double, 2> pixel;
    if (!ProjectToPixel(model, result.camera.params, {in_camera.x(), in_camera.y(), in_camera.z()},
                        &pixel)) {
      errors.push_back(std::numeric_limits<double>::infinity());  // behind the predicted camera
      continue;
    }
    errors.push_back(std::hypot(pixel[0] - frame.keypoints[2 * inliers[i].feature],
                                pixel[1] - frame.keypoints[2 * inliers[i].feature + 1]));
  }
  if (errors.empty()) return std::numeric_limits<double>::infinity();
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  return errors[errors.size() / 2];
}

// `pose` moved by `relative` (both cam_from_something): relative * pose.
CameraPose Then(const CameraPose& pose, const CameraPose& relative) {
  return {relative.rotation * pose.rotation,
          relative.rotation * pose.translation + relative.translation};
}

}  // namespace

std::variant<FrameMotion, std::string> MetricMotion(const std::array<double, 4>& rotation_wxyz,
                                                    const std::array<double, 3>& translation,
                                                    double sigma_rotation_deg,
                                                    double sigma_position) {
  std::variant<CameraPose, std::string> pose = PoseFromParts(rotation_wxyz, translation);
  if (const auto* problem = std::get_if<std::string>(&pose)) return *problem;
  if (!(sigma_rotation_deg >= 0.0) || !(sigma_position >= 0.0) ||
      !std::isfinite(sigma_rotation_deg + sigma_position))
    return std::string("the sigmas are finite and at least 0 (0: not known)");
  FrameMotion motion{std::get<CameraPose>(pose), true};
  motion.sigma_rotation_deg = sigma_rotation_deg;
  motion.sigma_position = sigma_position;
  return motion;
}

Tracker::Tracker(const Localizer& localizer, const LocalizerOptions& options,
                 const TrackerOptions& tracker_options)
    : localizer_(localizer),
      options_(options),
      tracking_options_(options),
      tracker_options_(tracker_options) {
  // The confidence ends RANSAC early on a tracked frame's mostly-inlier matches.
  RansacOptions& ransac = tracking_options_.pose.ransac;
  ransac.max_iterations = std::min(ransac.max_iterations, tracker_options.max_ransac_iterations);
  ransac.min_iterations = std::min(ransac.min_iterations, ransac.max_iterations / 10);
  rough_options_ = tracking_options_;
  // One local optimisation per new best hypothesis in the matching rounds, where the refinement
  // on all inliers follows: as accurate as four on fox_video, herz_jesu_p25's odd photos and
  // the 10.8M-view city walk, with 6 % fewer instructions there (measured); with none, the
  // refinement starts from a minimal sample's inliers and fox_video's tracked frames were 26 %
  // less accurate.
  ransac.max_refinements = std::min<uint32_t>(ransac.max_refinements, 1);
  rough_options_.pose.refine = false;
}

double Tracker::StepScale(const FrameMotion& motion) const {
  const auto& geo = localizer_.geo();
  if (motion.metric && geo) return 1.0 / geo->frame().georeference().scale;  // metres to model
  if (!before_last_) return 0.0;  // no step to take the length from: the rotation alone
  // Up to scale: the direction, at the length of the last step between camera centres.
  const double norm = motion.relative.translation.norm();
  const double length = (last_->pose.Center() - before_last_->pose.Center()).norm();
  return norm > 0 ? length / norm : 0.0;
}

std::optional<Tracker::MotionUncertainty> Tracker::UncertaintyOf(const FrameMotion& motion) const {
  if (!(motion.sigma_rotation_deg > 0 || motion.sigma_position > 0)) return std::nullopt;
  // A sigma the device does not give is no bound: the tracker's own bounds hold.
  MotionUncertainty uncertainty;
  uncertainty.rotation_rad = motion.sigma_rotation_deg > 0
                                 ? motion.sigma_rotation_deg * kDegree
                                 : std::numeric_limits<double>::infinity();
  const double scale = StepScale(motion);
  if (motion.sigma_position > 0 && scale > 0) uncertainty.position = motion.sigma_position * scale;
  return uncertainty;
}

CameraPose Tracker::Moved(const CameraPose& pose, const FrameMotion& motion) const {
  return Then(pose, CameraPose(motion.relative.rotation,
                               Eigen::Vector3d(motion.relative.translation * StepScale(motion))));
}

CameraPose Tracker::LastStepRepeated(std::optional<double> seconds) const {
  // The step from the frame before: last * before^-1.
  Eigen::Quaterniond rotation = last_->pose.rotation * before_last_->pose.rotation.conjugate();
  Eigen::Vector3d translation = last_->pose.translation - rotation * before_last_->pose.translation;
  if (seconds && last_->seconds && before_last_->seconds) {
    const double last_step = *last_->seconds - *before_last_->seconds;
    const double this_step = *seconds - *last_->seconds;
    if (last_step > 0 && this_step >= 0 && this_step != last_step) {
      // The step's rotation angle and translation scaled alike (its first-order power).
      const double scale = std::min(this_step / last_step, kMaxStepScale);
      const Eigen::AngleAxisd turn(rotation);
      rotation = Eigen::Quaterniond(Eigen::AngleAxisd(turn.angle() * scale, turn.axis()));
      translation *= scale;
    }
  }
  return Then(last_->pose, CameraPose(rotation, translation));
}

void Tracker::Reset() {
  last_.reset();
  before_last_.reset();
}

std::optional<Tracker::MatchedFrame> Tracker::MatchNear(const Query& frame,
                                                        const CameraPose& predicted,
                                                        double radius_px) const {
  FramePrediction prediction;
  prediction.hypothesis = last_->camera_and_pose;
  prediction.hypothesis.pose = predicted;
  if (frame.camera.FocalKnown()) {
    prediction.hypothesis.model_id = frame.camera.model_id;
    prediction.hypothesis.params = frame.camera.params;
  }
  // The rough pose: the last frame's matched views, evenly thinned, in the wide window.
  const std::vector<uint32_t>& seen = last_->inlier_views;
  const size_t step = std::max<size_t>(1, (seen.size() + tracker_options_.rough_views - 1) /
                                              std::max<uint32_t>(tracker_options_.rough_views, 1));
  for (size_t i = 0; i < seen.size(); i += step) prediction.views.push_back(seen[i]);
  prediction.radius_px = radius_px;
  const LocalizationResult rough = localizer_.Localize(frame, rough_options_, &prediction);
  if (!rough.success) return std::nullopt;

  // Matched again around the pose of the round before, until it stops moving: a rough pose
  // from a poor prediction keeps only the matches that agree with it.
  prediction.views.clear();
  prediction.nearest_images_first = true;
  prediction.radius_px = options_.guide_radius_px;
  prediction.min_back_matches = uint32_t(kMinShareOfLastInliers * double(seen.size()));
  CameraPose around = CameraPoseOf(rough);
  const LocalizationResult* before = &rough;
  prediction.seen_points = InlierPoints(rough);
  std::optional<LocalizationResult> result;
  double depth = 0;
  for (int round = 0; round < kMaxMatchingRounds; ++round) {
    prediction.hypothesis.pose = around;
    if (!frame.camera.FocalKnown()) prediction.hypothesis.params = before->camera.params;
    result = localizer_.Localize(frame, tracking_options_, &prediction);
    if (!result->success) return std::nullopt;
    const CameraPose pose = CameraPoseOf(*result);
    // The next round's points; a successful pose has inliers, whose rows the localizer checked.
    prediction.seen_points = InlierPoints(*result);
    depth = *MedianPointDepth(localizer_.index(), prediction.seen_points, pose);
    const bool still = RotationAngleDeg(pose, around) <= kStillDeg &&
                       (pose.Center() - around.Center()).norm() <= kStillDepthShare * depth;
    around = pose;
    before = &*result;
    if (still) break;
  }

  return MatchedFrame{std::move(*result), depth};
}

bool Tracker::Trusted(const MatchedFrame& matched, const CameraPose& predicted,
                      const std::optional<MotionUncertainty>& uncertainty,
                      TrackingInfo* info) const {
  const CameraPose pose = CameraPoseOf(matched.result);
  const double rotation_deg = RotationAngleDeg(pose, predicted);
  const double distance = (pose.Center() - predicted.Center()).norm();
  info->prediction_error = distance;
  info->prediction_error_deg = rotation_deg;
  double max_rotation_deg = tracker_options_.max_rotation_change_deg;
  double max_distance = tracker_options_.max_relative_position_change * matched.depth;
  if (uncertainty) {
    // This pose's variance (each covariance block's trace bounds its largest eigenvalue) twice,
    // for the last pose's, which the prediction started from.
    double rotation_var = 0.0, position_var = 0.0;
    if (const auto& covariance = matched.result.covariance) {
      rotation_var = PoseBlock(*covariance).topLeftCorner<3, 3>().trace();
      position_var = PositionBlock(*covariance).trace();
    }
    const double rotation_sigma =
        std::sqrt(uncertainty->rotation_rad * uncertainty->rotation_rad + 2.0 * rotation_var);
    max_rotation_deg = std::min(max_rotation_deg, kMotionSigmas * rotation_sigma / kDegree);
    if (uncertainty->position) {
      const double position_sigma =
          std::sqrt(*uncertainty->position * *uncertainty->position + 2.0 * position_var);
      max_distance = std::min(max_distance, kMotionSigmas * position_sigma);
    }
  }
  return rotation_deg <= max_rotation_deg && distance <= max_distance;
}

LocalizationResult Tracker::Track(const Query& frame, std::optional<double> seconds,
                                  const std::optional<FrameMotion>& motion) {
  const Stopwatch time;
  TrackingInfo info;
  if (frame.NumFeatures() == 0 && frame.descriptors.empty()) {
    // A black or blurred frame is part of a stream, not bad input: it is lost.
    LocalizationResult lost;
    lost.name = frame.name;
    static_cast<CameraUsed&>(lost.camera) = CameraUsedOf(frame.camera);
    lost.photo = frame.photo;
    lost.failure_reason = "the frame has no features";
    lost.times.extraction = frame.extraction_seconds;
    if (last_) info.predicted_from = last_->name;
    before_last_.reset();
    info.seconds = time.Seconds();
    lost.times.total = info.seconds + lost.times.extraction;
    lost.tracking = std::move(info);
    return lost;
  }
  std::optional<LocalizationResult> result;
  std::optional<CameraPose> first_prediction;
  std::optional<CameraPose> tracked_from;  // the prediction a tracked frame came from
  if (last_) {
    info.predicted_from = last_->name;
    // The given motion or the last step repeated, then the last pose alone (a camera that
    // stopped or turned).
    std::vector<std::pair<CameraPose, std::optional<MotionUncertainty>>> predictions;
    if (motion) {
      predictions.emplace_back(Moved(last_->pose, *motion), UncertaintyOf(*motion));
    } else if (before_last_) {
      predictions.emplace_back(LastStepRepeated(seconds), std::nullopt);
    }
    // A motion the device is sure of (its uncertainty given) rules that out.
    if (predictions.empty() || !predictions.front().second)
      predictions.emplace_back(last_->pose, std::nullopt);
    first_prediction = predictions.front().first;
    // The windows from --track-radius's, or from the guided one when that holds twice the last
    // prediction's error: a steady stream's prediction is a few pixels off and its frames are
    // matched there at once. A jerky stream's errors do not carry over from frame to frame:
    // starting wider after a frame that needed it made herz_jesu_p25's photos slower.
    const double radius_px = tracker_options_.radius_px;
    std::vector<double> windows = {radius_px, kWiderWindow * radius_px};
    const double guided_px = options_.guide_radius_px;
    if (guided_px < radius_px && last_->prediction_error_px &&
        2.0 * *last_->prediction_error_px <= guided_px)
      windows.insert(windows.begin(), guided_px);
    std::optional<MatchedFrame> matched;  // the last pose the matching found
    for (const double radius : windows) {
      for (const auto& [predicted, uncertainty] : predictions) {
        TrackingInfo attempt = info;
        // A pose matched from another prediction, which its checks refused, may pass this
        // one's: matching from here would find it again (herz_jesu_p25's frame 0017, after the
        // jump between its passes, did so at twice the time).
        if (!matched || !Trusted(*matched, predicted, uncertainty, &attempt)) {
          std::optional<MatchedFrame> fresh = MatchNear(frame, predicted, radius);
          if (!fresh) continue;
          matched = std::move(fresh);
          if (!Trusted(*matched, predicted, uncertainty, &attempt)) continue;
        }
        result = std::move(matched->result);
        info = attempt;
        info.mode = TrackingMode::kTracked;
        tracked_from = predicted;
        break;
      }
      if (result) break;
    }
  }
  if (!result) {
    result = localizer_.Localize(frame, options_);
    info.mode = result->success ? TrackingMode::kRelocalized : TrackingMode::kLost;
    info.prediction_error.reset();
    info.prediction_error_deg.reset();
    if (result->success && first_prediction) {
      const CameraPose pose = CameraPoseOf(*result);
      info.prediction_error = (pose.Center() - first_prediction->Center()).norm();
      info.prediction_error_deg = RotationAngleDeg(pose, *first_prediction);
    }
  }

  if (result->success) {
    PosedFrame posed;
    posed.name = frame.name;
    posed.pose = CameraPoseOf(*result);
    posed.seconds = seconds;
    posed.camera_and_pose.pose = posed.pose;
    posed.camera_and_pose.model_id = ModelIdOf(result->camera);
    posed.camera_and_pose.params = result->camera.params;
    posed.inlier_views.reserve(result->inliers.size());
    for (const Inlier& inlier : result->inliers) posed.inlier_views.push_back(inlier.view);
    if (tracked_from)
      posed.prediction_error_px =
          PredictionErrorPx(localizer_.index(), frame, *result, *tracked_from);
    before_last_ = std::move(last_);
    last_ = std::move(posed);
  } else {
    before_last_.reset();  // the motion since the last pose is unknown
  }
  info.seconds = time.Seconds();
  // The frame's whole time; the stages' are those of its last matching round.
  result->times.total = info.seconds + result->times.extraction;
  result->tracking = std::move(info);
  return std::move(*result);
}

}  // namespace cwloc
