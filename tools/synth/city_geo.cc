#include "tools/synth/city_geo.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "base/angles.h"
#include "base/option_value.h"
#include "tools/synth/sift_descriptors.h"

namespace cwloc::synth {
namespace {

// Stream tags of the globe's draws, apart from every tag the scene and the writer use, so that
// --geo and its knobs change none of the other numbers.
enum GeoStream : uint64_t {
  kModelFrameStream = 300,
  kGpsNoiseStream,
  kGpsOutlierStream,
  kQueryPriorStream,
};

// " LAT LON HEIGHT": 1e-12 degrees (0.1 um) and 1 um.
std::string GeodeticText(const Geodetic& g) {
  char buffer[96];
  std::snprintf(buffer, sizeof(buffer), " %.12f %.12f %.6f", g.latitude_deg, g.longitude_deg,
                g.height_m);
  return buffer;
}

// A unit vector perpendicular to unit `v`, at angle `phi` around it.
Eigen::Vector3d Perpendicular(const Eigen::Vector3d& v, double phi) {
  Eigen::Index smallest;
  v.cwiseAbs().minCoeff(&smallest);
  const Eigen::Vector3d a = v.cross(Eigen::Vector3d::Unit(smallest)).normalized();
  const Eigen::Vector3d b = v.cross(a);
  return std::cos(phi) * a + std::sin(phi) * b;
}

}  // namespace

Eigen::Vector3d ModelFrame::ModelFromWorld(const Eigen::Vector3d& world) const {
  if (identity) return world;
  return scale * (rotation * (world - enu_origin)) + translation;
}

colmap::Rigid3d ModelFrame::CamFromModel(const CityScene& scene, const SceneImage& image) const {
  if (identity) return scene.CamFromWorld(image);
  // X_cam = R_cw (X_world - C); in the model frame the camera frame is scaled alike, which
  // changes no projection: X_cam' = R_cw R^T (X_model - C_model).
  const Eigen::Matrix3d cam_from_model = image.pose.cam_from_world_rotation * rotation.transpose();
  Eigen::Quaterniond q(cam_from_model);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;
  const Eigen::Vector3d t = -(q.toRotationMatrix() * ModelFromWorld(image.pose.centre));
  colmap::Rigid3d rigid;
  rigid.rotation = {q.w(), q.x(), q.y(), q.z()};
  rigid.translation = {t.x(), t.y(), t.z()};
  return rigid;
}

Georeference ModelFrame::EnuFromModel(const Geodetic& origin) const {
  // model = s R enu + t  <=>  enu = (1/s) R^T model - (1/s) R^T t.
  Georeference g;
  g.origin = origin;
  g.scale = 1 / scale;
  g.rotation = Eigen::Quaterniond(Eigen::Matrix3d(rotation.transpose())).normalized();
  g.translation = -(rotation.transpose() * translation) / scale;
  return g;
}

ModelFrame MakeModelFrame(const CityScene& scene, const GeoOptions& geo) {
  ModelFrame frame;
  if (!geo.origin) return frame;
  const CityLayout& layout = scene.layout();
  Rng rng(Rng::Seed(scene.options().seed, kModelFrameStream));
  // Four independent normals, normalized: a rotation uniform on SO(3).
  Eigen::Quaterniond q;
  do {
    q.coeffs() << rng.Gaussian(), rng.Gaussian(), rng.Gaussian(), rng.Gaussian();
  } while (q.norm() < 1e-6);
  q.normalize();
  const double span = rng.Uniform(kModelMinSpan, kModelMaxSpan);
  frame.identity = false;
  frame.rotation = q.toRotationMatrix();
  frame.scale = span / std::max(layout.width(), layout.depth());
  for (int i = 0; i < 3; ++i) {
    frame.translation[i] = rng.Uniform(-kModelTranslationRange, kModelTranslationRange);
  }
  frame.enu_origin = Eigen::Vector3d(layout.width() / 2, layout.depth() / 2, 0);
  return frame;
}

size_t NumGpsOutliers(const GeoOptions& geo, size_t mapping_images) {
  return size_t(std::llround(geo.gps_outliers * double(mapping_images)));
}

namespace {

// The mapping images' noisy GPS positions (files->georef) and which of them are outliers
// (files->georef_outliers).
void MakeGeorefFile(const CityScene& scene, const GeoOptions& geo, const ModelFrame& frame,
                    const GeoFrame& globe, GeoFiles* files) {
  const uint64_t seed = scene.options().seed;
  const auto& images = scene.images();
  const size_t num_mapping = scene.num_mapping_images();
  // Which mapping images get a wild GPS position: exactly round(F x N), a partial
  // Fisher-Yates shuffle of one stream.
  const size_t num_outliers = NumGpsOutliers(geo, num_mapping);
  std::vector<size_t> order(num_mapping);
  std::iota(order.begin(), order.end(), size_t{0});
  {
    Rng rng(Rng::Seed(seed, kGpsOutlierStream));
    for (size_t i = 0; i < num_outliers; ++i) {
      std::swap(order[i], order[i + rng.Below(num_mapping - i)]);
    }
  }
  std::vector<bool> outlier(num_mapping, false);
  for (size_t i = 0; i < num_outliers; ++i) outlier[order[i]] = true;

  char line[160];
  std::snprintf(line, sizeof(line),
                "# Noise: Gaussian, %g m per ENU axis; %zu of %zu positions are outliers "
                "%g-%g m off horizontally (and up to %g m vertically).\n",
                geo.gps_noise, num_outliers, num_mapping, kGpsOutlierMinOffset,
                kGpsOutlierMaxOffset, kGpsOutlierMaxVertical);
  files->georef =
      "# Camera centres of the mapping images on the globe, as a noisy GPS gives them "
      "(cwloc-synth --geo).\n"
      "# IMAGE_NAME LAT LON HEIGHT: WGS84 degrees and metres above the ellipsoid (a cwloc georef "
      "file).\n";
  files->georef += line;
  for (size_t i = 0; i < num_mapping; ++i) {
    const SceneImage& image = images[i];
    Eigen::Vector3d enu = frame.EnuFromWorld(image.pose.centre);
    if (outlier[i]) {
      Rng rng(Rng::Seed(seed, kGpsOutlierStream, image.image_id));
      const double heading = rng.Uniform(0, 2 * std::numbers::pi);
      const double distance = rng.Uniform(kGpsOutlierMinOffset, kGpsOutlierMaxOffset);
      const double vertical = rng.Uniform(-kGpsOutlierMaxVertical, kGpsOutlierMaxVertical);
      enu += Eigen::Vector3d(distance * std::cos(heading), distance * std::sin(heading), vertical);
      files->georef_outliers += image.name + "\n";
    } else if (geo.gps_noise > 0) {
      Rng rng(Rng::Seed(seed, kGpsNoiseStream, image.image_id));
      for (int axis = 0; axis < 3; ++axis) enu[axis] += geo.gps_noise * rng.Gaussian();
    }
    files->georef += image.name + GeodeticText(globe.EnuToGeodetic(enu)) + "\n";
  }
}

// The queries' true positions on the globe (files->queries_geo) and their priors as a phone
// gives them (files->query_priors).
void MakeQueryFiles(const CityScene& scene, const GeoOptions& geo, const ModelFrame& frame,
                    const GeoFrame& globe, GeoFiles* files) {
  const uint64_t seed = scene.options().seed;
  const auto& images = scene.images();
  const size_t num_mapping = scene.num_mapping_images();
  char line[160];
  files->queries_geo =
      "# True camera centres of the queries on the globe (exact: the generator placed these "
      "cameras).\n"
      "# NAME LAT LON HEIGHT: WGS84 degrees and metres above the ellipsoid.\n";
  files->query_priors =
      "# Priors for cwloc-localize --priors (docs/cli.md, docs/synth.md): a position and a "
      "gravity direction per query.\n"
      "# NAME position LAT LON HEIGHT RADIUS_M: WGS84 degrees, metres above the ellipsoid; the "
      "camera is within RADIUS_M metres.\n"
      "# NAME gravity GX GY GZ: unit vector, the direction gravity pulls in the camera frame "
      "(x right, y down, z forward).\n";
  std::snprintf(line, sizeof(line),
                "# Generated: positions %g m off the true centres horizontally, gravity %g deg "
                "off.\n",
                geo.prior_position_error, geo.prior_gravity_error_deg);
  files->query_priors += line;
  const std::string radius = NumberText(geo.prior_radius);
  const double gravity_error = geo.prior_gravity_error_deg * kDegree;
  for (size_t i = num_mapping; i < images.size(); ++i) {
    const SceneImage& image = images[i];
    const Eigen::Vector3d enu = frame.EnuFromWorld(image.pose.centre);
    files->queries_geo += image.name + GeodeticText(globe.EnuToGeodetic(enu)) + "\n";

    // The camera's own tangent plane and vertical (the ellipsoid normal there), as the rows of
    // local_from_enu: a phone's position error is horizontal where it is, and its gravity
    // points along the local normal, which turns away from the city centre's (0, 0, -1) by
    // the camera's distance over the earth radius (0.009 degrees per km).
    const Eigen::Matrix3d local_from_enu =
        globe.LocalEnuFromModel(frame.ModelFromWorld(image.pose.centre)) * frame.rotation;
    Rng rng(Rng::Seed(seed, kQueryPriorStream, image.image_id));
    const double heading = rng.Uniform(0, 2 * std::numbers::pi);
    const Eigen::Vector3d prior =
        enu + geo.prior_position_error * (std::cos(heading) * local_from_enu.row(0) +
                                          std::sin(heading) * local_from_enu.row(1))
                                             .transpose();
    files->query_priors +=
        image.name + " position" + GeodeticText(globe.EnuToGeodetic(prior)) + " " + radius + "\n";
    // Gravity in the camera frame, then turned by exactly the error about an axis
    // perpendicular to it.
    const Eigen::Vector3d gravity =
        (image.pose.cam_from_world_rotation * -local_from_enu.row(2).transpose()).normalized();
    const Eigen::Vector3d axis = Perpendicular(gravity, rng.Uniform(0, 2 * std::numbers::pi));
    const Eigen::Vector3d noisy =
        (std::cos(gravity_error) * gravity + std::sin(gravity_error) * axis.cross(gravity))
            .normalized();
    files->query_priors += image.name + " gravity " + NumberText(noisy.x()) + " " +
                           NumberText(noisy.y()) + " " + NumberText(noisy.z()) + "\n";
  }
}

// The similarity from the model to the city's ENU frame, as cwloc-eval --scale reads it.
std::string ScaleToMetresFile(const GeoOptions& geo, const ModelFrame& frame) {
  char line[160];
  const Georeference enu_from_model = frame.EnuFromModel(*geo.origin);
  const Eigen::Matrix3d r = enu_from_model.rotation.toRotationMatrix();
  std::snprintf(line, sizeof(line), "%.12f %.12f %.6f", geo.origin->latitude_deg,
                geo.origin->longitude_deg, geo.origin->height_m);
  std::string text =
      "# Similarity model->ENU frame in metres (x east, y north, z up) whose origin is the city "
      "centre on the ground,\n# at WGS84 latitude, longitude, ellipsoidal height " +
      std::string(line) +
      " (cwloc-synth --geo)\n"
      "# X_gt = s * R * X_model + t (R row by row)\n"
      "scale " +
      NumberText(enu_from_model.scale) + "\nR";
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) text.append(" ").append(NumberText(r(row, col)));
  }
  text += "\nt";
  // Appended, not " " + ...: GCC 12 misreads that here (-Wrestrict).
  for (int i = 0; i < 3; ++i) text.append(" ").append(NumberText(enu_from_model.translation[i]));
  text += "\n";
  return text;
}

}  // namespace

GeoFiles MakeGeoFiles(const CityScene& scene, const GeoOptions& geo, const ModelFrame& frame) {
  if (!geo.origin || frame.identity) {
    throw std::logic_error("MakeGeoFiles needs --geo's origin and model frame");
  }
  const GeoFrame globe(frame.EnuFromModel(*geo.origin));
  GeoFiles files;
  MakeGeorefFile(scene, geo, frame, globe, &files);
  MakeQueryFiles(scene, geo, frame, globe, &files);
  files.scale_to_metres = ScaleToMetresFile(geo, frame);
  return files;
}

}  // namespace cwloc::synth
