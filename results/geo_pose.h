// A localized camera on the globe (results/describe.h; docs/geo.md defines the angles).
#ifndef CWLOC_RESULTS_GEO_POSE_H_
#define CWLOC_RESULTS_GEO_POSE_H_

#include <array>

#include "describe.h"

namespace cwloc {

struct GeoPose {
  double latitude_deg = 0;  // WGS84
  double longitude_deg = 0;
  double height_m = 0;          // above the ellipsoid
  std::array<double, 3> enu{};  // metres east, north, up of the index's origin
  double heading_deg = 0;       // of the optical axis, clockwise from true north, [0, 360)
  double pitch_deg = 0;         // of the optical axis above the horizon, [-90, 90]
  double roll_deg = 0;          // about the optical axis, (-180, 180]
};

template <>
struct Description<GeoPose> {
  static constexpr std::string_view name = "GeoPose";
  static constexpr std::string_view help =
      "A localized camera on the globe, when the index is georeferenced (docs/geo.md)";
  static constexpr auto fields = std::tuple(
      MakeField(&GeoPose::latitude_deg,
                Info("latitude_deg").Json("latitude_deg").Unit("deg").Help("WGS84")),
      MakeField(&GeoPose::longitude_deg,
                Info("longitude_deg").Json("longitude_deg").Unit("deg").Help("WGS84, east")),
      MakeField(&GeoPose::height_m,
                Info("height_m").Json("height_m").Unit("m").Help("Above the WGS84 ellipsoid")),
      MakeField(&GeoPose::enu,
                Info("enu").Json("enu").Unit("m").Help("East, north, up of the index's origin")),
      MakeField(&GeoPose::heading_deg,
                Info("heading_deg")
                    .Json("heading_deg")
                    .Unit("deg")
                    .Help("The optical axis' heading, clockwise from true north, [0, 360)")),
      MakeField(&GeoPose::pitch_deg, Info("pitch_deg")
                                         .Json("pitch_deg")
                                         .Unit("deg")
                                         .Help("The optical axis above the horizon, [-90, 90]")),
      MakeField(&GeoPose::roll_deg, Info("roll_deg")
                                        .Json("roll_deg")
                                        .Unit("deg")
                                        .Help("About the optical axis, (-180, 180]")));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_GEO_POSE_H_
