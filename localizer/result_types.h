// Plain result types of the localizer that the public C++ API hands out as they are: standard
// C++ only, since cwloc.hpp includes this file as <cwloc/result_types.h> (a copy in the build
// tree and in an installation, next to stage_times.inc).
// An include guard, not #pragma once: the library's files can see both copies, which define the
// same types.
#ifndef CWLOC_RESULT_TYPES_H_
#define CWLOC_RESULT_TYPES_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace cwloc {

// A model image and the co-visibility votes it got (docs/algorithm.md).
struct RankedImage {
  uint32_t image_id = 0;  // COLMAP's image id
  std::string name;
  uint32_t votes = 0;
};

// Wall-clock seconds per pipeline stage, one field per line of stage_times.inc.
struct StageTimes {
#define CWLOC_STAGE_TIME(name, help) double name = 0;
#include "stage_times.inc"
#undef CWLOC_STAGE_TIME
};

// How a frame of a sequence got its pose (tracker.h, docs/algorithm.md "Sequences").
enum class TrackingMode : int {
  kTracked = 0,      // matched near the pose predicted from the frames before it
  kRelocalized = 1,  // localized from scratch: the first frame, or tracking failed its checks
  kLost = 2,         // neither gave a pose
};
// The JSON's and Python's names, in enum order.
inline constexpr std::array<std::string_view, 3> kTrackingModeNames = {"tracked", "relocalized",
                                                                       "lost"};

struct TrackingInfo {
  TrackingMode mode = TrackingMode::kLost;
  std::string predicted_from;  // the frame the prediction started from; empty without one
  // How far the pose is from the prediction (model units, degrees); set when both exist.
  std::optional<double> prediction_error;
  std::optional<double> prediction_error_deg;
  double seconds = 0;  // the tracker's whole time on the frame, relocalization included
};

// How much the index's calibration (built with the index from model images left out and
// localized, docs/algorithm.md "Pose uncertainty") widened a pose's covariance: its rotation
// block by `rotation`, its centre block by `position`, the cross terms by the root of both.
struct CovarianceScales {
  double rotation = 1;
  double position = 1;
};

// A localized camera on the globe, when the index is georeferenced (docs/geo.md defines the
// angles).
struct GeoPose {
  double latitude_deg = 0;  // WGS84
  double longitude_deg = 0;
  double height_m = 0;          // above the ellipsoid
  std::array<double, 3> enu{};  // metres east, north, up of the index's origin
  double heading_deg = 0;       // of the optical axis, clockwise from true north, [0, 360)
  double pitch_deg = 0;         // of the optical axis above the horizon, [-90, 90]
  double roll_deg = 0;          // about the optical axis, (-180, 180]
};

}  // namespace cwloc

#endif  // CWLOC_RESULT_TYPES_H_
