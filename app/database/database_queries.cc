#include "app/database/database_queries.h"

#include "base/error.h"

namespace cwloc {

DatabaseQueries::DatabaseQueries(const std::filesystem::path& path) : reader_(path) {
  for (colmap::Camera& camera : reader_.ReadAllCameras())
    cameras_.emplace(camera.camera_id, std::move(camera));
  prior_focal_lengths_ = reader_.ReadPriorFocalLengths();
}

Query DatabaseQueries::Load(const std::string& name) const {
  const std::string db = reader_.path().string();
  Query query;
  query.name = name;
  query.source = db + ": image '" + name + "'";
  colmap::ImageFeatures features;
  camera_t camera_id;
  {
    std::lock_guard lock(mutex_);
    const auto image = reader_.FindImage(name);
    if (!image) throw InputError(db + ": no image named '" + name + "'");
    camera_id = image->camera_id;
    features = reader_.ReadFeatures(image->image_id);
  }
  const auto camera = cameras_.find(camera_id);
  if (camera == cameras_.end()) {
    throw InputError(db + ": image '" + name + "' refers to missing camera " +
                     std::to_string(camera_id));
  }
  query.camera.model_id = camera->second.model_id;
  query.camera.width = static_cast<uint32_t>(camera->second.width);
  query.camera.height = static_cast<uint32_t>(camera->second.height);
  query.camera.params = camera->second.params;
  query.camera.source = IntrinsicsSource::kDatabase;
  const auto prior = prior_focal_lengths_.find(camera_id);
  query.camera.calibration = prior != prior_focal_lengths_.end() && !prior->second
                                 ? Calibration::kUnknown
                                 : Calibration::kFocalPrior;
  query.keypoints = colmap::KeypointPositions(features.keypoints);
  query.descriptors = std::move(features.descriptors.data);
  return query;
}

}  // namespace cwloc
