#include "localizer/pose/rig_pose.h"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

#include "localizer/pose/refine_pose_solver.h"
#include "robust/pose_estimators.h"
#include "solvers/generalized_pose.h"
#include "solvers/p3p.h"

namespace cwloc {

CameraPose RigPose::CameraFromWorld(const CameraPose& cam_from_rig) const {
  return CameraPose(
      cam_from_rig.rotation * rig_from_world.rotation,
      cam_from_rig.rotation * rig_from_world.translation + scale * cam_from_rig.translation);
}

namespace {

// Each camera's cam_from_world under a rig pose, as a matrix and a translation.
struct CameraMaps {
  std::vector<Eigen::Matrix3d> rotation;
  std::vector<Eigen::Vector3d> translation;

  CameraMaps(std::span<const RigCamera> rig, const RigPose& pose) {
    for (const RigCamera& camera : rig) {
      const CameraPose cam = pose.CameraFromWorld(camera.cam_from_rig);
      rotation.push_back(cam.RotationMatrix());
      translation.push_back(cam.translation);
    }
  }
};

// The squared reprojection error of observation o in pixels; infinity behind its camera.
double SquaredError(const CameraMaps& maps, std::span<const RadialCamera> cameras,
                    const RigObservation& o) {
  const Eigen::Vector3d z = maps.rotation[o.camera] * o.point3D + maps.translation[o.camera];
  if (!(z.z() > 0.0)) return std::numeric_limits<double>::infinity();
  return (cameras[o.camera].Project(z) - o.pixel).squaredNorm();
}

// The refinement's state: world_from_rig's rotation and the rig origin C in the world (the
// covariance's parameters, PoseCovariance), the scale, the cameras' intrinsics.
struct RigState {
  Eigen::Matrix3d world_from_rig = Eigen::Matrix3d::Identity();
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double scale = 1.0;
  std::vector<RadialCamera> cameras;

  static RigState Of(const RigPose& pose, std::span<const RadialCamera> cameras) {
    RigState state;
    state.world_from_rig = pose.rig_from_world.RotationMatrix().transpose();
    state.center = pose.rig_from_world.Center();
    state.scale = pose.scale;
    state.cameras.assign(cameras.begin(), cameras.end());
    return state;
  }

  RigPose Pose() const {
    const Eigen::Matrix3d r = world_from_rig.transpose();
    return {CameraPose(Eigen::Quaterniond(r).normalized(), -r * center), scale};
  }
};

// The normal equations (J^T W J, J^T W r) of the loss-weighted residuals, their cost, and what
// HuberCovariance needs.
struct RigNormal {
  double cost = 0.0;
  Eigen::MatrixXd h;
  Eigen::VectorXd g;
  Linearization covariance_terms;
};

class RigProblem {
 public:
  RigProblem(std::span<const RigCamera> rig, std::span<const RigObservation> observations,
             std::span<const uint32_t> indices, const RigRefinementOptions& options)
      : rig_(rig), observations_(observations), indices_(indices), options_(options) {
    num_params_ = 6 + int{options.refine_scale};
    intrinsics_column_.assign(rig.size(), -1);
    for (size_t c = 0; c < rig.size(); ++c) {
      if (options.refine_intrinsics && rig[c].refine_intrinsics) {
        intrinsics_column_[c] = num_params_;
        num_params_ += 2;
      }
    }
  }

  int num_params() const { return num_params_; }

