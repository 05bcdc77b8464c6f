#include "geo/georeference.h"

#include <GeographicLib/Geocentric.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <array>
#include <charconv>
#include <cmath>
#include <numbers>
#include <vector>

#include "base/error.h"
#include "base/option_value.h"

namespace cwloc {
namespace {

constexpr double kDegrees = 180.0 / std::numbers::pi;

// Below this horizontal component of the unit optical axis (|pitch| above 90 - 5.7e-8 degrees)
// the attitude is treated as looking straight up or down (docs/geo.md).
constexpr double kGimbalHorizontal = 1e-9;

// A row-major 3x3 matrix from GeographicLib as an Eigen matrix.
Eigen::Matrix3d FromRowMajor(const std::vector<double>& m) {
  Eigen::Matrix3d result;
  result << m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8];
  return result;
}

// The rotation ENU-at-origin from ECEF: its rows are east, north and up at `origin` in ECEF.
// Also returns the origin's ECEF position.
Eigen::Matrix3d EnuFromEcef(const Geodetic& origin, Eigen::Vector3d* origin_ecef) {
  std::vector<double> ecef_from_enu(9);
  GeographicLib::Geocentric::WGS84().Forward(origin.latitude_deg, origin.longitude_deg,
                                             origin.height_m, (*origin_ecef)[0], (*origin_ecef)[1],
                                             (*origin_ecef)[2], ecef_from_enu);
  return FromRowMajor(ecef_from_enu).transpose();
}

// Normalizes -0 to +0 so printed angles never read "-0".
double PositiveZero(double angle) { return angle + 0.0; }

}  // namespace

Eigen::Vector3d Georeference::ModelToEnu(const Eigen::Vector3d& model) const {
  return scale * (rotation * model) + translation;
}

Eigen::Vector3d Georeference::EnuToModel(const Eigen::Vector3d& enu) const {
  return rotation.conjugate() * (enu - translation) / scale;
}

Eigen::Vector3d Georeference::EnuDirectionToModel(const Eigen::Vector3d& enu_direction) const {
  return rotation.conjugate() * enu_direction;
}

Eigen::Vector3d Georeference::ModelDirectionToEnu(const Eigen::Vector3d& model_direction) const {
  return rotation * model_direction;
}

struct GeoFrame::Impl {
  explicit Impl(const Geodetic& origin)
      : local(origin.latitude_deg, origin.longitude_deg, origin.height_m,
              GeographicLib::Geocentric::WGS84()) {}
  GeographicLib::LocalCartesian local;
};

GeoFrame::GeoFrame(const Georeference& georeference) : georeference_(georeference) {
  ValidateGeodetic(georeference_.origin, "georeference origin");
  if (!std::isfinite(georeference_.scale) || !(georeference_.scale > 0)) {
    throw InputError("georeference: scale " + NumberText(georeference_.scale) +
                     " is not a positive number");
  }
  const Eigen::Vector4d q = georeference_.rotation.coeffs();
  if (!q.allFinite() || !(q.norm() > 0)) {
    throw InputError("georeference: the rotation is not a finite non-zero quaternion");
  }
  if (!georeference_.translation.allFinite()) {
    throw InputError("georeference: the translation is not finite");
  }
  georeference_.rotation.normalize();
  impl_ = std::make_unique<Impl>(georeference_.origin);
}

GeoFrame::~GeoFrame() = default;
GeoFrame::GeoFrame(GeoFrame&&) noexcept = default;
GeoFrame& GeoFrame::operator=(GeoFrame&&) noexcept = default;

Geodetic GeoFrame::EnuToGeodetic(const Eigen::Vector3d& enu) const {
  Geodetic geodetic;
  impl_->local.Reverse(enu.x(), enu.y(), enu.z(), geodetic.latitude_deg, geodetic.longitude_deg,
                       geodetic.height_m);
  return geodetic;
}

Eigen::Vector3d GeoFrame::GeodeticToEnu(const Geodetic& geodetic) const {
  Eigen::Vector3d enu = Eigen::Vector3d::Zero();
  impl_->local.Forward(geodetic.latitude_deg, geodetic.longitude_deg, geodetic.height_m, enu.x(),
                       enu.y(), enu.z());
  return enu;
}

Geodetic GeoFrame::ModelToGeodetic(const Eigen::Vector3d& model) const {
  return EnuToGeodetic(georeference_.ModelToEnu(model));
}

Eigen::Vector3d GeoFrame::GeodeticToModel(const Geodetic& geodetic) const {
  return georeference_.EnuToModel(GeodeticToEnu(geodetic));
}

