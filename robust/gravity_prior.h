#pragma once

#include <Eigen/Core>
#include <string>

namespace cwloc {

// A gravity direction known before the pose: a phone's IMU measures it in the camera frame, the
// index's georeference gives it in the model frame. PoseContext::gravity takes it
// (absolute_pose.h says what each pose solver does with it; docs/algorithm.md, section 4).
struct GravityPrior {
  // The direction gravity pulls (down), camera frame: x right, y down, z forward (the image's
  // axes). (0, 1, 0) for an upright camera looking at the horizon, (0, 0, 1) for one looking
  // straight down. Need not be normalised; zero or non-finite is invalid.
  Eigen::Vector3d in_camera = Eigen::Vector3d::Zero();
  // The same direction in the model (world) frame, e.g. GeoFrame::GravityInModel.
  Eigen::Vector3d in_world = Eigen::Vector3d::Zero();
  // The standard deviation of in_camera's direction, degrees: the prior is an isotropic Gaussian
  // on the tangent plane of the sphere of directions, sigma_deg along each of its two axes. With
  // the default 1, the known-focal pose stage still succeeds wherever it does without a prior
  // when the prior is 3 degrees off (docs/algorithm.md); an accelerometer in motion also measures
  // the motion, which needs more. Must be positive and finite.
  double sigma_deg = 1.0;
};

// Empty if the prior is usable, else why not ("in_camera is zero", ...).
std::string GravityPriorError(const GravityPrior& prior);

// The prior with both directions scaled to unit length (for a valid prior).
GravityPrior NormalizedGravityPrior(const GravityPrior& prior);

// The angle (radians, in [0, pi]) between rotation * in_world and in_camera, both unit vectors.
double GravityAngle(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& in_world,
                    const Eigen::Vector3d& in_camera);

// The prior as a soft constraint of a least-squares problem (the local optimisation and the final
// refinement): one residual block weight * (R in_world - in_camera), in the problem's residual
// units, never robustified. Its norm is weight * 2 sin(theta / 2) for the angle theta between the
// two directions: weight * theta to within theta^2 / 24 (relative), and unlike sin(theta) it grows
// all the way to theta = pi.
//
// The weight makes the constraint a Gaussian prior next to the reprojection residuals: with
// residual noise sigma_r (per axis) and the prior's sigma_g (radians), the negative log-posterior
// times sigma_r^2 is 1/2 sum |r_i|^2 + 1/2 (sigma_r / sigma_g)^2 theta^2, so
// weight = sigma_r / sigma_g (GravityWeight).
struct GravityConstraint {
  Eigen::Vector3d in_camera = Eigen::Vector3d::Zero();  // unit
  Eigen::Vector3d in_world = Eigen::Vector3d::Zero();   // unit
  double weight = 0.0;                                  // residual units per radian of the angle
};

// The constraint of a normalised prior for residuals whose noise is residual_sigma per axis.
GravityConstraint GravityWeight(const GravityPrior& normalized_prior, double residual_sigma);

// The keypoint noise (pixels, per axis) that a Cauchy loss of scale a assumes: a = 2.3849 sigma
// is the Cauchy M-estimator's standard tuning, 95% efficient under Gaussian noise (Holland and
// Welsch, "Robust regression using iteratively reweighted least-squares", 1977). The default
// 2 px scale (AbsolutePoseOptions::loss_scale_px) thus assumes 0.84 px. Plain least squares
// (a <= 0) assumes 1 px.
double CauchyScaleNoise(double loss_scale_px);

// Known focal length: GravityP2P's hypotheses inherit the prior's error, and beyond a few
// degrees they stop overlapping the inliers. Measured on 100 and 300 correspondences with 70 to
// 90% outliers: with sigma and the actual error both 3 degrees, GravityP2P RANSAC alone fails 4
// and 6% of the hardest problems (100 correspondences with 80% outliers, 300 with 90%), none of
// the others; both 5 degrees, 60 and 70%. A prior with sigma_deg above this skips it
// (absolute_pose.h).
inline constexpr double kGravityP2PMaxSigmaDeg = 3.0;

// The bound on the prior's error (radians) that holds with RANSAC's confidence: k sigma with
// k = sqrt(-2 ln(1 - confidence)), since the angle of an isotropic 2D Gaussian error exceeds
// k sigma with probability exp(-k^2 / 2) (4.29 sigma for the default 0.9999).
double GravityErrorBound(double sigma_rad, double confidence);

// RANSAC with P3P or P4Pf (an uncalibrated camera, or a known focal length with a prior vaguer
// than kGravityP2PMaxSigmaDeg) drops hypotheses whose gravity angle exceeds
// GravityErrorBound + kGravityHypothesisAllowanceDeg: a minimal
// hypothesis may itself be off in tilt, and one within the allowance of the true tilt survives
// whenever the prior is within its bound. The allowance is measured: on 300 points with 1 px
// noise (f = 1000 px, 1600 x 1200 px, depths 5 to 50), minimal hypotheses from inlier samples
// more than 3 degrees off in tilt keep 1.4% (P4Pf), 2.2% (P3P) and 2.5% (P3P with a focal
// prior 5% short) of the inliers on average, against 58%, 73% and 17% for the rest.
inline constexpr double kGravityHypothesisAllowanceDeg = 3.0;
double GravityRejectionAngle(double sigma_rad, double confidence);

}  // namespace cwloc