  // False when a point is behind its camera or a value is not finite. With `linearize`, the
  // normal equations too, and with `covariance` HuberCovariance's sums. The Jacobian of a point
  // has the pose columns (theta, C, and s) and its camera's two intrinsics columns: the sums
  // are kept as blocks, fixed-size, and put together once.
  bool Evaluate(const RigState& x, bool linearize, RigNormal* out, bool covariance = false) const {
    const int n = num_params_;
    out->cost = 0.0;
    const double a2 = options_.loss_scale_px * options_.loss_scale_px;
    const bool robust = a2 > 0.0;
    const Eigen::Matrix3d rig_from_world = x.world_from_rig.transpose();
    const size_t cameras = rig_.size();
    // Per camera: world offset to camera coordinates, and its scaled translation.
    std::vector<Eigen::Matrix3d> to_cam(cameras);
    for (size_t c = 0; c < cameras; ++c)
      to_cam[c] = rig_[c].cam_from_rig.RotationMatrix() * rig_from_world;
    using Pose = Eigen::Matrix<double, 7, 7>;
    Pose h_pp = Pose::Zero(), d_pp = Pose::Zero();
    Eigen::Matrix<double, 7, 1> g_p = Eigen::Matrix<double, 7, 1>::Zero();
    std::vector<Eigen::Matrix<double, 7, 2>> h_pi(cameras, Eigen::Matrix<double, 7, 2>::Zero());
    std::vector<Eigen::Matrix<double, 7, 2>> d_pi(cameras, Eigen::Matrix<double, 7, 2>::Zero());
    std::vector<Eigen::Matrix2d> h_ii(cameras, Eigen::Matrix2d::Zero());
    std::vector<Eigen::Matrix2d> d_ii(cameras, Eigen::Matrix2d::Zero());
    std::vector<Eigen::Vector2d> g_i(cameras, Eigen::Vector2d::Zero());
    Linearization terms;
    for (const uint32_t i : indices_) {
      const RigObservation& o = observations_[i];
      const RigCamera& rc = rig_[o.camera];
      const RadialCamera& camera = x.cameras[o.camera];
      const Eigen::Vector3d offset = o.point3D - x.center;
      const Eigen::Vector3d q = to_cam[o.camera] * offset + x.scale * rc.cam_from_rig.translation;
      if (!(q.z() > 0.0)) return false;
      const Eigen::Vector2d u = q.hnormalized();
      const double uu = u.squaredNorm();
      const double d = 1.0 + camera.k * uu;
      const Eigen::Vector2d r = camera.focal_length_px * d * u - o.pixel;
      const double s = r.squaredNorm();
      if (!std::isfinite(s)) return false;
      double rho1 = 1.0, rho2 = 0.0;
      if (robust) {
        const double sum = 1.0 + s / a2;
        out->cost += 0.5 * a2 * std::log(sum);
        rho1 = 1.0 / sum;
        rho2 = -rho1 * rho1 / a2;
      } else {
        out->cost += 0.5 * s;
      }
      if (!linearize) continue;
      // d(pixel)/du, du/dq, then dq/d(theta, C, s); d(pixel)/d(f, k).
      const Eigen::Matrix2d dpix_du = camera.focal_length_px * (d * Eigen::Matrix2d::Identity() +
                                                                2.0 * camera.k * u * u.transpose());
      Eigen::Matrix<double, 2, 3> du_dq;
      du_dq << 1.0, 0.0, -u.x(), 0.0, 1.0, -u.y();
      const Eigen::Matrix<double, 2, 3> dpix_dq = dpix_du * du_dq / q.z();
      const Eigen::Matrix<double, 2, 3> dpix_dc = dpix_dq * to_cam[o.camera];
      Eigen::Matrix3d offset_cross;
      offset_cross << 0.0, -offset.z(), offset.y(), offset.z(), 0.0, -offset.x(), -offset.y(),
          offset.x(), 0.0;
      Eigen::Matrix<double, 2, 7> jp;
      jp.leftCols<3>() = dpix_dc * offset_cross;
      jp.middleCols<3>(3) = -dpix_dc;
      jp.col(6) = options_.refine_scale ? Eigen::Vector2d(dpix_dq * rc.cam_from_rig.translation)
                                        : Eigen::Vector2d::Zero();
      h_pp.noalias() += rho1 * jp.transpose() * jp;
      g_p.noalias() += rho1 * jp.transpose() * r;
      const bool intrinsics = intrinsics_column_[o.camera] >= 0;
      Eigen::Matrix2d ji;
      if (intrinsics) {
        ji.col(0) = d * u;
        ji.col(1) = camera.focal_length_px * uu * u;
        h_pi[o.camera].noalias() += rho1 * jp.transpose() * ji;
        h_ii[o.camera].noalias() += rho1 * ji.transpose() * ji;
        g_i[o.camera].noalias() += rho1 * ji.transpose() * r;
      }
      if (!covariance) continue;
      d_pp.noalias() += jp.transpose() * jp;
      if (intrinsics) {
        d_pi[o.camera].noalias() += jp.transpose() * ji;
        d_ii[o.camera].noalias() += ji.transpose() * ji;
      }
      const double curvature = rho1 + rho2 * s;
      terms.squared_scores += rho1 * rho1 * s;
      terms.curvature += curvature;
      terms.squared_curvature += curvature * curvature;
    }
    if (!std::isfinite(out->cost)) return false;
    if (!linearize) return true;
    const int p = 6 + int{options_.refine_scale};
    const auto assemble = [&](const Pose& pp, const std::vector<Eigen::Matrix<double, 7, 2>>& pi,
                              const std::vector<Eigen::Matrix2d>& ii, Eigen::MatrixXd* full) {
      *full = Eigen::MatrixXd::Zero(n, n);
      full->topLeftCorner(p, p) = pp.topLeftCorner(p, p);
      for (size_t c = 0; c < cameras; ++c) {
        const int col = intrinsics_column_[c];
        if (col < 0) continue;
        full->block(0, col, p, 2) = pi[c].topRows(p);
        full->block(col, 0, 2, p) = pi[c].topRows(p).transpose();
        full->block<2, 2>(col, col) = ii[c];
      }
    };
    assemble(h_pp, h_pi, h_ii, &out->h);
    out->g = Eigen::VectorXd::Zero(n);
    out->g.head(p) = g_p.head(p);
    for (size_t c = 0; c < cameras; ++c)
      if (const int col = intrinsics_column_[c]; col >= 0) out->g.segment<2>(col) = g_i[c];
    if (covariance) {
      assemble(d_pp, d_pi, d_ii, &terms.design);
      terms.prior = Eigen::MatrixXd::Zero(n, n);
      out->covariance_terms = std::move(terms);
    }
    return out->h.allFinite() && out->g.allFinite();
  }

