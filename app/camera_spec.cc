#include "app/camera_spec.h"

#include <cmath>
#include <sstream>

#include "base/error.h"

namespace cwloc {
namespace {

constexpr long long kMaxImageSide = 1000000;

std::string DimensionError(const std::string& field, const std::string& what) {
  return what + ": expected a positive image " + field + " (at most " +
         std::to_string(kMaxImageSide) + ")";
}

uint32_t ParseDimension(std::istringstream& in, const std::string& field, const std::string& what) {
  long long value;
  if (!(in >> value) || value <= 0 || value > kMaxImageSide)
    throw InputError(DimensionError(field, what));
  return static_cast<uint32_t>(value);
}

void CheckImageSize(uint32_t width, uint32_t height, const std::string& what) {
  if (width == 0 || width > kMaxImageSide) throw InputError(DimensionError("width", what));
  if (height == 0 || height > kMaxImageSide) throw InputError(DimensionError("height", what));
}

CameraModelInfo ProjectableModel(const std::string& model_name, const std::string& what) {
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
  return *model;
}

}  // namespace

QueryCamera MakeKnownCamera(const std::string& model_name, uint32_t width, uint32_t height,
                            std::vector<double> params, const std::string& what) {
  const CameraModelInfo model = ProjectableModel(model_name, what);
  CheckImageSize(width, height, what);
  for (const double value : params) {
    if (!std::isfinite(value))
      throw InputError(what + ": camera parameters must be finite numbers");
  }
  if (params.size() != static_cast<size_t>(model.num_params)) {
    throw InputError(what + ": " + std::string(model.name) + " takes " +
                     std::to_string(model.num_params) + " parameters, got " +
                     std::to_string(params.size()));
  }
  QueryCamera camera;
  camera.model_id = model.id;
  camera.width = width;
  camera.height = height;
  camera.params = std::move(params);
  if (!(MeanFocalLength(camera.model_id, camera.params) > 0)) {
    throw InputError(what + ": the focal length must be positive");
  }
  return camera;
}

QueryCamera ParseCameraSpec(const std::string& spec, const std::string& what) {
  std::istringstream in(spec);
  std::string model_name;
  if (!(in >> model_name))
    throw InputError(what + ": empty camera; expected 'MODEL WIDTH HEIGHT PARAMS...'");
  ProjectableModel(model_name, what);  // checked before the numbers that follow it
  const uint32_t width = ParseDimension(in, "width", what);
  const uint32_t height = ParseDimension(in, "height", what);
  std::vector<double> params;
  double value;
  while (in >> value) params.push_back(value);
  if (!in.eof()) throw InputError(what + ": camera parameters must be numbers");
  return MakeKnownCamera(model_name, width, height, std::move(params), what);
}

QueryCamera ParseImageSize(const std::string& spec, const std::string& what) {
  std::string text = spec;
  for (char& c : text) {
    if (c == 'x' || c == 'X') c = ' ';
  }
  std::istringstream in(text);
  const uint32_t width = ParseDimension(in, "width", what);
  const uint32_t height = ParseDimension(in, "height", what);
  std::string rest;
  if (in >> rest) throw InputError(what + ": expected 'WIDTH HEIGHT', got extra '" + rest + "'");
  QueryCamera camera = ImageSizeCamera(width, height, what);
  camera.source = IntrinsicsSource::kImageSizeOption;
  return camera;
}

QueryCamera ImageSizeCamera(uint32_t width, uint32_t height, const std::string& what) {
  CheckImageSize(width, height, what);
  return UnknownFocalCamera(width, height, IntrinsicsSource::kCameraOption);
}

QueryCamera WithUnknownFocal(const QueryCamera& camera) {
  QueryCamera unknown = ImageSizeCamera(camera.width, camera.height, "camera");
  unknown.source = camera.source;
  return unknown;
}

}  // namespace cwloc
