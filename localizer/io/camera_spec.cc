#include "localizer/io/camera_spec.h"

#include <cmath>
#include <sstream>

#include "format/base/error.h"

namespace cwloc {
namespace {

uint32_t ParseDimension(std::istringstream& in, const std::string& field, const std::string& what) {
  long long value;
  if (!(in >> value) || value <= 0 || value > 1000000) {
    throw InputError(what + ": expected a positive image " + field + " (at most 1000000)");
  }
  return static_cast<uint32_t>(value);
}

}  // namespace

QueryCamera ParseCameraSpec(const std::string& spec, const std::string& what) {
  std::istringstream in(spec);
  std::string model_name;
  if (!(in >> model_name))
    throw InputError(what + ": empty camera; expected 'MODEL WIDTH HEIGHT PARAMS...'");
  const auto model = FindCameraModel(model_name);
  if (!model) {
    std::string known;
    for (const CameraModelInfo& info : AllCameraModels())
      known += (known.empty() ? "" : ", ") + std::string(info.name);
    throw InputError(what + ": unknown camera model '" + model_name + "' (known: " + known + ")");
  }
  if (!model->can_project) {
    throw InputError(what + ": camera model " + std::string(model->name) +
                     " is not supported for localization");
  }
  QueryCamera camera;
  camera.model_id = model->id;
  camera.width = ParseDimension(in, "width", what);
  camera.height = ParseDimension(in, "height", what);
  double value;
  while (in >> value) {
    if (!std::isfinite(value))
      throw InputError(what + ": camera parameters must be finite numbers");
    camera.params.push_back(value);
  }
  if (!in.eof()) throw InputError(what + ": camera parameters must be numbers");
  if (camera.params.size() != static_cast<size_t>(model->num_params)) {
    throw InputError(what + ": " + std::string(model->name) + " takes " +
                     std::to_string(model->num_params) + " parameters, got " +
                     std::to_string(camera.params.size()));
  }
  if (!(MeanFocalLength(camera.model_id, camera.params) > 0)) {
    throw InputError(what + ": the focal length must be positive");
  }
  return camera;
}

QueryCamera ParseImageSize(const std::string& spec, const std::string& what) {
  std::string text = spec;
  for (char& c : text) {
    if (c == 'x' || c == 'X') c = ' ';
  }
  std::istringstream in(text);
  QueryCamera camera;
  camera.width = ParseDimension(in, "width", what);
  camera.height = ParseDimension(in, "height", what);
  std::string rest;
  if (in >> rest) throw InputError(what + ": expected 'WIDTH HEIGHT', got extra '" + rest + "'");
  camera.model_id = CameraModelId::kSimplePinhole;
  camera.params = {0.0, camera.width / 2.0, camera.height / 2.0};
  camera.calibration = Calibration::kUnknown;
  camera.source = IntrinsicsSource::kImageSizeOption;
  return camera;
}

QueryCamera WithUnknownFocal(const QueryCamera& camera) {
  QueryCamera unknown =
      ParseImageSize(std::to_string(camera.width) + " " + std::to_string(camera.height), "camera");
  unknown.source = camera.source;
  return unknown;
}

}  // namespace cwloc