  RigState Plus(const RigState& x, const Eigen::VectorXd& step) const {
    RigState y = x;
    const Eigen::Vector3d w = step.head<3>();
    if (w.norm() > 0.0)
      y.world_from_rig = Eigen::AngleAxisd(w.norm(), w.normalized()) * x.world_from_rig;
    y.center += step.segment<3>(3);
    if (options_.refine_scale) y.scale += step(6);
    for (size_t c = 0; c < rig_.size(); ++c) {
      if (const int col = intrinsics_column_[c]; col >= 0) {
        y.cameras[c].focal_length_px += step(col);
        y.cameras[c].k += step(col + 1);
      }
    }
    return y;
  }

  bool Sane(const RigState& x) const {
    if (!(x.scale > 0.0) || !x.center.allFinite() || !x.world_from_rig.allFinite()) return false;
    for (const RadialCamera& camera : x.cameras)
      if (!(camera.focal_length_px > 0.0) || !std::isfinite(camera.k)) return false;
    return true;
  }

 private:
  std::span<const RigCamera> rig_;
  std::span<const RigObservation> observations_;
  std::span<const uint32_t> indices_;
  RigRefinementOptions options_;
  int num_params_ = 6;
  std::vector<int> intrinsics_column_;  // a camera's f column (k follows), or -1
};

// Levenberg-Marquardt with Marquardt's damping; false when no finite start or solution.
bool Minimize(const RigProblem& problem, int max_iterations, RigState* x) {
  RigNormal at;
  if (!problem.Evaluate(*x, true, &at)) return false;
  double lambda = 1e-4;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    Eigen::MatrixXd damped = at.h;
    damped.diagonal() += lambda * at.h.diagonal().cwiseMax(1e-9);
    const Eigen::VectorXd step = -damped.ldlt().solve(at.g);
    if (!step.allFinite()) return false;
    const RigState candidate = problem.Plus(*x, step);
    // Linearized at once: most steps are taken, and one pass gives the cost and the equations.
    RigNormal next;
    if (problem.Sane(candidate) && problem.Evaluate(candidate, true, &next) &&
        next.cost < at.cost) {
      const double decrease = at.cost - next.cost;
      *x = candidate;
      at = std::move(next);
      lambda = std::max(lambda / 10.0, 1e-12);
      if (decrease <= 1e-10 * at.cost || step.norm() <= 1e-12) break;
    } else {
      lambda *= 10.0;
      if (lambda > 1e12) break;
    }
  }
  return problem.Sane(*x);
}

// The observations within sqrt(max_sq) pixels of their projection (and in front).
void CollectInliers(std::span<const RigCamera> rig, std::span<const RadialCamera> cameras,
                    std::span<const RigObservation> observations, const RigPose& pose,
                    double max_sq, std::vector<uint32_t>* inliers) {
  inliers->clear();
  const CameraMaps maps(rig, pose);
  for (uint32_t i = 0; i < observations.size(); ++i)
    if (SquaredError(maps, cameras, observations[i]) < max_sq) inliers->push_back(i);
}

// RANSAC's view of the observations: unit bearings in their cameras (ignoring k, which only
// the refinement estimates), each camera's observations, and the threshold.
class RigData {
 public:
  RigData(std::span<const RigCamera> rig, std::span<const RigObservation> observations,
          double max_error_px, int lo_iterations)
      : rig_(rig),
        observations_(observations),
        max_sq_(max_error_px * max_error_px),
        lo_iterations_(lo_iterations),
        by_camera_(rig.size()) {
    for (const RigCamera& camera : rig) cameras_.push_back(camera.camera);
    std::vector<std::vector<Eigen::Vector2d>> pixels(rig.size());
    std::vector<std::vector<Eigen::Vector3d>> points(rig.size());
    for (uint32_t i = 0; i < observations.size(); ++i) {
      const RigObservation& o = observations[i];
      bearings_.push_back(
          (o.pixel / rig[o.camera].camera.focal_length_px).homogeneous().normalized());
      by_camera_[o.camera].push_back(i);
      pixels[o.camera].push_back(o.pixel);
      points[o.camera].push_back(o.point3D);
    }
    for (size_t c = 0; c < rig.size(); ++c) columns_.emplace_back(pixels[c], points[c]);
  }

