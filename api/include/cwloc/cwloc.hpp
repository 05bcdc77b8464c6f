#pragma once

// cwloc's C++ API for apps: open an index file once (read-only memory map), then localize
// queries (SIFT features, a photo file, an encoded photo in memory or a grey image) from any
// number of threads. Everything here is plain standard C++; docs/api.md has the details and
// cwloc.h the same API for C.

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "cwloc/result_types.h"

#if defined(__GNUC__)
#define CWLOC_API __attribute__((visibility("default")))
#else
#define CWLOC_API
#endif

namespace cwloc::api {

// What went wrong; the values are the C API's cwloc_status codes.
enum class ErrorCode : int {
  kInvalidArgument = 1,  // an argument the caller got wrong (bad option, bad camera)
  kBadInput = 2,         // a file or buffer that cannot be used (corrupt index, broken photo)
  kOutOfMemory = 3,
  kInternal = 4,  // a bug: please report it
};

// Thrown by every function here; what() names the file or argument and the problem.
class CWLOC_API Error : public std::runtime_error {
 public:
  Error(ErrorCode code, const std::string& message);
  ErrorCode code() const { return code_; }

 private:
  ErrorCode code_;
};

// What the pose stage may trust about the camera (COLMAP's prior_focal_length).
enum class Calibration : int {
  kKnown = 0,       // every parameter is held fixed
  kFocalPrior = 1,  // the focal length is a guess: refined with a radial distortion term
  kUnknown = 2,     // only the image size: the focal length is estimated (P4Pf)
};

// A camera in COLMAP's terms: model name (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL,
// OPENCV, ...) and its parameters in COLMAP's order. For kUnknown only width and height count.
// For kFocalPrior the model's mean focal length is the guess; the principal point is taken at
// the image centre.
struct Camera {
  std::string model;
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<double> params;
  Calibration calibration = Calibration::kKnown;
};

// A query's own SIFT features: keypoints in COLMAP's pixel convention (the image's top-left
// corner is (0, 0), a pixel centre is at +0.5) and N x 128 uint8 descriptors in COLMAP's
// normalisation (what colmap feature_extractor stores).
struct Features {
  std::vector<float> keypoints;      // x0, y0, x1, y1, ...
  std::vector<uint8_t> descriptors;  // N * 128
};

// A GPS fix: the query was taken within radius_m of this WGS84 position (horizontally when the
// height is unknown). Only clusters with a model camera that near are matched. Needs a
// georeferenced index (IndexInfo::georeferenced).
struct PositionPrior {
  double latitude_deg = 0;         // [-90, 90]
  double longitude_deg = 0;        // east
  std::optional<double> height_m;  // above the WGS84 ellipsoid (not above sea level)
  double radius_m = 0;             // > 0
};

// The knobs of cwloc-localize, with its defaults (set by the constructor): one field per line
// of <cwloc/options.inc>, named there with its cwloc-localize flag, range and meaning
// (docs/cli.md). Values are checked when a query runs, as the CLI checks its flags: a bad one
// throws Error(kInvalidArgument) with the CLI's message ("--nb 0: expected at least 1").
struct CWLOC_API Options {
  Options();

#define CWLOC_OPTION(field, type, ...) type field;
#include "cwloc/options.inc"
#undef CWLOC_OPTION

  // Sets the option named by its flag without dashes ("nb", "matcher"), from text as
  // cwloc-localize takes it or from a number; throws Error(kInvalidArgument) with the CLI's
  // message for an unknown name or a value out of range.
  void Set(const std::string& name, const std::string& value);
  void Set(const std::string& name, double value);

