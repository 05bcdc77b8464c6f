// A frame of several images localized as one generalized camera (cwloc-localize --rig,
// --frames; docs/algorithm.md, "Rigs and multi-frame queries"): what LocalizeRig returns, the
// APIs hand out and the JSON record's rig_frame (results/describe.h). Transforms as COLMAP names
// them: an image's cam_from_world = cam_from_rig * rig_from_world.
#ifndef CWLOC_RESULTS_RIG_RESULT_H_
#define CWLOC_RESULTS_RIG_RESULT_H_

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera.h"
#include "describe.h"
#include "geo_pose.h"
#include "localization_result.h"
#include "pose.h"

namespace cwloc {

struct RigImageResult {
  std::string name;
  Transform cam_from_rig;
  std::optional<Pose> pose;  // cam_from_world, when the rig was localized
  CameraUsed camera;         // as the rig used it: a focal prior refined with the rig pose
  uint32_t num_inliers = 0;  // the rig's inliers in this image
  // The paper's matching on the image (no pose stage of its own).
  uint32_t num_features = 0;
  uint32_t forward_matches = 0;
  uint32_t back_matches = 0;
  uint32_t correspondences = 0;
  std::vector<Inlier> inliers;  // the rig's inliers in this image, in feature order
};

// The rig's pose and how it was found.
struct RigPoseInfo {
  std::string reference_image;  // the frame's first image, whose pose is the frame's
  std::optional<Pose> rig_from_world;
  bool unknown_scale = false;
  double scale = 1;  // estimated when unknown_scale
  std::optional<double> scale_std;
  uint32_t num_inliers = 0;      // over all images
  uint32_t correspondences = 0;  // pooled 2D-3D pairs given to RANSAC
  uint32_t ransac_iterations = 0;
  bool refined = false;
  std::optional<double> mean_reprojection_error_px;  // on success
};

struct RigStageTimes {
  double images = 0;  // the images' own pipelines, photo extraction excluded
  double rig_pose = 0;
  double total = 0;
};

struct RigResult {
  std::string name;
  bool success = false;
  std::string failure_reason;  // empty on success
  std::optional<Pose> pose;    // the frame's: its reference camera's cam_from_world
  RigPoseInfo rig;
  // The rig pose's uncertainty over (theta, C) as for a camera, widened by the index's
  // calibration for the reference image's calibration mode.
  std::optional<PoseCovariance> covariance;
  std::optional<GeoPose> geo;  // the reference camera's, with a georeferenced index
  std::vector<RigImageResult> images;
  RigStageTimes times;
};

inline bool Failed(const RigResult& result) { return !result.success; }

template <>
struct Description<RigImageResult> {
  using I = RigImageResult;
  static constexpr std::string_view name = "RigImageResult";
  static constexpr std::string_view help = "One image of a rig frame's answer";
  static constexpr auto fields = std::tuple(
      MakeField(&I::name, Info("name").Json("name")),
      MakeField(&I::cam_from_rig,
                Info("cam_from_rig")
                    .Json("cam_from_rig")
                    .Help("Where the camera sits on the rig: X_cam = R X_rig + t")),
      MakeField(&I::pose, Info("pose").Json("pose").Help(
                              "Its cam_from_world from the rig's pose (what --poses writes "
                              "for it)")),
      MakeField(&I::camera,
                Info("camera").Json("camera").Help(
                    "As the rig used it: a focal prior's SIMPLE_RADIAL refined with the rig "
                    "pose")),
      MakeField(&I::num_inliers,
                Info("num_inliers").Json("num_inliers").Help("The rig's inliers in this image")),
      MakeField(&I::num_features, Info("num_features").Json("matches.features")),
      MakeField(&I::forward_matches, Info("forward_matches").Json("matches.forward")),
      MakeField(&I::back_matches, Info("back_matches").Json("matches.back")),
      MakeField(&I::correspondences, Info("correspondences").Json("matches.correspondences")),
      MakeField(&I::inliers, Info("inliers").AsColumns().WhyNot(
                                 "the JSON record, as a single result's inliers")));
};

template <>
struct Description<RigPoseInfo> {
  using P = RigPoseInfo;
  static constexpr std::string_view name = "RigPose";
  static constexpr std::string_view help = "A rig's pose and how it was found";
  static constexpr auto fields = std::tuple(
      MakeField(&P::reference_image,
                Info("reference_image")
                    .Json("reference_image")
                    .Help("The frame's first image, whose pose is the frame's")),
      MakeField(&P::rig_from_world,
                Info("rig_from_world")
                    .Json("rig_from_world")
                    .Help("X_rig = R X_world + t; center the rig's origin; on success")),
      MakeField(&P::unknown_scale,
                Info("unknown_scale")
                    .Json("unknown_scale")
                    .Help("The cam_from_rig translations were known up to one scale, estimated "
                          "here (--frames-scale unknown)")),
      MakeField(&P::scale,
                Info("scale").Json("scale").Help(
                    "Model units per unit of the cam_from_rig translations (1 when known)")),
      MakeField(&P::scale_std, Info("scale_std").Json("scale_std")),
      MakeField(&P::num_inliers,
                Info("num_inliers").Json("num_inliers").Help("RANSAC inliers over all images")),
      MakeField(&P::correspondences,
                Info("correspondences")
                    .Json("correspondences")
                    .Help("The images' 2D-3D pairs pooled for the rig's RANSAC")),
      MakeField(&P::ransac_iterations, Info("ransac_iterations").Json("ransac_iterations")),
      MakeField(&P::refined, Info("refined").Json("refined").Help(
                                 "The final refinement of the rig pose was kept")),
      MakeField(&P::mean_reprojection_error_px, Info("mean_reprojection_error_px")
                                                    .Json("mean_reprojection_error_px")
                                                    .Unit("px")
                                                    .Help("Over the inliers, on success")));
};

template <>
struct Description<RigStageTimes> {
  static constexpr std::string_view name = "RigStageTimes";
  static constexpr std::string_view help = "Wall-clock time of a rig frame's stages";
  static constexpr auto fields = std::tuple(
      MakeField(
          &RigStageTimes::images,
          result_fields::Stage("images", "The images' own pipelines, photo extraction excluded")),
      MakeField(&RigStageTimes::rig_pose,
                result_fields::Stage("rig_pose", "The rig's RANSAC, refinement and covariance")),
      MakeField(&RigStageTimes::total,
                result_fields::Stage("total", "The whole frame, photo extraction included")));
};

template <>
struct Description<RigResult> {
  using R = RigResult;
  static constexpr std::string_view name = "RigResult";
  static constexpr std::string_view help =
      "A rig frame's answer: the frame's pose (its reference camera's), the rig's, and every "
      "image's cam_from_world = cam_from_rig * rig_from_world";
  static constexpr auto fields = std::tuple(
      MakeField(&R::name, Info("name").Json("name").Help(
                              "The frame's id: a --frames FRAME_ID, or the image name after "
                              "a rig camera's image_prefix")),
      MakeField(&R::success, Info("success").Json("success")),
      MakeField(&R::failure_reason, Info("failure_reason").Json("failure_reason"), &Failed),
      MakeField(&R::pose, Info("pose").Json("pose").Help(
                              "The frame's pose: its reference camera's cam_from_world")),
      MakeField(&R::rig, Info("rig").Json("rig")),
      MakeField(
          &R::covariance,
          Info("covariance").Json("covariance").Help("The rig pose's, over (theta, C) of the rig")),
      MakeField(&R::geo, Info("geo").Json("geo").Help(
                             "The reference camera on the globe (georeferenced index)")),
      MakeField(&R::images, Info("images").Json("images").Help("Per image, the reference first")),
      MakeField(&R::times, Info("times").Json("times_ms")));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_RIG_RESULT_H_