  size_t NumData() const { return observations_.size(); }

  // RANSAC's score: each camera's observations in vectorized columns (pose_estimators.h), with
  // the pinhole camera of RANSAC's hypotheses (k = 0: only the final refinement estimates k).
  double Score(const RigPose& model, uint32_t* num_inliers, double bound) const {
    double score = 0.0;
    uint32_t inliers = 0;
    for (size_t c = 0; c < rig_.size() && score < bound; ++c) {
      if (columns_[c].x.empty()) continue;
      uint32_t camera_inliers = 0;
      score += MsacScore(columns_[c], model.CameraFromWorld(rig_[c].cam_from_rig),
                         cameras_[c].focal_length_px, max_sq_, bound - score, &camera_inliers);
      inliers += camera_inliers;
    }
    *num_inliers = inliers;
    return score;
  }

  void Inliers(const RigPose& model, std::vector<uint32_t>* inliers) const {
    CollectInliers(rig_, cameras_, observations_, model, max_sq_, inliers);
  }

  // Least squares on the single camera's share of the model's inliers, spread evenly
  // (LocalOptimizationOptions::max_points), pose and scale only.
  void Refine(RigPose* model, bool refine_scale) const {
    std::vector<uint32_t> inliers;
    Inliers(*model, &inliers);
    if (inliers.size() < 4) return;
    Thin(LocalOptimizationOptions().max_points, &inliers);
    RigRefinementOptions options;
    options.max_iterations = lo_iterations_;
    options.refine_scale = refine_scale;
    options.refine_intrinsics = false;
    std::vector<RadialCamera> cameras = cameras_;
    RefineRigPose(rig_, observations_, inliers, options, model, &cameras);
  }

  RigRay Ray(uint32_t i) const {
    const CameraPose& cam = rig_[observations_[i].camera].cam_from_rig;
    return {cam.Center(), cam.rotation.conjugate() * bearings_[i]};
  }

 protected:
  std::span<const RigCamera> rig_;
  std::span<const RigObservation> observations_;
  std::vector<RadialCamera> cameras_;
  std::vector<Eigen::Vector3d> bearings_;
  double max_sq_;
  int lo_iterations_;
  std::vector<std::vector<uint32_t>> by_camera_;
  std::vector<ScoringColumns> columns_;  // per camera, for Score
};

// Known scale: GeneralizedP3P on three correspondences of any cameras.
class RigPoseEstimator : public RigData {
 public:
  using Model = RigPose;
  static constexpr size_t kSampleSize = 3;
  using RigData::RigData;

  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const {
    GeneralizedP3P({Ray(sample[0]), Ray(sample[1]), Ray(sample[2])},
                   {observations_[sample[0]].point3D, observations_[sample[1]].point3D,
                    observations_[sample[2]].point3D},
                   &poses_);
    for (const CameraPose& pose : poses_) models->push_back({pose, 1.0});
  }
  void Refine(Model* model) const { RigData::Refine(model, false); }

 private:
  mutable std::vector<CameraPose> poses_;
};

// Unknown scale: GeneralizedP3PScale. The uniform sample of four is mapped to its shape: the
// first correspondence's camera takes two more of its own (the second and third drawn indices
// taken modulo that camera's count), and the fourth, if in the same camera, is moved to the
// next correspondence of another camera.
class RigPoseScaleEstimator : public RigData {
 public:
  using Model = RigPose;
  static constexpr size_t kSampleSize = 4;

