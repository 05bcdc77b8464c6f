#include "solvers/generalized_pose.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "solvers/p3p.h"
#include "solvers/three_quadrics.h"

namespace cwloc {
namespace {

// A solution's distances must match the world's to this relative error (the quadric solver
// polishes its roots; worse ones are spurious roots of the elimination).
constexpr double kMaxRelativeDistanceError = 1e-6;

}  // namespace

int GeneralizedP3P(const std::array<RigRay, 3>& rays, const std::array<Eigen::Vector3d, 3>& points,
                   std::vector<CameraPose>* poses) {
  poses->clear();
  constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  // Coefficient columns (three_quadrics.h): x^2 xy xz y^2 yz z^2 x y z 1, the depths x, y, z.
  constexpr int kSquare[3] = {0, 3, 5};
  constexpr int kCross[3][3] = {{-1, 1, 2}, {1, -1, 4}, {2, 4, -1}};
  double scale = 0.0;  // the longest side, so that the quadrics' coefficients are O(1)
  for (const auto& [i, j] : kPairs) scale = std::max(scale, (points[i] - points[j]).norm());
  if (!(scale > 0.0) || !std::isfinite(scale)) return 0;
  const double inv = 1.0 / scale;
  Eigen::Matrix<double, 3, 10> coeffs = Eigen::Matrix<double, 3, 10>::Zero();
  for (int e = 0; e < 3; ++e) {
    const int i = kPairs[e][0], j = kPairs[e][1];
    const Eigen::Vector3d w = (rays[i].origin - rays[j].origin) * inv;
    coeffs(e, kSquare[i]) = 1.0;
    coeffs(e, kSquare[j]) = 1.0;
    coeffs(e, kCross[i][j]) = -2.0 * rays[i].direction.dot(rays[j].direction);
    coeffs(e, 6 + i) = 2.0 * rays[i].direction.dot(w);
    coeffs(e, 6 + j) = -2.0 * rays[j].direction.dot(w);
    coeffs(e, 9) = w.squaredNorm() - ((points[i] - points[j]) * inv).squaredNorm();
  }
  if (!coeffs.allFinite()) return 0;
  Eigen::Matrix<double, 3, 8> depths;
  const int found = SolveThreeQuadrics(coeffs, &depths);
  for (int s = 0; s < found; ++s) {
    if (!(depths.col(s).minCoeff() > 0.0)) continue;
    Eigen::Matrix3d in_rig, in_world;
    for (int i = 0; i < 3; ++i) {
      in_rig.col(i) = rays[i].origin + depths(i, s) * scale * rays[i].direction;
      in_world.col(i) = points[i];
    }
    bool consistent = true;
    for (const auto& [i, j] : kPairs) {
      const double d = (in_world.col(i) - in_world.col(j)).norm();
      consistent &=
          std::abs((in_rig.col(i) - in_rig.col(j)).norm() - d) <= kMaxRelativeDistanceError * scale;
    }
    if (!consistent) continue;
    // The rigid motion taking the world triangle onto the rig's.
    const Eigen::Matrix4d motion = Eigen::umeyama(in_world, in_rig, /*with_scaling=*/false);
    if (!motion.allFinite()) continue;
    const Eigen::Matrix3d rotation = motion.topLeftCorner<3, 3>();
    if (!(rotation.determinant() > 0.5)) continue;  // collinear points: no unique motion
    const CameraPose pose(rotation, motion.topRightCorner<3, 1>());
    if (((in_rig - ((rotation * in_world).colwise() + pose.translation)).colwise().norm().array() >
         kMaxRelativeDistanceError * scale)
            .any())
      continue;
    poses->push_back(pose);
  }
  return static_cast<int>(poses->size());
}

int GeneralizedP3PScale(const std::array<Eigen::Vector3d, 4>& bearings,
                        const std::array<Eigen::Vector3d, 4>& points, const CameraPose& camera_a,
                        const CameraPose& camera_b, double max_fourth_error,
                        std::vector<CameraPose>* poses, std::vector<double>* scales) {
  poses->clear();
  scales->clear();
  std::vector<CameraPose> in_a;
  P3P({bearings[0], bearings[1], bearings[2]}, {points[0], points[1], points[2]}, &in_a);
  const Eigen::Matrix3d ra_t = camera_a.RotationMatrix().transpose();
  const Eigen::Matrix3d rb = camera_b.RotationMatrix();
  // Camera b's coordinates of the fourth point: A + s B.
  const Eigen::Vector3d b_dir = camera_b.translation - rb * ra_t * camera_a.translation;
  const Eigen::Vector3d& bearing = bearings[3];
  const Eigen::Vector3d bb = bearing.cross(b_dir);
  // A baseline along the ray (or none) leaves s free.
  const double baseline_scale = camera_a.translation.norm() + camera_b.translation.norm();
  if (!(bb.norm() > 1e-9 * baseline_scale)) return 0;
  for (const CameraPose& cam : in_a) {
    const Eigen::Matrix3d rotation = ra_t * cam.RotationMatrix();
    const Eigen::Vector3d a = rb * (rotation * points[3] + ra_t * cam.translation);
    const double scale = -bearing.cross(a).dot(bb) / bb.squaredNorm();
    if (!(scale > 0.0) || !std::isfinite(scale)) continue;
    const Eigen::Vector3d fourth = a + scale * b_dir;
    if (!(bearing.dot(fourth) > 0.0)) continue;  // behind camera b
    if (!(bearing.cross(fourth).norm() <= max_fourth_error * fourth.norm())) continue;
    poses->push_back(CameraPose(rotation, ra_t * (cam.translation - scale * camera_a.translation)));
    scales->push_back(scale);
  }
  return static_cast<int>(poses->size());
}

}  // namespace cwloc