  // Priors (docs/geo.md); each needs a georeferenced index. gravity is the direction gravity
  // pulls in the camera frame (x right, y down, z forward), of any non-zero length. The
  // position prior wins over a photo's EXIF GPS (use_exif_gps).
  std::optional<PositionPrior> position_prior;   // --prior-position
  std::optional<std::array<double, 3>> gravity;  // --prior-gravity
};

// A model image and its votes, a stage's seconds, a camera on the globe: the localizer's own
// plain types (cwloc/result_types.h).
using cwloc::CovarianceScales;
using cwloc::GeoPose;
using cwloc::RankedImage;
using cwloc::StageTimes;
// How a Tracker's frame got its pose: mode (kTracked, kRelocalized, kLost), predicted_from,
// prediction_error (model units), prediction_error_deg, seconds.
using cwloc::TrackingMode;
using Tracking = cwloc::TrackingInfo;

// A RANSAC inlier of the reported pose.
struct Inlier {
  uint32_t feature = 0;             // row of the query's features
  std::array<float, 2> keypoint{};  // its pixel
  uint32_t point = 0;               // row of the index's 3D points
  std::array<double, 3> xyz{};      // the point, model frame
};

// How well the refined pose is known (docs/algorithm.md, "Pose uncertainty"): from the final
// refinement's Jacobian and its inliers' reprojection residuals; an estimated focal length and
// distortion are marginalised out.
struct PoseCovariance {
  // 6 x 6, row-major, over (theta, C): theta the rotation vector (radians, model frame) of the
  // error of the camera's orientation, world_from_cam_estimate = exp([theta]x) world_from_cam_true, and
  // C the camera centre (model units).
  std::array<double, 36> pose{};
  double position_radius95 = 0;        // model units: C's 95 % ellipsoid lies within it
  std::optional<double> focal_std_px;  // when the focal length was estimated
  // What the index's calibration widened `pose` by; empty when the index has none for the
  // query's calibration mode (the covariance then knows the keypoints' noise only).
  std::optional<CovarianceScales> calibration;
  // A georeferenced index: C's 3 x 3 covariance in square metres, row-major, in the local
  // east-north-up frame at the camera, and its 95 % radius in metres.
  std::optional<std::array<double, 9>> enu_position;
  std::optional<double> position_radius95_m;
};

struct Result {
  bool success = false;
  std::string failure_reason;  // why not, when success is false
  // COLMAP's cam_from_world: X_cam = R(rotation) X_world + translation; rotation = (w, x, y, z).
  std::array<double, 4> rotation{1, 0, 0, 0};
  std::array<double, 3> translation{};
  std::array<double, 3> center{};  // the camera centre in the model frame
  Camera camera;                   // as used; estimated (SIMPLE_RADIAL) unless it was known
  bool focal_estimated = false;
  // The result's numbers (num_inliers, the match counts, ...): one field per line of
  // <cwloc/result_fields.inc>, which says what each counts.
#define CWLOC_RESULT_FIELD(name, type, group, key, help) type name{};
#include "cwloc/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  std::vector<Inlier> inliers;  // on success
  std::vector<RankedImage> ranked_images;
  StageTimes times;
  std::optional<GeoPose> geo;  // on success with a georeferenced index
  // What the priors did. The position prior used: Options::position_prior, else the photo's
  // EXIF GPS (Options::use_exif_gps).
  std::optional<PositionPrior> position_prior;
  uint32_t clusters_in_radius = 0;  // clusters with a model camera within the position prior
  std::optional<std::array<double, 3>> gravity;  // the gravity prior used (Options::gravity)
  // The angle between the gravity prior and the localized pose's gravity; on success with one.
  std::optional<double> gravity_error_deg;
  std::optional<PoseCovariance> covariance;  // on success
  std::optional<Tracking> tracking;          // a frame that a Tracker took
  // The JSON record cwloc-localize writes for this query (schemas/localization-result.schema.json).
  std::string json;
};

// One image of a multi-image query (docs/api.md, "Rigs and multi-frame queries"): a rig's
// frame, or a window of video frames whose relative poses VIO knows. Its SIFT features with a
// camera, or a photo file (its EXIF focal length a prior without a camera); and where its camera
// sits, COLMAP's cam_from_rig: X_cam = R(rotation) X_rig + translation, rotation (w, x, y, z) of
// unit length. The first image is the reference camera; the camera must be known or a focal
// prior.
struct RigImage {
  std::string name;        // in the result and in error messages
  Features features;       // used when photo_path is empty
  std::string photo_path;  // a JPEG or PNG file instead
  std::optional<Camera> camera;
  std::array<double, 4> cam_from_rig_rotation{1, 0, 0, 0};
  std::array<double, 3> cam_from_rig_translation{};
};

struct RigImageResult {
  std::string name;
  bool posed = false;  // the rig was localized: cam_from_world = cam_from_rig * rig_from_world
  std::array<double, 4> rotation{1, 0, 0, 0};  // cam_from_world
  std::array<double, 3> translation{};
  std::array<double, 3> center{};
  uint32_t num_inliers = 0;  // the rig's inliers in this image
  Camera camera;             // as used: a focal prior refined with the rig pose
};

struct RigResult {
  bool success = false;
  std::string failure_reason;
  // rig_from_world: X_rig = R(rotation) X_world + translation; center is the rig's origin.
  std::array<double, 4> rotation{1, 0, 0, 0};
  std::array<double, 3> translation{};
  std::array<double, 3> center{};
  double scale = 1;  // model units per cam_from_rig translation unit (estimated if unknown)
  std::optional<double> scale_std;
  uint32_t num_inliers = 0;      // over all images
  uint32_t correspondences = 0;  // pooled 2D-3D pairs
  // The rig pose's covariance over (theta, C) as PoseCovariance defines it for a camera.
  std::optional<PoseCovariance> covariance;
  std::optional<GeoPose> geo;  // the reference camera's, with a georeferenced index
  std::vector<RigImageResult> images;
  // The JSON record cwloc-localize --frames writes for this frame.
  std::string json;
};

struct IndexInfo {
  std::string path;
  std::string format_version;  // "MAJOR.MINOR"
  uint32_t num_images = 0;
  uint32_t num_points = 0;
  uint32_t num_views = 0;  // 3D point observations, one descriptor each
  // Whether the index lies on the globe (cwloc-index build --georef): then results have a
  // GeoPose and queries may have priors. The origin of its ENU frame (GeoPose::enu), WGS84;
  // zero when not georeferenced.
  bool georeferenced = false;
  double origin_latitude_deg = 0;
  double origin_longitude_deg = 0;
  double origin_height_m = 0;  // above the ellipsoid
};

// An opened index. Open maps the file read-only; every Localize* is const and thread-safe, so
// one Localizer serves all threads. A query that does not localize is no error: it returns
// success = false and the reason. Bad input throws Error.
class CWLOC_API Localizer {
 public:
  // verify: also check every checksum and stored index (reads the whole file).
  static Localizer Open(const std::string& index_path, bool verify = false);

