#pragma once

#include <array>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "localizer/localizer.h"
#include "results/localization_result.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// Tracking frames of one moving camera (docs/algorithm.md, "Sequences").
struct TrackerOptions {
  // The first matching's window around a point's projection under the predicted pose, pixels:
  // the views that matched the last frame's inliers, at most `rough_views` of them, give a rough
  // pose (a frame no prediction tracks is tried again with the window twice as wide). The frame
  // is then matched around that pose in the model images nearest it, as
  // guided back-matching matches a query around its first pose (with
  // LocalizerOptions::guide_radius_px), until the pose stops moving.
  double radius_px = 200.0;
  uint32_t rough_views = 100;
  // RANSAC's iterations on a tracked frame, whose matches near the prediction are mostly inliers.
  uint32_t max_ransac_iterations = 100;
  // A tracked pose farther than this from its prediction is not trusted and the frame is
  // localized from scratch: the rotation between them, and the distance between the centres
  // over the median depth of the frame's inliers.
  double max_rotation_change_deg = 30.0;
  double max_relative_position_change = 0.6;
};

// What the device knows of its own motion since the previous frame (visual-inertial
// odometry): the frame's camera from the previous frame's camera, COLMAP's convention
// (X_cam = R X_previous_cam + t). Its translation is in metres when `metric`: on a
// georeferenced index it becomes model units by the georeference's scale; otherwise (or on
// an index without one) only its direction counts, at the length of the last step between
// poses (the scale of a map without a georeference is unknown).
struct FrameMotion {
  CameraPose relative;
  bool metric = false;
  // How sure the device is of it, one standard deviation per axis, when it says (0: it does
  // not): the rotation in degrees and the translation in its own units (metres when metric).
  // The pose a tracked frame gets may then differ from the motion's prediction by at most
  // kMotionSigmas of the combined uncertainty (of the motion, of this pose and of the last);
  // a pose farther off is localized from scratch instead.
  double sigma_rotation_deg = 0.0;
  double sigma_position = 0.0;
};
// A metric motion from its parts as a motion file's line and the API give them: a rotation
// quaternion (w, x, y, z) of unit length within 1e-3 (then normalised), a finite translation in
// metres and sigmas finite and at least 0 (0: not known); else why not, for the caller to say
// where the motion came from.
std::variant<FrameMotion, std::string> MetricMotion(const std::array<double, 4>& rotation_wxyz,
                                                    const std::array<double, 3>& translation,
                                                    double sigma_rotation_deg,
                                                    double sigma_position);

// 99.9 % of a 3-D normal distribution lies within this many standard deviations per axis
// (the chi-square quantile's square root).
inline constexpr double kMotionSigmas = 4.03;

// Frames of one camera, in order: a frame's pose is predicted from the frames before it (the
// last pose moved by the last motion, or the last pose alone), the frame is matched near that
// prediction for a rough pose, then near the rough pose, and its pose fit to those matches with
// the same inlier checks as any query (tracked); when that
// fails or lands far from the prediction, the frame is localized from scratch (relocalized);
// when both fail it is lost: no pose, never a guessed one. One Tracker per stream; several on
// one Localizer may run on several threads.
class Tracker {
 public:
  // The localizer must outlive the tracker.
  Tracker(const Localizer& localizer, const LocalizerOptions& options,
          const TrackerOptions& tracker_options = {});

  // The frame's result, with its `tracking` set. With a motion the prediction is the last pose
  // moved by it, instead of by the last step. `seconds`, when the frame was seen: with those of
  // the two frames before, the last step is scaled to the time since the last frame (frames
  // without them are taken as evenly spaced). Throws InputError as Localizer::Localize does.
  LocalizationResult Track(const Query& frame, std::optional<double> seconds = std::nullopt,
                           const std::optional<FrameMotion>& motion = std::nullopt);
  // Forgets the frames so far: the next frame is localized from scratch.
  void Reset();

 private:
  struct PosedFrame {
    std::string name;
    CameraPose pose;  // cam_from_world
    std::optional<double> seconds;
    PoseHypothesis camera_and_pose;
    std::vector<uint32_t> inlier_views;
    // How far its prediction was off (PredictionErrorPx), when it was tracked.
    std::optional<double> prediction_error_px;
  };
  // A motion's uncertainty in model units and radians; no position when its step is unknown.
  struct MotionUncertainty {
    double rotation_rad = 0.0;
    std::optional<double> position;
  };
  // The factor that takes the motion's translation to model units (0: its length is unknown).
  double StepScale(const FrameMotion& motion) const;
  // Its sigmas in those units; nothing when the device gives none.
  std::optional<MotionUncertainty> UncertaintyOf(const FrameMotion& motion) const;
  // The last pose moved by the motion, its translation in model units.
  CameraPose Moved(const CameraPose& pose, const FrameMotion& motion) const;
  // The last pose moved by the last step, scaled to the time since the last frame when the
  // three frames' times are known.
  CameraPose LastStepRepeated(std::optional<double> seconds) const;
  // A frame's pose matched near a prediction, and the median depth of its inliers.
  struct MatchedFrame {
    LocalizationResult result;
    double depth = 0.0;
  };
  // The frame matched near a prediction: a rough pose in the window of `radius_px`, then
  // rounds around it until it stops moving; nothing when a round finds no pose.
  std::optional<MatchedFrame> MatchNear(const Query& frame, const CameraPose& predicted,
                                        double radius_px) const;
  // Whether the pose may be the frame's tracked pose from this prediction (the checks of
  // TrackerOptions and, with the motion's uncertainty, within it); sets the prediction errors.
  bool Trusted(const MatchedFrame& matched, const CameraPose& predicted,
               const std::optional<MotionUncertainty>& uncertainty, TrackingInfo* info) const;

  const Localizer& localizer_;
  LocalizerOptions options_;
  LocalizerOptions rough_options_;     // the rough pose's: no refinement
  LocalizerOptions tracking_options_;  // options_ with the tracker's RANSAC iterations
  TrackerOptions tracker_options_;
  std::optional<PosedFrame> last_;
  std::optional<PosedFrame> before_last_;  // the frame just before last_, when it had a pose
};

}  // namespace cwloc