  RigPoseScaleEstimator(std::span<const RigCamera> rig,
                        std::span<const RigObservation> observations, double max_error_px,
                        int lo_iterations)
      : RigData(rig, observations, max_error_px, lo_iterations) {
    // The fourth ray's tolerance: the threshold in the narrowest camera's normalised units.
    for (const RigCamera& camera : rig)
      fourth_error_ = std::max(fourth_error_, std::sqrt(max_sq_) / camera.camera.focal_length_px);
  }

  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const {
    const uint32_t a = observations_[sample[0]].camera;
    const std::vector<uint32_t>& own = by_camera_[a];
    if (own.size() < 3) return;
    const std::array<uint32_t, 3> first = {sample[0], own[sample[1] % own.size()],
                                           own[sample[2] % own.size()]};
    if (first[0] == first[1] || first[0] == first[2] || first[1] == first[2]) return;
    uint32_t fourth = sample[3];
    for (size_t step = 0; observations_[fourth].camera == a; ++step) {
      if (step == observations_.size()) return;  // one camera only: no scale
      fourth = static_cast<uint32_t>((fourth + 1) % observations_.size());
    }
    const uint32_t b = observations_[fourth].camera;
    GeneralizedP3PScale(
        {bearings_[first[0]], bearings_[first[1]], bearings_[first[2]], bearings_[fourth]},
        {observations_[first[0]].point3D, observations_[first[1]].point3D,
         observations_[first[2]].point3D, observations_[fourth].point3D},
        rig_[a].cam_from_rig, rig_[b].cam_from_rig, fourth_error_, &poses_, &scales_);
    for (size_t s = 0; s < poses_.size(); ++s) models->push_back({poses_[s], scales_[s]});
  }
  void Refine(Model* model) const { RigData::Refine(model, true); }

 private:
  double fourth_error_ = 0.0;
  mutable std::vector<CameraPose> poses_;
  mutable std::vector<double> scales_;
};

// Refinement of a focal-prior camera's intrinsics needs this many of its inliers.
constexpr uint32_t kMinInliersForIntrinsics = 12;

// The final refinement's rig: a focal-prior camera's intrinsics are refined only where it has
// kMinInliersForIntrinsics of `inliers`.
std::vector<RigCamera> FinalRig(std::span<const RigCamera> cameras,
                                std::span<const RigObservation> observations,
                                std::span<const uint32_t> inliers) {
  std::vector<uint32_t> per_camera(cameras.size(), 0);
  for (const uint32_t i : inliers) ++per_camera[observations[i].camera];
  std::vector<RigCamera> rig(cameras.begin(), cameras.end());
  for (size_t c = 0; c < rig.size(); ++c)
    rig[c].refine_intrinsics &= per_camera[c] >= kMinInliersForIntrinsics;
  return rig;
}

}  // namespace

bool RefineRigPose(std::span<const RigCamera> rig, std::span<const RigObservation> observations,
                   std::span<const uint32_t> indices, const RigRefinementOptions& options,
                   RigPose* pose, std::vector<RadialCamera>* cameras) {
  const RigProblem problem(rig, observations, indices, options);
  if (indices.size() * 2 <= size_t(problem.num_params())) return false;
  RigState x = RigState::Of(*pose, *cameras);
  if (!Minimize(problem, options.max_iterations, &x)) return false;
  *pose = x.Pose();
  *cameras = x.cameras;
  return true;
}

