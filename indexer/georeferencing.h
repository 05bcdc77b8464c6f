#pragma once

// `cwloc-index build --georef FILE | --georef-images DIR | --model-frame ecef|enu:LAT,LON,H`:
// where the model lies on the globe, stored as the optional GEOR section (docs/geo.md).

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "format/index_sections.h"
#include "geo/georeference_fit.h"
#include "indexer/model_views.h"

namespace cwloc {

struct GeoreferencingOptions {
  std::filesystem::path georef_file;  // --georef: IMAGE_NAME LAT LON HEIGHT [SIGMA_M] lines
  std::filesystem::path images_dir;   // --georef-images: the model's photos, read for EXIF GPS
  std::string model_frame;            // --model-frame: "ecef" or "enu:LAT,LON,H"
  GeoFitOptions fit;                  // its default_sigma_m is --georef-sigma

  bool Requested() const {
    return !georef_file.empty() || !images_dir.empty() || !model_frame.empty();
  }
};

struct ModelGeoreference {
  IndexGeoreference section;
  nlohmann::ordered_json manifest;  // the manifest's "georeference" object
};

// nullopt when no georeference was asked for. Throws InputError naming the option, file or
// image for every problem (two sources given, an unknown image name, a photo that cannot be
// read, too few positions, a degenerate fit). fit.default_sigma_m (--georef-sigma) is in the
// range ValidateBuildOptions checks (BuildIndex does, before reading the model).
std::optional<ModelGeoreference> GeoreferenceModel(const ModelViews& views,
                                                   const GeoreferencingOptions& options);

}  // namespace cwloc
