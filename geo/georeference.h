#pragma once

// Where a model lies on the globe: a similarity from model coordinates to a local
// east-north-up frame, and that frame's origin on the WGS84 ellipsoid (GeographicLib's
// LocalCartesian). docs/geo.md defines every frame and angle.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <string>

namespace cwloc {

// A WGS84 position: degrees, and metres above the ellipsoid (not the geoid).
struct Geodetic {
  double latitude_deg = 0;
  double longitude_deg = 0;
  double height_m = 0;
};

// enu = scale * rotation * model + translation, in metres of the ENU frame at `origin`.
struct Georeference {
  Geodetic origin;
  double scale = 1;
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();  // unit (GeoFrame normalizes)
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d ModelToEnu(const Eigen::Vector3d& model) const;
  Eigen::Vector3d EnuToModel(const Eigen::Vector3d& enu) const;
  // A direction given in ENU (at the origin) in the model frame, and back: rotation only.
  Eigen::Vector3d EnuDirectionToModel(const Eigen::Vector3d& enu_direction) const;
  Eigen::Vector3d ModelDirectionToEnu(const Eigen::Vector3d& model_direction) const;
};

// The orientation of a camera's optical axis in the local ENU frame at the camera itself:
// heading clockwise from true north in [0, 360), pitch above the horizon in [-90, 90], roll
// about the optical axis in (-180, 180], positive when the image's x axis tilts down. The camera
// (x right, y down, z forward) is an aerospace body frame (forward z, right x, down y):
// ned_from_cam = Rz(heading) Ry(pitch) Rx(roll) in north-east-down. Looking straight up or down
// (|pitch| > 90 - 5.7e-8 degrees) roll is 0 and the heading is the one the image x axis gives
// (docs/geo.md has the table).
struct CameraAttitude {
  double heading_deg = 0;
  double pitch_deg = 0;
  double roll_deg = 0;
};

// A georeference with the conversions through the globe (WGS84). Thread-safe (const).
class GeoFrame {
 public:
  // Throws InputError unless the origin passes ValidateGeodetic, the scale is finite and
  // positive, and the rotation and translation are finite; the rotation is normalized.
  explicit GeoFrame(const Georeference& georeference);
  ~GeoFrame();
  GeoFrame(GeoFrame&&) noexcept;
  GeoFrame& operator=(GeoFrame&&) noexcept;

  const Georeference& georeference() const { return georeference_; }

  Geodetic EnuToGeodetic(const Eigen::Vector3d& enu) const;
  Eigen::Vector3d GeodeticToEnu(const Geodetic& geodetic) const;
  Geodetic ModelToGeodetic(const Eigen::Vector3d& model) const;
  Eigen::Vector3d GeodeticToModel(const Geodetic& geodetic) const;

  // The rotation from the model frame to the local ENU frame at a model point (its rows are
  // east, north and up there, in model coordinates; no scale).
  Eigen::Matrix3d LocalEnuFromModel(const Eigen::Vector3d& model_point) const;

  // cam_from_world is COLMAP's (world = model); attitude in the ENU frame at the camera centre.
  CameraAttitude Attitude(const Eigen::Quaterniond& cam_from_model_rotation,
                          const Eigen::Vector3d& camera_center_model) const;

  // The direction gravity pulls (down) in the model frame at a model point: the local
  // ellipsoid normal there, pointing inwards.
  Eigen::Vector3d GravityInModel(const Eigen::Vector3d& model_point) const;

 private:
  struct Impl;
  Georeference georeference_;
  std::unique_ptr<Impl> impl_;
};

// For models already in a geographic frame (COLMAP's model_aligner output).
// ECEF: model coordinates are WGS84 earth-centred earth-fixed metres; the ENU origin is put at
// `origin` (callers use the camera centroid, converted to geodetic).
Georeference GeoreferenceFromEcefModel(const Geodetic& origin);
// ENU: model coordinates are already metres east, north and up of `origin`.
Georeference GeoreferenceFromEnuModel(const Geodetic& origin);

// Throws InputError naming `what` unless latitude is in [-90, 90], longitude in [-180, 360)
// and every value finite.
void ValidateGeodetic(const Geodetic& geodetic, const std::string& what);

}  // namespace cwloc
