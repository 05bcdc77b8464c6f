#include "localizer/tracker.h"

#include <algorithm>
#include <cmath>
#include <numbers>

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

CameraPose PoseOf(const LocalizationResult& result) {
  const auto& q = result.rotation;
  const auto& t = result.translation;
  return {Eigen::Quaterniond(q[0], q[1], q[2], q[3]), Eigen::Vector3d(t[0], t[1], t[2])};
}

double RotationAngleDeg(const CameraPose& a, const CameraPose& b) {
  return a.rotation.angularDistance(b.rotation) * 180.0 / std::numbers::pi;
}

std::vector<uint32_t> InlierPoints(const LocalizationResult& result) {
  std::vector<uint32_t> points;
  points.reserve(result.inliers.size());
  for (const InlierMatch& inlier : result.inliers) points.push_back(inlier.point);
  return points;
}

// `pose` moved by `relative` (both cam_from_something): relative * pose.
CameraPose Then(const CameraPose& pose, const CameraPose& relative) {
  return {relative.rotation * pose.rotation,
          relative.rotation * pose.translation + relative.translation};
}

}  // namespace

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
  rough_options_.pose.refine = false;
}

CameraPose Tracker::Moved(const CameraPose& pose, const FrameMotion& motion) const {
  Eigen::Vector3d step = motion.relative.translation;
  const auto& geo = localizer_.geo();
  if (motion.metric && geo) {
    step /= geo->frame().georeference().scale;  // metres to model units
  } else if (before_last_) {
    // Up to scale: the direction, at the length of the last step between camera centres.
    const double length = (last_->pose.Center() - before_last_->pose.Center()).norm();
    const double norm = step.norm();
    step = norm > 0 ? Eigen::Vector3d(step * (length / norm)) : Eigen::Vector3d::Zero();
  } else {
    step.setZero();  // no step to take the length from: the rotation alone
  }
  return Then(pose, CameraPose(motion.relative.rotation, step));
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

std::optional<LocalizationResult> Tracker::TrackFrom(const Query& frame,
                                                     const CameraPose& predicted,
                                                     TrackingInfo* info) const {
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
  prediction.radius_px = tracker_options_.radius_px;
  const LocalizationResult rough = localizer_.Localize(frame, rough_options_, &prediction);
  if (!rough.success) return std::nullopt;

  // Matched again around the pose of the round before, until it stops moving: a rough pose
  // from a poor prediction keeps only the matches that agree with it.
  prediction.views.clear();
  prediction.nearest_images_first = true;
  prediction.radius_px = options_.guide_radius_px;
  CameraPose around = PoseOf(rough);
  const LocalizationResult* before = &rough;
  prediction.seen_points = InlierPoints(rough);
  std::optional<LocalizationResult> result;
  double depth = 0;
  for (int round = 0; round < kMaxMatchingRounds; ++round) {
    prediction.hypothesis.pose = around;
    if (!frame.camera.FocalKnown()) prediction.hypothesis.params = before->camera.params;
    result = localizer_.Localize(frame, tracking_options_, &prediction);
    if (!result->success) return std::nullopt;
    const CameraPose pose = PoseOf(*result);
    // The next round's points; a successful pose has inliers, whose rows the localizer checked.
    prediction.seen_points = InlierPoints(*result);
    depth = *MedianPointDepth(localizer_.index(), prediction.seen_points, pose);
    const bool still = RotationAngleDeg(pose, around) <= kStillDeg &&
                       (pose.Center() - around.Center()).norm() <= kStillDepthShare * depth;
    around = pose;
    before = &*result;
    if (still) break;
  }

  // `around` is the last round's pose, `depth` its inliers' median depth.
  const double rotation_deg = RotationAngleDeg(around, predicted);
  const double distance = (around.Center() - predicted.Center()).norm();
  info->prediction_error = distance;
  info->prediction_error_deg = rotation_deg;
  if (!(rotation_deg <= tracker_options_.max_rotation_change_deg) ||
      !(distance <= tracker_options_.max_relative_position_change * depth))
    return std::nullopt;
  return result;
}

LocalizationResult Tracker::Track(const Query& frame, std::optional<double> seconds,
                                  const std::optional<FrameMotion>& motion) {
  const Stopwatch time;
  TrackingInfo info;
  if (frame.NumFeatures() == 0 && frame.descriptors.empty()) {
    // A black or blurred frame is part of a stream, not bad input: it is lost.
    LocalizationResult lost;
    lost.name = frame.name;
    lost.camera = frame.camera;
    lost.photo = frame.photo;
    lost.failure_reason = "the frame has no features";
    lost.times.extraction = frame.photo ? frame.photo->extraction_seconds : 0.0;
    if (last_) info.predicted_from = last_->name;
    before_last_.reset();
    info.seconds = time.Seconds();
    lost.times.total = info.seconds + lost.times.extraction;
    lost.tracking = std::move(info);
    return lost;
  }
  std::optional<LocalizationResult> result;
  std::optional<CameraPose> first_prediction;
  if (last_) {
    info.predicted_from = last_->name;
    // The given motion or the last step repeated, then the last pose alone (a camera that
    // stopped or turned).
    std::vector<CameraPose> predictions;
    if (motion) {
      predictions.push_back(Moved(last_->pose, *motion));
    } else if (before_last_) {
      predictions.push_back(LastStepRepeated(seconds));
    }
    predictions.push_back(last_->pose);
    first_prediction = predictions.front();
    for (const CameraPose& predicted : predictions) {
      TrackingInfo attempt = info;
      result = TrackFrom(frame, predicted, &attempt);
      if (result) {
        info = attempt;
        info.mode = TrackingMode::kTracked;
        break;
      }
    }
  }
  if (!result) {
    result = localizer_.Localize(frame, options_);
    info.mode = result->success ? TrackingMode::kRelocalized : TrackingMode::kLost;
    info.prediction_error.reset();
    info.prediction_error_deg.reset();
    if (result->success && first_prediction) {
      const CameraPose pose = PoseOf(*result);
      info.prediction_error = (pose.Center() - first_prediction->Center()).norm();
      info.prediction_error_deg = RotationAngleDeg(pose, *first_prediction);
    }
  }

  if (result->success) {
    PosedFrame posed;
    posed.name = frame.name;
    posed.pose = PoseOf(*result);
    posed.seconds = seconds;
    posed.camera_and_pose.pose = posed.pose;
    posed.camera_and_pose.model_id = result->camera.model_id;
    posed.camera_and_pose.params = result->camera.params;
    posed.inlier_views.reserve(result->inliers.size());
    for (const InlierMatch& inlier : result->inliers) posed.inlier_views.push_back(inlier.view);
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
