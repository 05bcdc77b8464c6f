#include "serve/geopose_protocol.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <vector>

#include "app/camera_spec.h"
#include "app/query_priors.h"
#include "base/error.h"
#include "localizer/pose/refine_pose.h"

namespace cwloc {
namespace {

using Json = nlohmann::json;

constexpr double kDegreesPerRadian = 180.0 / 3.14159265358979323846;

const Json& Field(const Json& object, const char* key, const std::string& where) {
  const auto found = object.find(key);
  if (found == object.end()) throw InputError("geopose: " + where + " has no '" + key + "'");
  return *found;
}

double FiniteNumber(const Json& value, const std::string& where) {
  if (!value.is_number() || !std::isfinite(value.get<double>()))
    throw InputError("geopose: " + where + ": expected a finite number");
  return value.get<double>();
}

uint32_t ImageSide(const Json& value, const std::string& where) {
  const double side = FiniteNumber(value, where);
  if (side < 1 || side > 100000 || side != std::floor(side))
    throw InputError("geopose: " + where + ": expected a whole number of pixels in 1..100000");
  return static_cast<uint32_t>(side);
}

}  // namespace

std::string DecodeBase64(std::string_view text, const std::string& what) {
  while (!text.empty() && text.back() == '=') text.remove_suffix(1);
  if (text.size() % 4 == 1) throw InputError(what + ": base64 of a length no encoding has");
  std::string bytes;
  bytes.reserve(text.size() / 4 * 3 + 2);
  uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    int value;
    if (c >= 'A' && c <= 'Z') {
      value = c - 'A';
    } else if (c >= 'a' && c <= 'z') {
      value = c - 'a' + 26;
    } else if (c >= '0' && c <= '9') {
      value = c - '0' + 52;
    } else if (c == '+' || c == '-') {
      value = 62;
    } else if (c == '/' || c == '_') {
      value = 63;
    } else {
      throw InputError(what + ": not base64 (a character outside A-Z a-z 0-9 + /)");
    }
    bits = bits << 6 | static_cast<uint32_t>(value);
    if (++count == 4) {
      bytes.push_back(static_cast<char>(bits >> 16));
      bytes.push_back(static_cast<char>(bits >> 8 & 0xff));
      bytes.push_back(static_cast<char>(bits & 0xff));
      bits = 0;
      count = 0;
    }
  }
  if (count == 2) bytes.push_back(static_cast<char>(bits >> 4));
  if (count == 3) {
    bytes.push_back(static_cast<char>(bits >> 10));
    bytes.push_back(static_cast<char>(bits >> 2 & 0xff));
  }
  return bytes;
}

