#include "tools/eval/geo_error.h"

#include <cmath>

namespace cwloc::eval {

GroundError ErrorInEnu(const Eigen::Vector3d& estimate_enu, const Eigen::Vector3d& truth_enu) {
  const Eigen::Vector3d d = estimate_enu - truth_enu;
  return {d.norm(), std::hypot(d.x(), d.y()), std::abs(d.z())};
}

GroundError ErrorInIndexFrame(const Georeference& georeference, const Pose& estimate,
                              const Pose& truth) {
  // ModelToEnu of each centre minus the other, without the translation, which is millions of
  // metres for an ECEF model and would cost digits.
  const Eigen::Vector3d difference = georeference.scale * (georeference.rotation.normalized() *
                                                           (estimate.Center() - truth.Center()));
  return ErrorInEnu(difference, Eigen::Vector3d::Zero());
}

GroundError ErrorOnGlobe(const Geodetic& estimate, const Geodetic& truth) {
  Georeference at_truth;
  at_truth.origin = truth;
  const GeoFrame frame(at_truth);
  return ErrorInEnu(frame.GeodeticToEnu(estimate), Eigen::Vector3d::Zero());
}

}  // namespace cwloc::eval
