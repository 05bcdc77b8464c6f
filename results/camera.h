// A query's camera: as a caller gives it, and as a result reports it (results/describe.h).
#ifndef CWLOC_RESULTS_CAMERA_H_
#define CWLOC_RESULTS_CAMERA_H_

#include <optional>
#include <string>
#include <vector>

#include "describe.h"

namespace cwloc {

// What the pose stage may trust about the query camera; COLMAP's registrator draws the same
// line with prior_focal_length.
enum class Calibration : int {
  kKnown = 0,       // every parameter is trusted and held fixed
  kFocalPrior = 1,  // params hold a focal guess (EXIF, --focal): it seeds the estimate
  kUnknown = 2,     // only the image size: P4Pf estimates the focal
};
template <>
struct EnumNames<Calibration> {
  static constexpr std::array<std::string_view, 3> names = {"known", "focal-prior", "unknown"};
};

// Where the query camera came from.
enum class IntrinsicsSource : int {
  kCameraOption,     // --camera (and the API's camera)
  kQueryList,        // a query-list line's "MODEL W H PARAMS"
  kImageSizeOption,  // --image-size
  kFocalOption,      // --focal
  kExif,             // the photo's EXIF focal length
  kDatabase,         // the COLMAP database's camera
  kNone,             // nothing but the photo's size
};
template <>
struct EnumNames<IntrinsicsSource> {
  static constexpr std::array<std::string_view, 7> names = {
      "camera-option", "query-list", "image-size-option", "focal-option", "exif",
      "database",      "none"};
};

// A camera in COLMAP's terms. For kUnknown only the size counts; for kFocalPrior the model's
// mean focal length is the guess and the principal point is taken at the image centre.
struct Camera {
  std::string model;  // COLMAP's model name: SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, OPENCV, ...
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<double> params;  // COLMAP's order
  Calibration calibration = Calibration::kKnown;
};

// A camera as a localization used it: estimated (SIMPLE_RADIAL) unless it was known.
struct CameraUsed : Camera {
  IntrinsicsSource intrinsics_source = IntrinsicsSource::kCameraOption;
};

// How a localized query's lens distortion was fitted.
enum class DistortionFit : int {
  kGiven,       // a known camera: its own model and parameters, held fixed
  kEstimated,   // SIMPLE_RADIAL's k refined with the focal length
  kHeldAtZero,  // focal estimated, k left at 0: the refinement did not run or kept no camera
};
template <>
struct EnumNames<DistortionFit> {
  static constexpr std::array<std::string_view, 3> names = {"given", "estimated", "held-at-zero"};
};

struct Distortion {
  std::string model;
  DistortionFit fit = DistortionFit::kGiven;
  std::optional<double> k;
  std::optional<double> k_std;
  std::optional<bool> k_significant;
  std::string why;
};

// The camera of a single query's result.
struct ResultCamera : CameraUsed {
  bool focal_estimated = false;
  std::optional<Distortion> distortion;  // on success
};

// An estimated focal length: how well it is told apart from the camera's distance.
struct FocalDepth {
  double correlation = 0;  // between the focal length and that depth, in [-1, 1]
  double focal_std_px = 0;
  double depth_std = 0;  // of the camera centre along its optical axis, model units
  bool weakly_constrained = false;
};

namespace camera_fields {
inline constexpr auto kModel =
    MakeField(&Camera::model, Info("model").Json("model").Help("COLMAP's camera model"));
inline constexpr auto kWidth = MakeField(&Camera::width, Info("width").Json("width").Unit("px"));
inline constexpr auto kHeight =
    MakeField(&Camera::height, Info("height").Json("height").Unit("px"));
inline constexpr auto kParams =
    MakeField(&Camera::params, Info("params").Json("params").Help("COLMAP's order for the model"));
inline constexpr auto kCalibration = MakeField(
    &Camera::calibration,
    Info("calibration")
        .Json("calibration")
        .Help("What the pose stage trusted: every parameter, a focal guess it refined, or only the "
              "image size"));
inline constexpr auto kIntrinsicsSource =
    MakeField(&CameraUsed::intrinsics_source,
              Info("intrinsics_source")
                  .Json("intrinsics_source")
                  .Help("Where the camera came from: --camera, a query-list line, --image-size, "
                        "--focal, the photo's EXIF, the COLMAP database, or nothing but its size"));
inline constexpr auto kFocalEstimated = MakeField(
    &ResultCamera::focal_estimated,
    Info("focal_estimated").Json("focal_estimated").Help("Whether the focal length was estimated"));
inline constexpr auto kDistortion = MakeField(
    &ResultCamera::distortion,
    Info("distortion")
        .Json("distortion")
        .Help("A localized query's lens distortion: the model it was fitted with, and why"));
}  // namespace camera_fields

template <>
struct Description<Camera> {
  static constexpr std::string_view name = "Camera";
  static constexpr std::string_view help = "A camera in COLMAP's terms";
  static constexpr auto fields =
      std::tuple(camera_fields::kModel, camera_fields::kWidth, camera_fields::kHeight,
                 camera_fields::kParams, camera_fields::kCalibration);
};

template <>
struct Description<CameraUsed> {
  static constexpr std::string_view name = "CameraUsed";
  static constexpr std::string_view help = "A camera as a localization used it";
  static constexpr auto fields = std::tuple(
      camera_fields::kModel, camera_fields::kWidth, camera_fields::kHeight, camera_fields::kParams,
      camera_fields::kCalibration, camera_fields::kIntrinsicsSource);
};

template <>
struct Description<ResultCamera> {
  static constexpr std::string_view name = "ResultCamera";
  static constexpr std::string_view help =
      "The camera a query was localized with: estimated (SIMPLE_RADIAL) unless it was known";
  static constexpr auto fields = std::tuple(
      camera_fields::kModel, camera_fields::kWidth, camera_fields::kHeight, camera_fields::kParams,
      camera_fields::kFocalEstimated, camera_fields::kCalibration, camera_fields::kIntrinsicsSource,
      camera_fields::kDistortion);
};

template <>
struct Description<Distortion> {
  static constexpr std::string_view name = "Distortion";
  static constexpr std::string_view help =
      "How a localized query's lens distortion was fitted (docs/algorithm.md, section 4)";
  static constexpr auto fields = std::tuple(
      MakeField(&Distortion::model,
                Info("model").Json("model").Help(
                    "The camera model of params (SIMPLE_RADIAL when the focal length was "
                    "estimated)")),
      MakeField(&Distortion::fit,
                Info("fit").Json("fit").Help(
                    "given: a known camera's, held fixed; estimated: SIMPLE_RADIAL's k refined "
                    "with the focal length; held-at-zero: the focal length estimated without "
                    "the final refinement, k = 0")),
      MakeField(&Distortion::k,
                Info("k").Json("k").Help("SIMPLE_RADIAL's radial distortion (fit estimated or "
                                         "held-at-zero)")),
      MakeField(&Distortion::k_std,
                Info("k_std").Json("k_std").Help(
                    "k's standard deviation from the final refinement's covariance")),
      MakeField(
          &Distortion::k_significant,
          Info("k_significant").Json("k_significant").Help("|k| >= 2 k_std: the data constrain k")),
      MakeField(&Distortion::why, Info("why").Json("why").Help("Why this fit")));
};

template <>
struct Description<FocalDepth> {
  static constexpr std::string_view name = "FocalDepth";
  static constexpr std::string_view help =
      "An estimated and refined focal length: how well it is told apart from the camera's "
      "distance to the scene, from the final refinement's covariance";
  static constexpr auto fields = std::tuple(
      MakeField(&FocalDepth::correlation,
                Info("correlation")
                    .Json("correlation")
                    .Help("Between the focal length and the camera centre's position along its "
                          "optical axis")),
      MakeField(&FocalDepth::focal_std_px, Info("focal_std_px")
                                               .Json("focal_std_px")
                                               .Unit("px")
                                               .Help("Standard deviation of the focal length")),
      MakeField(&FocalDepth::depth_std,
                Info("depth_std")
                    .Json("depth_std")
                    .Unit("model units")
                    .Help("Standard deviation of the camera centre along its optical axis")),
      MakeField(&FocalDepth::weakly_constrained,
                Info("weakly_constrained")
                    .Json("weakly_constrained")
                    .Help("focal_std_px above 0.5 % of the focal length and |correlation| >= 0.95: "
                          "the camera's distance is uncertain by about as much")));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_CAMERA_H_
