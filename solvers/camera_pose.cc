#include "solvers/camera_pose.h"

#include <cmath>

#include "base/option_value.h"

namespace cwloc {

std::variant<CameraPose, std::string> PoseFromParts(const std::array<double, 4>& rotation_wxyz,
                                                    const std::array<double, 3>& translation) {
  const auto& q = rotation_wxyz;
  const Eigen::Quaterniond rotation(q[0], q[1], q[2], q[3]);
  if (!(std::abs(rotation.norm() - 1.0) <= 1e-3))
    return "the quaternion (w, x, y, z) has length " + NumberText(rotation.norm()) + ", not 1";
  const auto& t = translation;
  if (!std::isfinite(t[0] + t[1] + t[2])) return std::string("the translation is not finite");
  return CameraPose(rotation.normalized(), Eigen::Vector3d(t[0], t[1], t[2]));
}

}  // namespace cwloc
