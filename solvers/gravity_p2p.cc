#include "solvers/gravity_p2p.h"

#include <cmath>

namespace cwloc {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// Below these the equations carry no information about the unknowns (relative to the scale of
// the data, where rounding alone leaves ~1e-16): sin of the angle between the two rays, and
// |(alpha, beta)| / (|n| |D|), the product of the sines of the angles that the plane of the rays'
// normal and the world points' difference make with gravity.
constexpr double kMinRaySine = 1e-12;
constexpr double kMinConditioning = 1e-12;
// A line that misses the unit circle by this little (relative) is taken as tangent: rounding.
constexpr double kTangentTolerance = 1e-12;

// A rotation whose third row is the unit vector g, so that it maps g to the z axis. The first
// row is perpendicular to g and to the coordinate axis least aligned with g: |axis x g| >=
// sqrt(2/3), so the normalisation never divides by a small number.
Matrix3d AlignWithZ(const Vector3d& g) {
  int axis = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(g(i)) < std::abs(g(axis))) axis = i;
  }
  const Vector3d e0 = Vector3d::Unit(axis).cross(g).normalized();
  const Vector3d e1 = g.cross(e0);  // unit; e0 x e1 = g, a right-handed frame
  Matrix3d rows;
  rows.row(0) = e0;
  rows.row(1) = e1;
  rows.row(2) = g;
  return rows;
}

// The rotation by theta about z, from (cos, sin).
Matrix3d RotationZ(double c, double s) {
  Matrix3d r;
  r << c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0;
  return r;
}

}  // namespace

int GravityP2P(const std::array<Vector3d, 2>& bearings, const std::array<Vector3d, 2>& points,
               const Vector3d& gravity_in_camera, const Vector3d& gravity_in_world,
               std::vector<CameraPose>* poses) {
  poses->clear();
  for (int i = 0; i < 2; ++i) {
    if (!bearings[i].allFinite() || !points[i].allFinite()) return 0;
  }
  if (!gravity_in_camera.allFinite() || !gravity_in_world.allFinite()) return 0;

  const Matrix3d align_camera = AlignWithZ(gravity_in_camera);
  const Matrix3d align_world = AlignWithZ(gravity_in_world);
  const Vector3d b0 = align_camera * bearings[0];
  const Vector3d b1 = align_camera * bearings[1];
  const Vector3d x0 = align_world * points[0];
  const Vector3d x1 = align_world * points[1];
  const Vector3d d = x0 - x1;
  const Vector3d n = b0.cross(b1);
  const double n_sq = n.squaredNorm();
  const double n_norm = std::sqrt(n_sq);
  const double d_norm = d.norm();
  if (!(n_norm > kMinRaySine) || !(d_norm > 0.0)) return 0;

  // n . R_z d = cos (n_x d_x + n_y d_y) + sin (n_y d_x - n_x d_y) + n_z d_z, scaled by |n| |d|.
  const double scale = 1.0 / (n_norm * d_norm);
  const double alpha = scale * (n(0) * d(0) + n(1) * d(1));
  const double beta = scale * (n(1) * d(0) - n(0) * d(1));
  const double gamma = scale * n(2) * d(2);
  const double rho = std::hypot(alpha, beta);
  if (!(rho > kMinConditioning)) return 0;
  // (cos, sin) = offset u +- along u_perp with u = (alpha, beta) / rho: the foot of the line
  // alpha c + beta s = -gamma, then along the line to the circle.
  double offset = -gamma / rho;
  if (std::abs(offset) > 1.0) {
    if (std::abs(offset) > 1.0 + kTangentTolerance) return 0;
    offset = std::copysign(1.0, offset);
  }
  const double along = std::sqrt((1.0 - offset) * (1.0 + offset));
  const double u0 = alpha / rho, u1 = beta / rho;
  const int num_roots = along > 0.0 ? 2 : 1;
  for (int root = 0; root < num_roots; ++root) {
    const double sign = root == 0 ? 1.0 : -1.0;
    double c = offset * u0 - sign * along * u1;
    double s = offset * u1 + sign * along * u0;
    const double norm = std::hypot(c, s);
    c /= norm;
    s /= norm;
    const Matrix3d rz = RotationZ(c, s);
    // lambda_0 b0 - lambda_1 b1 = e: crossing with b1 and b0 isolates each depth.
    const Vector3d e = rz * d;
    const double lambda0 = e.cross(b1).dot(n) / n_sq;
    const double lambda1 = e.cross(b0).dot(n) / n_sq;
    if (!(lambda0 > 0.0) || !(lambda1 > 0.0)) continue;
    // Both rays give t'; their mean spreads the rounding.
    const Vector3d t_aligned = 0.5 * (lambda0 * b0 + lambda1 * b1 - rz * (x0 + x1));
    const Matrix3d rotation = align_camera.transpose() * rz * align_world;
    const CameraPose pose(rotation, align_camera.transpose() * t_aligned);
    if (pose.rotation.coeffs().allFinite() && pose.translation.allFinite()) poses->push_back(pose);
  }
  return static_cast<int>(poses->size());
}

}  // namespace cwloc
