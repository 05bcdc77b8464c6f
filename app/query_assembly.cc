#include "app/query_assembly.h"

#include <cmath>
#include <utility>

#include "app/camera_spec.h"
#include "app/feature_file.h"
#include "app/photo_query.h"
#include "base/error.h"

namespace cwloc {

std::string QuerySource::Label() const {
  return path.empty() ? "query '" + name + "'" : path.string();
}

QueryAssembler::QueryAssembler(const QueryOptions& options, CameraInputs cameras,
                               PriorInputs priors)
    : options_(options), cameras_(std::move(cameras)), priors_(std::move(priors)) {
  if (cameras_.focal_px != 0.0 && !(std::isfinite(cameras_.focal_px) && cameras_.focal_px > 0.0))
    throw InputError("--focal must be a positive number of pixels");
}

Query QueryAssembler::Read(const QuerySource& source) const {
  switch (source.kind) {
    case QuerySource::Kind::kPhoto:
      return LoadPhotoQuery(source.path, source.name, options_.photo);
    case QuerySource::Kind::kTextFeatures: {
      Query query;
      ReadFeatureFile(source.path, &query);
      query.name = source.name;
      query.source = source.path.string();
      return query;
    }
    default:
      throw InputError(source.Label() + ": cannot be read here");
  }
}

void QueryAssembler::Complete(const QuerySource& source, Query* query) const {
  query->camera = ChooseCamera(source, *query);
  if (cameras_.unknown_focal) query->camera = WithUnknownFocal(query->camera);
  AddPriors(query);
}

QueryCamera QueryAssembler::ChooseCamera(const QuerySource& source, const Query& query) const {
  const QueryCamera& own = query.camera;  // width 0 for features without an image
  const bool has_image =
      source.kind == QuerySource::Kind::kPhoto || source.kind == QuerySource::Kind::kImage;
  QueryCamera camera = own;
  if (!source.camera_spec.empty()) {
    camera = ParseCameraSpec(source.camera_spec, source.list + " (" + source.name + ")");
    camera.source = IntrinsicsSource::kQueryList;
  } else if (cameras_.camera) {
    camera = *cameras_.camera;
  } else if (cameras_.focal_px > 0.0) {
    const QueryCamera& sized = own.width > 0 || !cameras_.image_size ? own : *cameras_.image_size;
    if (sized.width == 0) {
      throw InputError(query.Source() +
                       ": --focal needs the image size: give --image-size \"W H\"");
    }
    camera = FocalPriorCamera(cameras_.focal_px, sized.width, sized.height,
                              IntrinsicsSource::kFocalOption);
  } else if (cameras_.image_size && !has_image) {
    camera = *cameras_.image_size;
  }
  if (camera.width == 0) {
    throw InputError(query.Source() +
                     ": no camera: give --camera \"MODEL W H PARAMS\", --image-size \"W H\", or "
                     "a camera in the query list");
  }
  if (has_image && (camera.width != own.width || camera.height != own.height)) {
    throw InputError(query.Source() + ": the camera is " + std::to_string(camera.width) + " x " +
                     std::to_string(camera.height) + " but the " +
                     (source.kind == QuerySource::Kind::kPhoto ? "photo" : "image") + " is " +
                     std::to_string(own.width) + " x " + std::to_string(own.height));
  }
  return camera;
}

void QueryAssembler::AddPriors(Query* query) const {
  const auto listed = priors_.per_query.find(query->name);
  const QueryPriors* own = listed == priors_.per_query.end() ? nullptr : &listed->second;
  query->position_prior = own && own->position ? own->position : priors_.position;
  if (!query->position_prior && options_.use_exif_gps)
    query->position_prior = ExifPositionPrior(*query, options_.exif_gps_radius_m);
  query->gravity = own && own->gravity ? own->gravity : priors_.gravity;
}

}  // namespace cwloc
