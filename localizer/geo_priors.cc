#include "localizer/geo_priors.h"

#include <algorithm>
#include <limits>

#include "geo/geo_region.h"
#include "geo/index_georeference.h"

namespace cwloc {

std::optional<IndexGeo> IndexGeo::Of(const Index& index) {
  if (index.georeference() == nullptr) return std::nullopt;
  GeoFrame frame(GeoreferenceOfSection(*index.georeference()));
  std::vector<Eigen::Vector3d> centers;
  centers.reserve(index.images().size());
  for (const IndexImage& image : index.images())
    centers.push_back(frame.georeference().ModelToEnu(CameraCenterOf(image)));
  return IndexGeo(std::move(frame), std::move(centers));
}

std::vector<char> IndexGeo::ClustersNear(const PositionPrior& prior,
                                         const ClusterMembers& clusters) const {
  const EnuRegion region(frame_, prior);
  std::vector<char> near(clusters.num_clusters(), 0);
  for (uint32_t c = 0; c < clusters.num_clusters(); ++c) {
    for (uint32_t i = clusters.offsets[c]; i < clusters.offsets[c + 1] && !near[c]; ++i)
      near[c] = region.Contains(image_centers_enu_[clusters.images[i]]);
  }
  return near;
}

IndexGeo::CamerasNear IndexGeo::CamerasWithin(const PositionPrior& region) const {
  const EnuRegion enu_region(frame_, region);
  CamerasNear near;
  near.nearest_m = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& center : image_centers_enu_) {
    const double distance = enu_region.Distance(center);
    near.count += distance <= region.radius_m;
    near.nearest_m = std::min(near.nearest_m, distance);
  }
  return near;
}

Eigen::Vector3d IndexGeo::GravityInModel(const std::optional<PositionPrior>& prior) const {
  const Georeference& g = frame_.georeference();
  const Eigen::Vector3d at =
      prior ? frame_.GeodeticToModel(
                  {prior->latitude_deg, prior->longitude_deg, prior->height_m.value_or(0.0)})
            : g.EnuToModel(Eigen::Vector3d::Zero());
  return frame_.GravityInModel(at);
}

Eigen::Matrix3d IndexGeo::LocalEnuCovariance(const Eigen::Vector3d& model_point,
                                             const Eigen::Matrix3d& model_covariance) const {
  const Eigen::Matrix3d enu_from_model =
      frame_.georeference().scale * frame_.LocalEnuFromModel(model_point);
  return enu_from_model * model_covariance * enu_from_model.transpose();
}

GeoPose IndexGeo::PoseOnGlobe(const Eigen::Quaterniond& cam_from_model_rotation,
                              const Eigen::Vector3d& center_model) const {
  GeoPose pose;
  const Geodetic position = frame_.ModelToGeodetic(center_model);
  pose.latitude_deg = position.latitude_deg;
  pose.longitude_deg = position.longitude_deg;
  pose.height_m = position.height_m;
  const Eigen::Vector3d enu = frame_.georeference().ModelToEnu(center_model);
  pose.enu = {enu.x(), enu.y(), enu.z()};
  const CameraAttitude attitude = frame_.Attitude(cam_from_model_rotation, center_model);
  pose.heading_deg = attitude.heading_deg;
  pose.pitch_deg = attitude.pitch_deg;
  pose.roll_deg = attitude.roll_deg;
  return pose;
}

}  // namespace cwloc