RigPoseResult EstimateRigPose(std::span<const RigCamera> cameras,
                              std::span<const RigObservation> observations, bool unknown_scale,
                              const AbsolutePoseOptions& options, const PoseContext& context) {
  RigPoseResult result;
  for (const RigCamera& camera : cameras) result.cameras.push_back(camera.camera);
  result.inliers_per_camera.assign(cameras.size(), 0);
  const size_t sample_size = unknown_scale ? 4 : 3;
  if (observations.size() <
      std::max<size_t>(sample_size, size_t(std::max(options.min_inliers, 0)))) {
    result.failure_reason =
        "too few correspondences over all images: " + std::to_string(observations.size()) + " < " +
        std::to_string(std::max<size_t>(sample_size, options.min_inliers));
    return result;
  }
  std::vector<uint32_t> inliers;
  const auto run = [&](const auto& estimator) {
    result.stats = Ransac(estimator, options.ransac, context.ransac, &result.pose);
    if (std::isfinite(result.stats.score)) estimator.Inliers(result.pose, &inliers);
  };
  if (unknown_scale) {
    run(RigPoseScaleEstimator(cameras, observations, options.max_error_px, options.lo_iterations));
  } else {
    run(RigPoseEstimator(cameras, observations, options.max_error_px, options.lo_iterations));
  }
  if (!std::isfinite(result.stats.score)) {
    result.failure_reason =
        unknown_scale ? "no pose hypothesis: an unknown scale needs three correspondences in "
                        "one image and one in another"
                      : "no pose hypothesis: every minimal sample was degenerate";
    return result;
  }

  // The final refinement on RANSAC's inliers, kept unless it loses more than 2 % of them; with
  // focal-prior cameras in rounds as a single uncalibrated camera's (absolute_pose.h): each
  // round re-scores every correspondence with the refined pose and cameras and refines again on
  // the new inliers, until they stop changing.
  const size_t ransac_inliers = inliers.size();
  const bool any_intrinsics = std::any_of(cameras.begin(), cameras.end(),
                                          [](const RigCamera& c) { return c.refine_intrinsics; });
  const int rounds = any_intrinsics ? std::max(1, options.camera_refinement_rounds) : 1;
  RigRefinementOptions refinement;
  refinement.loss_scale_px = options.loss_scale_px;
  refinement.refine_scale = unknown_scale;
  for (int round = 0; options.refine && round < rounds; ++round) {
    const std::vector<RigCamera> rig = FinalRig(cameras, observations, inliers);
    RigPose pose = result.pose;
    std::vector<RadialCamera> refined_cameras = result.cameras;
    if (!RefineRigPose(rig, observations, inliers, refinement, &pose, &refined_cameras)) break;
    std::vector<uint32_t> refined_inliers;
    CollectInliers(rig, refined_cameras, observations, pose,
                   options.max_error_px * options.max_error_px, &refined_inliers);
    if (refined_inliers.size() * 50 < ransac_inliers * 49) break;
    result.pose = pose;
    result.cameras = refined_cameras;
    result.refined = true;
    const bool changed = refined_inliers != inliers;
    inliers = std::move(refined_inliers);
    if (!changed) break;
  }

  result.inliers.assign(observations.size(), 0);
  double error_sum = 0.0;
  const CameraMaps maps(cameras, result.pose);
  for (const uint32_t i : inliers) {
    result.inliers[i] = 1;
    ++result.inliers_per_camera[observations[i].camera];
    error_sum += std::sqrt(SquaredError(maps, result.cameras, observations[i]));
  }
  result.num_inliers = static_cast<int>(inliers.size());
  result.mean_reprojection_error_px = inliers.empty() ? 0.0 : error_sum / double(inliers.size());
  const int with_inliers = static_cast<int>(std::count_if(result.inliers_per_camera.begin(),
                                                          result.inliers_per_camera.end(),
                                                          [](uint32_t n) { return n > 0; }));
  if (result.num_inliers < options.min_inliers) {
    result.failure_reason = "best rig pose has " + std::to_string(result.num_inliers) +
                            " inliers over all images < " + std::to_string(options.min_inliers);
    return result;
  }
  if (unknown_scale && with_inliers < 2) {
    result.failure_reason =
        "an unknown scale needs inliers in two images, the pose has them in one";
    return result;
  }
  result.success = true;

  // The covariance at the reported pose, with the final refinement's loss and parameters.
  const std::vector<RigCamera> rig = FinalRig(cameras, observations, inliers);
  const RigProblem problem(rig, observations, inliers, refinement);
  RigNormal at;
  if (problem.Evaluate(RigState::Of(result.pose, result.cameras), true, &at, /*covariance=*/true)) {
    if (const std::optional<Eigen::MatrixXd> covariance =
            HuberCovariance(at.covariance_terms, inliers.size())) {
      Eigen::Matrix<double, 6, 6> block = covariance->topLeftCorner<6, 6>();
      block = 0.5 * (block + block.transpose()).eval();
      if (block.allFinite() && (block.diagonal().array() > 0.0).all()) {
        PoseCovariance& pose_covariance = result.covariance.emplace();
        PoseBlock(pose_covariance) = block;
        pose_covariance.position_radius95 = Radius95(PositionBlock(pose_covariance));
        if (unknown_scale) result.scale_std = std::sqrt((*covariance)(6, 6));
      }
    }
  }
  return result;
}

}  // namespace cwloc
