#include "robust/gravity_prior.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "base/angles.h"

namespace cwloc {
namespace {

// The Cauchy scale that is 95% efficient for Gaussian noise, in units of its sigma.
constexpr double kCauchyTuning = 2.3849;

std::string DirectionError(const Eigen::Vector3d& v, const char* name) {
  if (!v.allFinite()) return std::string(name) + " is not finite";
  if (!(v.norm() > 0.0)) return std::string(name) + " is zero";
  return {};
}

}  // namespace

std::string GravityPriorError(const GravityPrior& prior) {
  std::string error = DirectionError(prior.in_camera, "in_camera");
  if (error.empty()) error = DirectionError(prior.in_world, "in_world");
  if (error.empty() && !(prior.sigma_deg > 0.0 && std::isfinite(prior.sigma_deg))) {
    std::ostringstream out;
    out << "sigma_deg " << prior.sigma_deg << " is not positive and finite";
    error = out.str();
  }
  return error;
}

GravityPrior NormalizedGravityPrior(const GravityPrior& prior) {
  GravityPrior normalized = prior;
  normalized.in_camera.normalize();
  normalized.in_world.normalize();
  return normalized;
}

double GravityAngle(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& in_world,
                    const Eigen::Vector3d& in_camera) {
  const Eigen::Vector3d predicted = rotation * in_world;
  // atan2 of |sin| and cos is accurate at every angle, unlike acos near 0 and pi.
  return std::atan2(predicted.cross(in_camera).norm(), predicted.dot(in_camera));
}

GravityConstraint GravityWeight(const GravityPrior& normalized_prior, double residual_sigma) {
  return {normalized_prior.in_camera, normalized_prior.in_world,
          residual_sigma / (normalized_prior.sigma_deg * kDegree)};
}

double CauchyScaleNoise(double loss_scale_px) {
  return loss_scale_px > 0.0 ? loss_scale_px / kCauchyTuning : 1.0;
}

double GravityErrorBound(double sigma_rad, double confidence) {
  const double miss = 1.0 - std::clamp(confidence, 0.0, 1.0 - 1e-16);
  return std::sqrt(-2.0 * std::log(miss)) * sigma_rad;
}

double GravityRejectionAngle(double sigma_rad, double confidence) {
  return GravityErrorBound(sigma_rad, confidence) + kGravityHypothesisAllowanceDeg * kDegree;
}

}  // namespace cwloc