Eigen::Matrix3d GeoFrame::LocalEnuFromModel(const Eigen::Vector3d& model_point) const {
  const Eigen::Vector3d enu = georeference_.ModelToEnu(model_point);
  // GeographicLib: v_origin = M * v_local for a vector at the point, so v_local = M^T v_origin.
  std::vector<double> origin_from_local(9);
  double lat = 0, lon = 0, h = 0;
  impl_->local.Reverse(enu.x(), enu.y(), enu.z(), lat, lon, h, origin_from_local);
  return FromRowMajor(origin_from_local).transpose() * georeference_.rotation.toRotationMatrix();
}

CameraAttitude GeoFrame::Attitude(const Eigen::Quaterniond& cam_from_model_rotation,
                                  const Eigen::Vector3d& camera_center_model) const {
  // The camera's axes (x right, y down, z forward) in the local ENU frame at the camera, then
  // in north-east-down, where the camera is an aerospace body frame (forward, right, down):
  // ned_from_cam = Rz(heading) * Ry(pitch) * Rx(roll).
  const Eigen::Matrix3d enu_from_cam =
      LocalEnuFromModel(camera_center_model) *
      cam_from_model_rotation.normalized().toRotationMatrix().transpose();
  Eigen::Matrix3d ned_from_enu;
  ned_from_enu << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  const Eigen::Matrix3d ned = ned_from_enu * enu_from_cam;
  const Eigen::Vector3d right = ned.col(0), forward = ned.col(2);

  CameraAttitude attitude;
  const double horizontal = std::hypot(forward.x(), forward.y());
  attitude.pitch_deg = std::atan2(-forward.z(), horizontal) * kDegrees;
  double heading = 0;
  if (horizontal > kGimbalHorizontal) {
    heading = std::atan2(forward.y(), forward.x());
    // Roll from the down components of the right and down axes: cos(pitch) sin(roll) and
    // cos(pitch) cos(roll).
    attitude.roll_deg = std::atan2(right.z(), ned(2, 1)) * kDegrees;
  } else {
    // Looking straight up or down: heading and roll turn about the same axis. Roll is 0 and
    // the heading is the one the right axis gives: right = (-sin(heading), cos(heading), 0).
    heading = std::atan2(-right.x(), right.y());
    attitude.roll_deg = 0;
  }
  attitude.heading_deg = heading * kDegrees;
  if (attitude.heading_deg < 0) attitude.heading_deg += 360;
  if (attitude.heading_deg >= 360) attitude.heading_deg = 0;
  if (attitude.roll_deg <= -180) attitude.roll_deg = 180;
  attitude.heading_deg = PositiveZero(attitude.heading_deg);
  attitude.pitch_deg = PositiveZero(attitude.pitch_deg);
  attitude.roll_deg = PositiveZero(attitude.roll_deg);
  return attitude;
}

Eigen::Vector3d GeoFrame::GravityInModel(const Eigen::Vector3d& model_point) const {
  // The local up in the model frame is the third row of local_enu_from_model.
  return -LocalEnuFromModel(model_point).row(2).transpose();
}

Georeference GeoreferenceFromEcefModel(const Geodetic& origin) {
  ValidateGeodetic(origin, "ECEF georeference origin");
  Eigen::Vector3d origin_ecef = Eigen::Vector3d::Zero();
  const Eigen::Matrix3d enu_from_ecef = EnuFromEcef(origin, &origin_ecef);
  Georeference georeference;
  georeference.origin = origin;
  georeference.scale = 1;
  georeference.rotation = Eigen::Quaterniond(enu_from_ecef).normalized();
  // enu = R (ecef - origin_ecef); the translation uses the quaternion's own rotation so that
  // the origin maps to exactly zero up to rounding.
  georeference.translation = -(georeference.rotation * origin_ecef);
  return georeference;
}

Georeference GeoreferenceFromEnuModel(const Geodetic& origin) {
  ValidateGeodetic(origin, "ENU georeference origin");
  Georeference georeference;
  georeference.origin = origin;
  return georeference;
}

void ValidateGeodetic(const Geodetic& geodetic, const std::string& what) {
  const double lat = geodetic.latitude_deg, lon = geodetic.longitude_deg;
  if (!std::isfinite(lat) || lat < -90 || lat > 90) {
    throw InputError(what + ": latitude " + NumberText(lat) + " is outside [-90, 90]");
  }
  if (!std::isfinite(lon) || lon < -180 || lon >= 360) {
    throw InputError(what + ": longitude " + NumberText(lon) + " is outside [-180, 360)");
  }
  if (!std::isfinite(geodetic.height_m)) {
    throw InputError(what + ": height " + NumberText(geodetic.height_m) + " is not finite");
  }
}

}  // namespace cwloc
