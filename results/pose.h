// Poses and their uncertainty as results report them (results/describe.h).
#ifndef CWLOC_RESULTS_POSE_H_
#define CWLOC_RESULTS_POSE_H_

#include <array>
#include <optional>

#include "describe.h"

namespace cwloc {

// A rigid transform as COLMAP names them, e.g. cam_from_rig: X_cam = R(rotation) X_rig +
// translation, rotation a unit quaternion (w, x, y, z).
struct Transform {
  std::array<double, 4> rotation{1, 0, 0, 0};
  std::array<double, 3> translation{};
};

// A pose from the world: X_cam = R(rotation) X_world + translation; center = -R^T translation,
// the camera's (or rig's) origin in the model frame.
struct Pose : Transform {
  std::array<double, 3> center{};
};

// What the index's calibration (model images left out and localized when it was built)
// multiplied a pose covariance by: its rotation block by `rotation`, its centre block by
// `position`, the cross terms by the root of both.
struct CovarianceScales {
  double rotation = 1;
  double position = 1;
};

// How well a refined pose is known (docs/algorithm.md, "Pose uncertainty").
struct PoseCovariance {
  // 6 x 6, row-major, over (theta, C): theta the rotation vector (radians, model frame) of the
  // camera orientation's error, world_from_cam_estimate = exp([theta]x) world_from_cam_true; C
  // the camera centre (model units).
  std::array<double, 36> pose{};
  double position_radius95 = 0;  // C's 95 % ellipsoid lies within this radius
  std::optional<double> focal_std_px;
  std::optional<CovarianceScales> calibration;
  std::optional<std::array<double, 9>> enu_position;  // square metres, row-major
  std::optional<double> position_radius95_m;
};

namespace pose_fields {
inline constexpr auto kRotation = MakeField(
    &Transform::rotation, Info("rotation").Json("qvec").Help("Unit quaternion (w, x, y, z)"));
inline constexpr auto kTranslation =
    MakeField(&Transform::translation, Info("translation").Json("tvec"));
}  // namespace pose_fields

template <>
struct Description<Transform> {
  static constexpr std::string_view name = "Transform";
  static constexpr std::string_view help =
      "A rigid transform as COLMAP names them: X_to = R(rotation) X_from + translation";
  static constexpr auto fields = std::tuple(pose_fields::kRotation, pose_fields::kTranslation);
};

template <>
struct Description<Pose> {
  static constexpr std::string_view name = "Pose";
  static constexpr std::string_view help =
      "COLMAP's world-to-camera pose: X_cam = R(rotation) X_world + translation; center = -R^T "
      "translation";
  static constexpr auto fields = std::tuple(
      pose_fields::kRotation, pose_fields::kTranslation,
      MakeField(
          &Pose::center,
          Info("center").Json("center").Unit("model units").Help("The origin in the model frame")));
};

template <>
struct Description<CovarianceScales> {
  static constexpr std::string_view name = "CovarianceScales";
  static constexpr std::string_view help =
      "What the index's calibration multiplied a pose covariance's blocks by";
  static constexpr auto fields =
      std::tuple(MakeField(&CovarianceScales::rotation,
                           Info("rotation").Json("rotation_scale").Help("The rotation block's")),
                 MakeField(&CovarianceScales::position,
                           Info("position").Json("position_scale").Help("The centre block's")));
};

template <>
struct Description<PoseCovariance> {
  static constexpr std::string_view name = "PoseCovariance";
  static constexpr std::string_view help =
      "How well the refined pose is known (docs/algorithm.md, 'Pose uncertainty'): from the "
      "final refinement's Jacobian and its inliers' residuals, widened by the index's "
      "calibration; an estimated focal length and distortion are marginalised out";
  static constexpr auto fields = std::tuple(
      MakeField(&PoseCovariance::pose,
                Info("pose")
                    .Json("pose")
                    .Help("6 x 6 over (theta, C): theta the rotation vector (radians, model frame) "
                          "of the orientation's error, C the centre (model units)")
                    .Rows(6)),
      MakeField(&PoseCovariance::position_radius95,
                Info("position_radius95")
                    .Json("position_radius95")
                    .Unit("model units")
                    .Help("The radius of the smallest sphere around the centre that holds its "
                          "95 % ellipsoid")),
      MakeField(&PoseCovariance::focal_std_px,
                Info("focal_std_px")
                    .Json("focal_std_px")
                    .Unit("px")
                    .Help("When the focal length was estimated: its standard deviation")),
      MakeField(&PoseCovariance::calibration,
                Info("calibration")
                    .Json("calibration")
                    .Help("What the index's calibration multiplied the covariance by; none when "
                          "the index has no calibration for the query's calibration mode")
                    .NullWhenAbsent()),
      MakeField(&PoseCovariance::enu_position,
                Info("enu_position")
                    .Json("enu_position")
                    .Unit("m^2")
                    .Help("Georeferenced index: the centre's 3 x 3 covariance in the local "
                          "east-north-up frame at the camera")
                    .Rows(3)),
      MakeField(&PoseCovariance::position_radius95_m,
                Info("position_radius95_m")
                    .Json("position_radius95_m")
                    .Unit("m")
                    .Help("Georeferenced index: position_radius95 in metres")));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_POSE_H_
