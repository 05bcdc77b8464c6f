#pragma once

// A georeferenced index at query time: poses on the globe, the position prior's clusters,
// the gravity direction in the model (docs/geo.md).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>
#include <vector>

#include "format/index.h"
#include "geo/georeference.h"
#include "localizer/matching.h"
#include "localizer/query.h"
#include "results/localization_result.h"

namespace cwloc {

class IndexGeo {
 public:
  // nullopt when the index has no georeference. O(images).
  static std::optional<IndexGeo> Of(const Index& index);

  const GeoFrame& frame() const { return frame_; }

  // Per cluster: 1 when one of its cameras lies within the prior's radius (horizontally when
  // the prior has no height).
  std::vector<char> ClustersNear(const PositionPrior& prior, const ClusterMembers& clusters) const;

  // How many model cameras lie within the region (cwloc-serve's coverage), and the distance in
  // metres from its centre to the nearest camera (horizontal when it has no height).
  struct CamerasNear {
    uint32_t count = 0;
    double nearest_m = 0;
  };
  CamerasNear CamerasWithin(const PositionPrior& region) const;

  // The direction gravity pulls, in the model frame: the ellipsoid normal at the prior's
  // position when there is one, else at the ENU origin.
  Eigen::Vector3d GravityInModel(const std::optional<PositionPrior>& prior) const;

  // A covariance of a model point, in square metres in the local east-north-up frame there.
  Eigen::Matrix3d LocalEnuCovariance(const Eigen::Vector3d& model_point,
                                     const Eigen::Matrix3d& model_covariance) const;

  GeoPose PoseOnGlobe(const Eigen::Quaterniond& cam_from_model_rotation,
                      const Eigen::Vector3d& center_model) const;

 private:
  IndexGeo(GeoFrame frame, std::vector<Eigen::Vector3d> image_centers_enu)
      : frame_(std::move(frame)), image_centers_enu_(std::move(image_centers_enu)) {}

  GeoFrame frame_;
  std::vector<Eigen::Vector3d> image_centers_enu_;  // per IMGS row
};

}  // namespace cwloc
