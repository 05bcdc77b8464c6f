#include "tools/eval/pose_error.h"

#include <cmath>
#include <numbers>

namespace cwloc::eval {

Eigen::Vector3d Pose::Center() const { return -(qvec.toRotationMatrix().transpose() * tvec); }

double PositionError(const Pose& estimate, const Pose& truth) {
  return (estimate.Center() - truth.Center()).norm();
}

double RotationErrorDeg(const Pose& estimate, const Pose& truth) {
  const Eigen::Quaterniond relative =
      estimate.qvec.normalized() * truth.qvec.normalized().conjugate();
  // |w| folds q and -q, which are the same rotation.
  const double angle = 2.0 * std::atan2(relative.vec().norm(), std::abs(relative.w()));
  return angle * 180.0 / std::numbers::pi;
}

}  // namespace cwloc::eval