GeoPoseRequest ParseGeoPoseRequest(std::string_view json_text, RequestInputs* inputs) {
  const Json request = Json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (request.is_discarded()) throw InputError("geopose: not valid JSON");
  if (!request.is_object()) throw InputError("geopose: expected a JSON object");
  GeoPoseRequest parsed;
  if (const auto id = request.find("id"); id != request.end()) {
    if (!id->is_string()) throw InputError("geopose: 'id': expected a string");
    parsed.id = id->get<std::string>();
  }
  const Json& readings = Field(request, "sensorReadings", "the request");
  if (!readings.is_object()) throw InputError("geopose: 'sensorReadings': expected an object");
  const Json& cameras = Field(readings, "cameraReadings", "'sensorReadings'");
  if (!cameras.is_array() || cameras.empty())
    throw InputError("geopose: 'cameraReadings': expected an array of one reading or more");
  const Json& camera = cameras.front();
  if (!camera.is_object()) throw InputError("geopose: 'cameraReadings'[0]: expected an object");
  const std::string where = "'cameraReadings'[0]";

  const Json& format = Field(camera, "imageFormat", where);
  const std::string image_format = format.is_string() ? format.get<std::string>() : "";
  if (image_format == "GRAY8") {
    parsed.grey = true;
  } else if (image_format != "JPG" && image_format != "JPEG" && image_format != "PNG") {
    throw InputError("geopose: " + where +
                     ": 'imageFormat' must be JPG, PNG or GRAY8 (cwloc reads no other)");
  }
  const Json& size = Field(camera, "size", where);
  if (!size.is_array() || size.size() != 2)
    throw InputError("geopose: " + where + ": 'size': expected [width, height]");
  parsed.width = ImageSide(size[0], where + ".size[0]");
  parsed.height = ImageSide(size[1], where + ".size[1]");
  const Json& image = Field(camera, "imageBytes", where);
  if (!image.is_string()) throw InputError("geopose: " + where + ": 'imageBytes': expected base64");
  parsed.image = DecodeBase64(image.get<std::string>(), "geopose: " + where + ".imageBytes");
  if (parsed.grey && parsed.image.size() != uint64_t{parsed.width} * parsed.height) {
    throw InputError("geopose: " + where + ": GRAY8 of " + std::to_string(parsed.width) + " x " +
                     std::to_string(parsed.height) + " needs as many bytes, got " +
                     std::to_string(parsed.image.size()));
  }
  if (const auto params = camera.find("params"); params != camera.end() && params->is_object()) {
    const auto model = params->find("model");
    if (model != params->end() && model->is_string() && *model != "UNKNOWN_CAMERA") {
      const Json& numbers = Field(*params, "modelParams", where + ".params");
      if (!numbers.is_array())
        throw InputError("geopose: " + where + ".params.modelParams: expected numbers");
      std::vector<double> values;
      for (const Json& number : numbers)
        values.push_back(FiniteNumber(number, where + ".params.modelParams"));
      inputs->cameras.camera =
          MakeKnownCamera(model->get<std::string>(), parsed.width, parsed.height, std::move(values),
                          "geopose: " + where + ".params");
    }
  }

  if (const auto geolocations = readings.find("geolocationReadings");
      geolocations != readings.end() && geolocations->is_array() && !geolocations->empty()) {
    const Json& fix = geolocations->front();
    const std::string fix_where = "'geolocationReadings'[0]";
    if (!fix.is_object()) throw InputError("geopose: " + fix_where + ": expected an object");
    const double latitude =
        FiniteNumber(Field(fix, "latitude", fix_where), fix_where + ".latitude");
    const double longitude =
        FiniteNumber(Field(fix, "longitude", fix_where), fix_where + ".longitude");
    double radius = kDefaultExifGpsRadiusM;
    if (const auto accuracy = fix.find("accuracy"); accuracy != fix.end() && !accuracy->is_null())
      radius = FiniteNumber(*accuracy, fix_where + ".accuracy");
    char text[96];
    std::snprintf(text, sizeof(text), "%.10f %.10f %.3f", latitude, longitude, radius);
    inputs->priors.position = ParsePositionPrior(text, "geopose: " + fix_where);
  }
  return parsed;
}

nlohmann::ordered_json GeoPoseResponse(const std::string& id, const LocalizationResult& result,
                                       const GeoFrame& frame) {
  const Eigen::Vector3d center(result.center[0], result.center[1], result.center[2]);
  const Eigen::Quaterniond cam_from_model(result.rotation[0], result.rotation[1],
                                          result.rotation[2], result.rotation[3]);
  const Eigen::Quaterniond enu_from_cam(frame.LocalEnuFromModel(center) *
                                        cam_from_model.toRotationMatrix().transpose());
  nlohmann::ordered_json response;
  response["id"] = id;
  response["timestamp"] = std::chrono::duration_cast<std::chrono::milliseconds>(
                              std::chrono::system_clock::now().time_since_epoch())
                              .count();
  if (result.covariance && result.covariance->enu_position) {
    const std::array<double, 9>& enu = *result.covariance->enu_position;
    const double position = std::sqrt((enu[0] + enu[4] + enu[8]) / 3);
    const double orientation =
        std::sqrt(PoseBlock(*result.covariance).topLeftCorner<3, 3>().trace() / 3) *
        kDegreesPerRadian;
    response["accuracy"] = {{"position", position}, {"orientation", orientation}};
  }
  response["type"] = "geopose";
  const GeoPose& geo = *result.geo;
  response["geopose"] = {
      {"position", {{"lat", geo.latitude_deg}, {"lon", geo.longitude_deg}, {"h", geo.height_m}}},
      {"quaternion",
       {{"x", enu_from_cam.x()},
        {"y", enu_from_cam.y()},
        {"z", enu_from_cam.z()},
        {"w", enu_from_cam.w()}}}};
  return response;
}

}  // namespace cwloc
