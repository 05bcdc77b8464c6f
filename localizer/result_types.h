// Plain result types of the localizer that the public C++ API hands out as they are: standard
// C++ only, since cwloc.hpp includes this file as <cwloc/result_types.h> (a copy in the build
// tree and in an installation, next to stage_times.inc).
// An include guard, not #pragma once: the library's files can see both copies, which define the
// same types.
#ifndef CWLOC_RESULT_TYPES_H_
#define CWLOC_RESULT_TYPES_H_

#include <array>
#include <cstdint>
#include <string>

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
