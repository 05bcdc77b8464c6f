#include "serve/geopose_protocol.h"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <limits>
#include <vector>

#include "app/camera_spec.h"
#include "app/query_priors.h"
#include "base/error.h"
#include "localizer/pose/refine_pose.h"
#include "photo/grey_image.h"
#include "serve/base64.h"

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

// A JPEG or PNG by its signature, whatever `imageFormat` says (clients label encoded bytes
// RGBA32); else raw pixels of the stated size: GRAY8 as they are, RGBA32 to grey as a photo's
// colours are (COLMAP's luma, photo/grey_image.h).
void ReadImageFormat(const std::string& format, const std::string& where, GeoPoseRequest* parsed) {
  const std::string_view bytes = parsed->image;
  const bool jpeg = bytes.substr(0, 3) == "\xff\xd8\xff";
  const bool png = bytes.substr(0, 8) == "\x89PNG\r\n\x1a\n";
  if (jpeg || png) return;
  const uint64_t pixels = uint64_t{parsed->width} * parsed->height;
  const auto check_bytes = [&](uint64_t per_pixel) {
    if (bytes.size() != pixels * per_pixel) {
      throw InputError("geopose: " + where + ": " + format + " of " +
                       std::to_string(parsed->width) + " x " + std::to_string(parsed->height) +
                       " needs " + std::to_string(pixels * per_pixel) + " bytes, got " +
                       std::to_string(bytes.size()));
    }
  };
  if (format == "GRAY8") {
    check_bytes(1);
  } else if (format == "RGBA32") {
    check_bytes(4);
    std::string grey(pixels, '\0');
    const auto* rgba = reinterpret_cast<const uint8_t*>(bytes.data());
    for (uint64_t i = 0; i < pixels; ++i)
      grey[i] = static_cast<char>(Luma709(rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]));
    parsed->image = std::move(grey);
  } else if (format == "JPG" || format == "JPEG" || format == "PNG") {
    throw InputError("geopose: " + where + ": 'imageBytes' are no JPEG or PNG (imageFormat " +
                     format + ")");
  } else {
    throw InputError("geopose: " + where +
                     ": 'imageFormat' must be JPG, PNG, RGBA32 or GRAY8 (cwloc reads no other)");
  }
  parsed->grey = true;
}

}  // namespace

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
  const Json& size = Field(camera, "size", where);
  if (!size.is_array() || size.size() != 2)
    throw InputError("geopose: " + where + ": 'size': expected [width, height]");
  parsed.width = ImageSide(size[0], where + ".size[0]");
  parsed.height = ImageSide(size[1], where + ".size[1]");
  const Json& image = Field(camera, "imageBytes", where);
  if (!image.is_string()) throw InputError("geopose: " + where + ": 'imageBytes': expected base64");
  parsed.image = DecodeBase64(image.get<std::string>(), "geopose: " + where + ".imageBytes");
  ReadImageFormat(image_format, where, &parsed);
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
    // The protocol's clients send 0 for an accuracy they do not know.
    double radius = kDefaultExifGpsRadiusM;
    if (const auto accuracy = fix.find("accuracy"); accuracy != fix.end() && !accuracy->is_null()) {
      const double given = FiniteNumber(*accuracy, fix_where + ".accuracy");
      if (given > 0) radius = given;
    }
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
  // Always there (the protocol's clients read it); unknown is the largest double, as theirs.
  double position = std::numeric_limits<double>::max();
  double orientation = std::numeric_limits<double>::max();
  if (result.covariance && result.covariance->enu_position) {
    const std::array<double, 9>& enu = *result.covariance->enu_position;
    position = std::sqrt((enu[0] + enu[4] + enu[8]) / 3);
    orientation = std::sqrt(PoseBlock(*result.covariance).topLeftCorner<3, 3>().trace() / 3) *
                  kDegreesPerRadian;
  }
  response["accuracy"] = {{"position", position}, {"orientation", orientation}};
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
