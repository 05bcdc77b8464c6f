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

#include "cwloc/localization_result.h"
#include "cwloc/rig_result.h"

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

// What the pose stage may trust about the camera (COLMAP's prior_focal_length): kKnown holds
// every parameter fixed; kFocalPrior takes the model's mean focal length as a guess, refined
// with a radial distortion term (principal point at the image centre); kUnknown has only the
// image size and estimates the focal length (P4Pf). A Camera in COLMAP's terms: model name
// (SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL, OPENCV, ...) and its parameters in COLMAP's
// order (cwloc/camera.h).
using cwloc::Calibration;
using cwloc::Camera;

// A query's own SIFT features: keypoints in COLMAP's pixel convention (the image's top-left
// corner is (0, 0), a pixel centre is at +0.5) and N x 128 uint8 descriptors in COLMAP's
// normalisation (what colmap feature_extractor stores).
struct Features {
  std::vector<float> keypoints;      // x0, y0, x1, y1, ...
  std::vector<uint8_t> descriptors;  // N * 128
};

// A GPS fix: the query was taken within radius_m of this WGS84 position (horizontally when the
// height is unknown). Only clusters with a model camera that near are matched. Needs a
// georeferenced index (IndexInfo::georeferenced). Its `source` is the API's on input
// (cwloc/priors.h).
using cwloc::PositionPrior;

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

// A query's answer, the localizer's own (cwloc/localization_result.h): every field is listed
// there once with its meaning, and the JSON record, C's accessors by path and Python's
// properties are walks over that list (docs/api.md). A query that does not localize has success
// false and failure_reason.
using Result = cwloc::LocalizationResult;
using cwloc::Budget;
using cwloc::CameraUsed;
using cwloc::CovarianceScales;
using cwloc::Distortion;
using cwloc::DistortionFit;
using cwloc::FocalDepth;
using cwloc::GeoPose;
using cwloc::GravityPriorUse;
using cwloc::Inlier;
using cwloc::IntrinsicsSource;
using cwloc::PhotoInfo;
using cwloc::Pose;
using cwloc::PoseCovariance;
using cwloc::PositionPriorUse;
using cwloc::PriorsUsed;
using cwloc::PriorSource;
using cwloc::RankedImage;
using cwloc::ResultCamera;
using cwloc::StageTimes;
using cwloc::TrackingMode;
using cwloc::Transform;
using Tracking = cwloc::TrackingInfo;

// A rig frame's answer (cwloc/rig_result.h).
using cwloc::RigImageResult;
using cwloc::RigPoseInfo;
using cwloc::RigResult;
using cwloc::RigStageTimes;

// The JSON record cwloc-localize writes for a result made with these options
// (schemas/localization-result.schema.json; for a rig frame, its rig_frame).
CWLOC_API std::string ToJson(const Result& result, const Options& options);
CWLOC_API std::string ToJson(const RigResult& result, const Options& options);

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