  Localizer(Localizer&&) noexcept;
  Localizer& operator=(Localizer&&) noexcept;
  ~Localizer();

  IndexInfo Info() const;

  // Features with their camera (at least the image size: Calibration::kUnknown).
  Result Localize(const Features& features, const Camera& camera,
                  const Options& options = Options()) const;

  // A JPEG or PNG file. Without a camera the EXIF focal length is the prior; without EXIF the
  // focal length is estimated. A given camera must have the photo's size.
  Result LocalizePhoto(const std::string& path, const std::optional<Camera>& camera = std::nullopt,
                       const Options& options = Options()) const;

  // The same for a JPEG or PNG file's bytes in memory.
  Result LocalizeEncodedPhoto(const uint8_t* bytes, size_t size,
                              const std::optional<Camera>& camera = std::nullopt,
                              const Options& options = Options()) const;

  // An 8-bit grey image, row-major, `stride` bytes from one row to the next (a camera frame).
  Result LocalizeGreyImage(const uint8_t* pixels, uint32_t width, uint32_t height, size_t stride,
                           const Camera& camera, const Options& options = Options()) const;

  // Several images localized as one generalized camera (cwloc-localize --frames): the paper's
  // matching on each image finds its correspondences, one robust pose fits them all. unknown_scale: the
  // cam_from_rig translations are known up to one scale, which is estimated.
  RigResult LocalizeRig(const std::vector<RigImage>& images, bool unknown_scale = false,
                        const Options& options = Options(),
                        const std::string& name = "frame") const;

 private:
  friend class Tracker;
  struct Impl;
  explicit Localizer(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

// What a device knows of its camera's motion since the previous frame (visual-inertial
// odometry), as cwloc-localize --motion takes it: the frame's camera from the previous frame's
// camera (X_cam = R(rotation) X_previous_cam + translation), metres. On a georeferenced index
// the metres become model units by its scale; otherwise only the translation's direction counts.
// Its standard deviations per axis, when the device knows them (0: it does not), bound how far
// the tracked pose may land from the motion's prediction, as --motion's sigmas do.
struct Motion {
  std::array<double, 4> rotation{1, 0, 0, 0};  // w, x, y, z
  std::array<double, 3> translation{};
  double sigma_rotation_deg = 0.0;
  double sigma_position = 0.0;  // metres
};

// The frames of one moving camera, in order (cwloc-localize --sequence): each frame is tracked
// from the frames before it, or localized from scratch when that fails, or lost (no pose);
// every Result has `tracking`. One Tracker per stream, its calls one at a time; trackers on one
// Localizer may run on several threads. The Localizer must outlive its trackers.
class CWLOC_API Tracker {
 public:
  explicit Tracker(const Localizer& localizer, const Options& options = Options());
  Tracker(Tracker&&) noexcept;
  Tracker& operator=(Tracker&&) noexcept;
  ~Tracker();

  // The next frame, as Localizer's Localize, LocalizePhoto and LocalizeGreyImage take a query,
  // with when it was seen (seconds, any origin: with the two frames' before, the last step is
  // scaled to the time since the last frame; without, frames count as evenly spaced) and the
  // camera's motion since the previous frame when the device knows it (Motion: it then predicts
  // the frame's pose).
  Result Track(const Features& features, const Camera& camera,
               std::optional<double> timestamp = std::nullopt,
               const std::optional<Motion>& motion = std::nullopt);
  Result TrackPhoto(const std::string& path, const std::optional<Camera>& camera = std::nullopt,
                    std::optional<double> timestamp = std::nullopt,
                    const std::optional<Motion>& motion = std::nullopt);
  Result TrackGreyImage(const uint8_t* pixels, uint32_t width, uint32_t height, size_t stride,
                        const Camera& camera, std::optional<double> timestamp = std::nullopt,
                        const std::optional<Motion>& motion = std::nullopt);
  // Forgets the frames so far: the next frame is localized from scratch.
  void Reset();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// COLMAP's text feature file ("N 128", then "X Y SCALE ORIENTATION D1 ... D128" per feature),
// what cwloc-localize --features reads.
CWLOC_API Features ReadFeatureFile(const std::string& path);

// Writes (atomically) the index that a delta of `cwloc-index update --delta` makes of the index
// it was made for, bit for bit as the update wrote it (docs/format.md, "Deltas"). Throws Error
// (kBadInput) naming the file for a delta made for another index (a chain applied out of
// order), a truncated or corrupt delta or index; nothing is written then. threads: 0 = all
// cores.
CWLOC_API void ApplyIndexDelta(const std::string& index_path, const std::string& delta_path,
                               const std::string& output_path, int threads = 0);

// "0.1.0"
CWLOC_API const char* Version();

}  // namespace cwloc::api
