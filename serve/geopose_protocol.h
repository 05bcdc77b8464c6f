#pragma once

// The OSCP GeoPose protocol (github.com/OpenArCloud/oscp-geopose-protocol, version 1): a
// request with a base64 camera image, the camera's model and a geolocation reading; a response
// with the camera's OGC GeoPose (Basic-Quaternion) and its accuracy (docs/serve.md).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "geo/georeference.h"
#include "results/localization_result.h"
#include "serve/request_inputs.h"

namespace cwloc {

struct GeoPoseRequest {
  std::string id;
  std::string image;   // decoded bytes: JPEG or PNG, or width x height grey pixels
  bool grey = false;   // raw pixels (GRAY8, or RGBA32 made grey)
  uint32_t width = 0;  // its `size`
  uint32_t height = 0;
};

// Reads the request; its camera (`params`: model and modelParams, with `size`) and its first
// geolocation reading (a horizontal position prior whose radius is the reading's accuracy, or
// kDefaultExifGpsRadiusM without one) go into `inputs`. Throws InputError "geopose: ..." naming
// the field and the problem.
GeoPoseRequest ParseGeoPoseRequest(std::string_view json_text, RequestInputs* inputs);

// The response for a localized result on a georeferenced index: position (lat, lon, h above the
// ellipsoid), the quaternion (x, y, z, w) that rotates the camera frame (COLMAP's: x right,
// y down, z forward) into the local east-north-up frame at the camera, and the accuracy (the
// position's and the orientation's standard deviation per axis, averaged over the axes, in
// metres and degrees) when the result has a covariance.
nlohmann::ordered_json GeoPoseResponse(const std::string& id, const LocalizationResult& result,
                                       const GeoFrame& frame);

}  // namespace cwloc
