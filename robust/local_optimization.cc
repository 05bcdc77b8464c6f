#include "robust/local_optimization.h"

#include <Eigen/Geometry>
#include <cmath>

#include "robust/cholesky.h"

namespace cwloc {
namespace {

// exp([w]x) as a unit quaternion.
Eigen::Quaterniond ExpQuaternion(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  if (theta < 1e-12)
    return Eigen::Quaterniond(1.0, 0.5 * w(0), 0.5 * w(1), 0.5 * w(2)).normalized();
  const Eigen::Vector3d v = std::sin(0.5 * theta) / theta * w;
  return Eigen::Quaterniond(std::cos(0.5 * theta), v(0), v(1), v(2));
}

template <int kNumParams>
struct LmProblem {
  using Hessian = Eigen::Matrix<double, kNumParams, kNumParams>;
  using Gradient = Eigen::Matrix<double, kNumParams, 1>;
  static constexpr bool kFocal = kNumParams == 7;

  std::span<const Eigen::Vector2d> points2D;
  std::span<const Eigen::Vector3d> points3D;
  std::span<const uint32_t> indices;
  double loss_scale;
  const GravityConstraint* gravity;  // nullptr: none

  // Robust cost and, if requested, the IRLS normal equations (J^T W J, J^T W r).
  double Evaluate(const Eigen::Quaterniond& q, const Eigen::Vector3d& t, double f, Hessian* jtj,
                  Gradient* jtr) const {
    const Eigen::Matrix3d rot = q.toRotationMatrix();
    const double s2 = loss_scale * loss_scale;
    double cost = 0.0;
    if (jtj != nullptr) {
      jtj->setZero();
      jtr->setZero();
    }
    for (const uint32_t i : indices) {
      const Eigen::Vector3d rx = rot * points3D[i];
      const Eigen::Vector3d z = rx + t;
      if (!(z(2) > 1e-12)) continue;
      const double inv_z = 1.0 / z(2);
      const Eigen::Vector2d proj(z(0) * inv_z, z(1) * inv_z);
      const Eigen::Vector2d r = f * proj - points2D[i];
      const double r2 = r.squaredNorm();
      double weight = 1.0;
      if (s2 > 0.0) {
        cost += s2 * std::log1p(r2 / s2);
        weight = 1.0 / (1.0 + r2 / s2);
      } else {
        cost += r2;
      }
      if (jtj == nullptr) continue;
      // d r / d z = f / z [1 0 -x/z; 0 1 -y/z]; dz/dw = -[R X]x, dz/dt = I.
      Eigen::Matrix<double, 2, 3> dr_dz;
      dr_dz << f * inv_z, 0.0, -f * proj(0) * inv_z, 0.0, f * inv_z, -f * proj(1) * inv_z;
      Eigen::Matrix3d skew;
      skew << 0.0, -rx(2), rx(1), rx(2), 0.0, -rx(0), -rx(1), rx(0), 0.0;
      Eigen::Matrix<double, 2, kNumParams> jac;
      jac.template leftCols<3>() = -dr_dz * skew;
      jac.template block<2, 3>(0, 3) = dr_dz;
      if constexpr (kFocal) jac.col(6) = proj;
      jtj->noalias() += weight * jac.transpose() * jac;
      jtr->noalias() += weight * jac.transpose() * r;
    }
    if (gravity != nullptr) {
      // r = w (R g_w - g_c); R <- exp([d]x) R moves R g_w by -[R g_w]x d.
      const Eigen::Vector3d y = rot * gravity->in_world;
      const Eigen::Vector3d r = gravity->weight * (y - gravity->in_camera);
      cost += r.squaredNorm();
      if (jtj != nullptr) {
        Eigen::Matrix3d skew;
        skew << 0.0, -y(2), y(1), y(2), 0.0, -y(0), -y(1), y(0), 0.0;
        const Eigen::Matrix3d jac = -gravity->weight * skew;
        jtj->template topLeftCorner<3, 3>().noalias() += jac.transpose() * jac;
        jtr->template head<3>().noalias() += jac.transpose() * r;
      }
    }
    return cost;
  }
};

template <int kNumParams>
int Optimize(const LmProblem<kNumParams>& problem, int max_iterations, CameraPose* pose,
             double* focal) {
  using Hessian = typename LmProblem<kNumParams>::Hessian;
  using Gradient = typename LmProblem<kNumParams>::Gradient;
  Eigen::Quaterniond q = pose->rotation.normalized();
  Eigen::Vector3d t = pose->translation;
  double f = focal != nullptr ? *focal : 1.0;
  Hessian jtj;
  Gradient jtr;
  double cost = problem.Evaluate(q, t, f, &jtj, &jtr);
  double lambda = 1e-4;
  int iter = 0;
  for (; iter < max_iterations; ++iter) {
    if (!(cost > 0.0)) break;
    Hessian damped = jtj;
    damped.diagonal() += lambda * jtj.diagonal().cwiseMax(1e-12);
    Gradient step;
    if (!SolveCholesky(kNumParams, damped.data(), kNumParams, jtr.data(), step.data())) break;
    step = -step;
    const Eigen::Quaterniond q_new = (ExpQuaternion(step.template head<3>()) * q).normalized();
    const Eigen::Vector3d t_new = t + step.template segment<3>(3);
    double f_new = f;
    if constexpr (kNumParams == 7) f_new += step(6);
    const double cost_new = problem.Evaluate(q_new, t_new, f_new, nullptr, nullptr);
    if (cost_new < cost && f_new > 0.0) {
      const bool converged = cost - cost_new < 1e-12 * cost;
      q = q_new;
      t = t_new;
      f = f_new;
      cost = problem.Evaluate(q, t, f, &jtj, &jtr);
      lambda = std::max(1e-10, lambda * 0.1);
      if (converged) {
        ++iter;
        break;
      }
    } else {
      lambda *= 10.0;
      if (lambda > 1e8) break;
    }
  }
  pose->rotation = q;
  pose->translation = t;
  if (focal != nullptr) *focal = f;
  return iter;
}

}  // namespace

int OptimizePose(std::span<const Eigen::Vector2d> points2D,
                 std::span<const Eigen::Vector3d> points3D, std::span<const uint32_t> indices,
                 const LocalOptimizationOptions& options, CameraPose* pose) {
  const LmProblem<6> problem{points2D, points3D, indices, options.loss_scale,
                             options.gravity ? &*options.gravity : nullptr};
  return Optimize(problem, options.max_iterations, pose, nullptr);
}

int OptimizePoseAndFocal(std::span<const Eigen::Vector2d> centered_pixels,
                         std::span<const Eigen::Vector3d> points3D,
                         std::span<const uint32_t> indices, const LocalOptimizationOptions& options,
                         CameraPose* pose, double* focal_length) {
  const LmProblem<7> problem{centered_pixels, points3D, indices, options.loss_scale,
                             options.gravity ? &*options.gravity : nullptr};
  return Optimize(problem, options.max_iterations, pose, focal_length);
}

}  // namespace cwloc
