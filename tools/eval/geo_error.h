#pragma once

// Position errors on the ground: in an index's east-north-up frame (--index) and between two
// positions on the globe (--gt-geo). docs/eval.md, "On the globe".

#include <Eigen/Core>

#include "geo/georeference.h"
#include "tools/eval/pose_error.h"

namespace cwloc::eval {

// Metres; all three are >= 0.
struct GroundError {
  double distance = 0;  // 3D
  double ground = 0;    // horizontal: the east-north components
  double height = 0;    // |vertical difference|: the up component
};

// The error of an estimate given in an ENU frame (east, north, up metres) against the truth
// in the same frame.
GroundError ErrorInEnu(const Eigen::Vector3d& estimate_enu, const Eigen::Vector3d& truth_enu);

// The camera centres (model frame) converted to the georeference's ENU frame (ModelToEnu),
// then compared.
GroundError ErrorInIndexFrame(const Georeference& georeference, const Pose& estimate,
                              const Pose& truth);

// Both positions in the local ENU frame at the truth (WGS84, GeographicLib's LocalCartesian
// through GeoFrame), then compared: "ground" is along the ellipsoid's tangent plane there and
// "height" along its normal. Throws InputError if the truth is not a valid position.
GroundError ErrorOnGlobe(const Geodetic& estimate, const Geodetic& truth);

}  // namespace cwloc::eval
