#include "app/trajectory_file.h"

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>

#include "base/error.h"

namespace cwloc {
namespace {

std::string Format(const char* format, auto... values) {
  char buffer[256];
  std::snprintf(buffer, sizeof(buffer), format, values...);
  return buffer;
}

// LaMAR's covariance of world_from_camera = T perturbed on the right, T Exp(omega, v), from
// ours over (theta, C) with world_from_camera's rotation perturbed on the left,
// exp([theta]x) R: theta = R omega and C's change = R v to first order, so both blocks turn by
// camera_from_world's rotation.
Eigen::Matrix<double, 6, 6> LamarCovariance(const LocalizationResult& result) {
  const auto& q = result.rotation;
  const Eigen::Matrix3d camera_from_world =
      Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
  Eigen::Matrix<double, 6, 6> turn = Eigen::Matrix<double, 6, 6>::Zero();
  turn.topLeftCorner<3, 3>() = camera_from_world;
  turn.bottomRightCorner<3, 3>() = camera_from_world;
  const Eigen::Matrix<double, 6, 6> pose =
      Eigen::Map<const Eigen::Matrix<double, 6, 6, Eigen::RowMajor>>(
          result.covariance->pose.data());
  return turn * pose * turn.transpose();
}

}  // namespace

TrajectoryFormat TrajectoryFormatNamed(std::string_view name) {
  for (size_t i = 0; i < kTrajectoryFormatNames.size(); ++i) {
    if (name == kTrajectoryFormatNames[i]) return TrajectoryFormat(i);
  }
  throw InputError("--trajectory-format " + std::string(name) + ": expected tum, kapture or lamar");
}

std::string TrajectoryHeader(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "";
    case TrajectoryFormat::kKapture:
      return "# kapture format: 1.1\n# timestamp, device_id, qw, qx, qy, qz, tx, ty, tz\n";
    case TrajectoryFormat::kLamar:
      return "# timestamp, device_id, qw, qx, qy, qz, tx, ty, tz, *covar\n";
  }
  return "";
}

std::string TrajectoryLine(const LocalizationResult& result, FrameStamp stamp,
                           TrajectoryFormat format) {
  const auto& q = result.rotation;     // camera_from_world, w x y z
  const auto& t = result.translation;  // camera_from_world
  const auto& c = result.center;       // world_from_camera's translation
  if (format == TrajectoryFormat::kTum) {
    // world_from_camera's rotation is camera_from_world's inverse: the conjugate quaternion.
    return Format("%.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g", stamp.value, c[0], c[1], c[2],
                  -q[1], -q[2], -q[3], q[0]);
  }
  const long long timestamp =
      stamp.seconds ? std::llround(stamp.value * 1e6) : std::llround(stamp.value);
  const std::string device(kTrajectoryDeviceId);
  // kapture's camera_from_world as the record has it; LaMAR's world_from_camera: the conjugate
  // quaternion and the centre.
  const bool lamar = format == TrajectoryFormat::kLamar;
  const double sign = lamar ? -1.0 : 1.0;
  const auto& position = lamar ? c : t;
  std::string line =
      Format("%lld, %s, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g, %.17g", timestamp, device.c_str(),
             q[0], sign * q[1], sign * q[2], sign * q[3], position[0], position[1], position[2]);
  if (lamar && result.covariance) {
    const Eigen::Matrix<double, 6, 6> covariance = LamarCovariance(result);
    for (int row = 0; row < 6; ++row) {
      for (int col = 0; col < 6; ++col) line += Format(", %.17g", covariance(row, col));
    }
  }
  return line;
}

}  // namespace cwloc
