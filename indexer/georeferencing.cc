#include "indexer/georeferencing.h"

#include <algorithm>
#include <sstream>
#include <unordered_map>
#include <vector>

#include "base/error.h"
#include "geo/index_georeference.h"
#include "photo/exif.h"
#include "photo/image_decode.h"

namespace cwloc {
namespace {

nlohmann::ordered_json GeodeticJson(const Geodetic& g) {
  return {{"latitude_deg", g.latitude_deg},
          {"longitude_deg", g.longitude_deg},
          {"height_m", g.height_m}};
}

nlohmann::ordered_json SimilarityJson(const Georeference& g) {
  return {{"origin", GeodeticJson(g.origin)},
          {"scale", g.scale},
          {"rotation", {g.rotation.w(), g.rotation.x(), g.rotation.y(), g.rotation.z()}},
          {"translation", {g.translation.x(), g.translation.y(), g.translation.z()}}};
}

// "enu:LAT,LON,H" -> the origin; throws naming the option.
Geodetic ParseEnuOrigin(const std::string& spec) {
  const std::string what = "--model-frame '" + spec + "'";
  std::string rest = spec.substr(4);
  for (char& c : rest)
    if (c == ',') c = ' ';
  std::istringstream in(rest);
  Geodetic origin;
  std::string extra;
  if (!(in >> origin.latitude_deg >> origin.longitude_deg >> origin.height_m) || (in >> extra)) {
    throw InputError(what + ": expected enu:LAT,LON,HEIGHT (degrees, metres)");
  }
  ValidateGeodetic(origin, what);
  return origin;
}

ModelGeoreference GivenModelFrame(const ModelViews& views, const std::string& spec) {
  ModelGeoreference out;
  Georeference georeference;
  if (spec == "ecef") {
    // The ENU origin at the cameras' centroid: any origin converts exactly, a near one keeps
    // the stored ENU coordinates small.
    Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
    for (const IndexImage& image : views.images) centroid += CameraCenterOf(image);
    centroid /= static_cast<double>(std::max<size_t>(1, views.images.size()));
    if (centroid.norm() < 6.0e6 || centroid.norm() > 7.0e6) {
      throw InputError("--model-frame ecef: the cameras' centroid is " +
                       std::to_string(centroid.norm() / 1000) +
                       " km from the earth's centre; the model is not in ECEF metres");
    }
    const GeoFrame at_zero(GeoreferenceFromEcefModel({0, 0, 0}));
    georeference = GeoreferenceFromEcefModel(at_zero.ModelToGeodetic(centroid));
    out.section = SectionOfGeoreference(georeference);
    out.section.source = static_cast<uint32_t>(GeoreferenceSource::kEcefModel);
    out.manifest["source"] = "model-frame-ecef";
  } else if (spec.rfind("enu:", 0) == 0) {
    georeference = GeoreferenceFromEnuModel(ParseEnuOrigin(spec));
    out.section = SectionOfGeoreference(georeference);
    out.section.source = static_cast<uint32_t>(GeoreferenceSource::kEnuModel);
    out.manifest["source"] = "model-frame-enu";
  } else {
    throw InputError("--model-frame '" + spec + "': expected ecef or enu:LAT,LON,HEIGHT");
  }
  out.manifest["model_frame"] = spec;
  out.manifest.update(SimilarityJson(georeference));
  return out;
}

// The model camera centre of every observation's image; unknown names are an error.
std::vector<Eigen::Vector3d> CentersOf(const ModelViews& views,
                                       std::span<const GeoObservation> observations,
                                       const std::string& source) {
  std::unordered_map<std::string_view, const IndexImage*> by_name;
  for (const IndexImage& image : views.images) by_name[views.ImageName(image)] = &image;
  std::vector<Eigen::Vector3d> centers;
  for (const GeoObservation& observation : observations) {
    const auto it = by_name.find(observation.image_name);
    if (it == by_name.end()) {
      throw InputError(source + ": image '" + observation.image_name + "' is not in the model");
    }
    centers.push_back(CameraCenterOf(*it->second));
  }
  return centers;
}

// EXIF GPS of every model image's photo; images without a fix (or its altitude) are skipped.
std::vector<GeoObservation> ExifObservations(const ModelViews& views,
                                             const std::filesystem::path& dir, size_t* without) {
  std::vector<GeoObservation> observations;
  for (const IndexImage& image : views.images) {
    const std::string name(views.ImageName(image));
    const std::optional<ExifGps> gps = ReadExifGps(ReadPhotoFile(dir / name));
    if (!gps || !gps->altitude_m) {
      ++*without;
      continue;
    }
    GeoObservation observation;
    observation.image_name = name;
    observation.position = {gps->latitude_deg, gps->longitude_deg, *gps->altitude_m};
    observation.sigma_m = gps->horizontal_error_m.value_or(0.0);
    observations.push_back(observation);
  }
  return observations;
}

ModelGeoreference FittedGeoreference(const ModelViews& views,
                                     const GeoreferencingOptions& options) {
  const bool from_file = !options.georef_file.empty();
  const std::string source =
      from_file ? options.georef_file.string() : "--georef-images " + options.images_dir.string();
  size_t without_gps = 0;
  const std::vector<GeoObservation> observations =
      from_file ? ReadGeorefFile(options.georef_file)
                : ExifObservations(views, options.images_dir, &without_gps);
  const std::vector<Eigen::Vector3d> centers = CentersOf(views, observations, source);
  GeoFitResult fit;
  try {
    fit = FitGeoreference(centers, observations, options.fit);
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }

  ModelGeoreference out;
  out.section = SectionOfGeoreference(fit.georeference);
  out.section.source =
      static_cast<uint32_t>(from_file ? GeoreferenceSource::kFile : GeoreferenceSource::kExifGps);
  out.section.rms_residual_m = fit.rms_residual_m;
  out.section.num_observations = static_cast<uint32_t>(observations.size());
  out.section.num_inliers = static_cast<uint32_t>(fit.num_inliers);

  double max_inlier_residual = 0;
  nlohmann::ordered_json outliers = nlohmann::ordered_json::array();
  for (size_t i = 0; i < observations.size(); ++i) {
    if (fit.inliers[i]) {
      max_inlier_residual = std::max(max_inlier_residual, fit.residuals_m[i]);
    } else {
      outliers.push_back(
          {{"image", observations[i].image_name}, {"residual_m", fit.residuals_m[i]}});
    }
  }
  out.manifest["source"] = from_file ? "georef-file" : "exif-gps";
  out.manifest["path"] = from_file ? options.georef_file.string() : options.images_dir.string();
  out.manifest.update(SimilarityJson(fit.georeference));
  out.manifest["fit"] = {{"observations", observations.size()},
                         {"inliers", fit.num_inliers},
                         {"default_sigma_m", options.fit.default_sigma_m},
                         {"inlier_sigmas", options.fit.inlier_sigmas},
                         {"rms_residual_m", fit.rms_residual_m},
                         {"max_inlier_residual_m", max_inlier_residual},
                         {"outliers", outliers}};
  if (!from_file) out.manifest["fit"]["images_without_gps"] = without_gps;
  return out;
}

}  // namespace

std::optional<ModelGeoreference> GeoreferenceModel(const ModelViews& views,
                                                   const GeoreferencingOptions& options) {
  const int sources = int{!options.georef_file.empty()} + int{!options.images_dir.empty()} +
                      int{!options.model_frame.empty()};
  if (sources == 0) return std::nullopt;
  if (sources > 1) {
    throw InputError("--georef, --georef-images and --model-frame exclude each other; give one");
  }
  if (!options.model_frame.empty()) return GivenModelFrame(views, options.model_frame);
  return FittedGeoreference(views, options);
}

}  // namespace cwloc
