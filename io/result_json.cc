#include "io/result_json.h"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <type_traits>
#include <variant>

#include "camera/camera_models.h"

namespace cwloc {

nlohmann::ordered_json OptionsToJson(const QueryOptions& options) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const OptionSpec& spec : OptionTable()) {
    std::visit(
        [&](const auto& value) {
          if constexpr (std::is_same_v<std::decay_t<decltype(value)>, std::filesystem::path>)
            out[std::string(spec.name)] = value.string();
          else
            out[std::string(spec.name)] = value;
        },
        spec.get(options));
  }
  return out;
}

namespace {

nlohmann::ordered_json Rows(const Eigen::MatrixXd& matrix) {
  nlohmann::ordered_json rows = nlohmann::ordered_json::array();
  for (Eigen::Index r = 0; r < matrix.rows(); ++r) {
    nlohmann::ordered_json row = nlohmann::ordered_json::array();
    for (Eigen::Index c = 0; c < matrix.cols(); ++c) row.push_back(matrix(r, c));
    rows.push_back(std::move(row));
  }
  return rows;
}

nlohmann::ordered_json CovarianceToJson(const PoseCovariance& covariance,
                                        const std::optional<CovarianceScales>& calibration,
                                        const std::optional<Eigen::Matrix3d>& enu_position) {
  nlohmann::ordered_json out;
  out["pose"] = Rows(covariance.pose);
  out["position_radius95"] = Radius95(covariance.Position());
  if (covariance.focal_std_px) out["focal_std_px"] = *covariance.focal_std_px;
  out["calibration"] = calibration
                           ? nlohmann::ordered_json{{"rotation_scale", calibration->rotation},
                                                    {"position_scale", calibration->position}}
                           : nlohmann::ordered_json();
  if (enu_position) {
    out["enu_position"] = Rows(*enu_position);
    out["position_radius95_m"] = Radius95(*enu_position);
  }
  return out;
}

// Which distortion model a localized query was fitted with, and why.
nlohmann::ordered_json DistortionToJson(const LocalizationResult& result) {
  nlohmann::ordered_json out;
  out["model"] = std::string(CameraModelName(result.camera.model_id));
  out["fit"] = std::string(kDistortionFitNames[static_cast<size_t>(result.distortion_fit)]);
  switch (result.distortion_fit) {
    case DistortionFit::kGiven:
      out["why"] = "the camera was known: its own model and parameters, held fixed";
      break;
    case DistortionFit::kHeldAtZero:
      out["k"] = 0.0;
      out["why"] =
          "the focal length was estimated without the final refinement (--no-refine, a latency "
          "budget, or a refined camera that was not sane), so k stayed 0";
      break;
    case DistortionFit::kEstimated: {
      const double k = result.camera.params.back();
      out["k"] = k;
      std::string why =
          "the camera was not known: one radial term k was refined with the focal length, as "
          "COLMAP's registrator refines a camera that no registered image has refined";
      if (result.covariance && result.covariance->distortion_std) {
        const double k_std = *result.covariance->distortion_std;
        const bool significant = std::abs(k) >= 2.0 * k_std;
        out["k_std"] = k_std;
        out["k_significant"] = significant;
        why += significant ? "; the data constrain it (|k| is at least 2 standard deviations)"
                           : "; the data hardly constrain it (|k| is under 2 standard deviations)";
      }
      out["why"] = why;
      break;
    }
  }
  return out;
}

nlohmann::ordered_json PoseToJson(const CameraPose& pose) {
  const Eigen::Quaterniond& q = pose.rotation;
  const Eigen::Vector3d& t = pose.translation;
  const Eigen::Vector3d c = pose.Center();
  return {{"qvec", {q.w(), q.x(), q.y(), q.z()}},
          {"tvec", {t.x(), t.y(), t.z()}},
          {"center", {c.x(), c.y(), c.z()}}};
}

nlohmann::ordered_json CameraToJson(const QueryCamera& camera) {
  return {{"model", std::string(CameraModelName(camera.model_id))},
          {"width", camera.width},
          {"height", camera.height},
          {"params", camera.params},
          {"calibration", std::string(CalibrationName(camera.calibration))},
          {"intrinsics_source", std::string(IntrinsicsSourceName(camera.source))}};
}

nlohmann::ordered_json GeoToJson(const GeoPose& g) {
  return {{"latitude_deg", g.latitude_deg}, {"longitude_deg", g.longitude_deg},
          {"height_m", g.height_m},         {"enu", g.enu},
          {"heading_deg", g.heading_deg},   {"pitch_deg", g.pitch_deg},
          {"roll_deg", g.roll_deg}};
}

}  // namespace

nlohmann::ordered_json ResultToJson(const LocalizationResult& result, const QueryOptions& options) {
  nlohmann::ordered_json out;
  out["name"] = result.name;
  out["success"] = result.success;
  if (!result.success) out["failure_reason"] = result.failure_reason;
  if (result.success) {
    out["pose"] = {
        {"qvec", result.rotation}, {"tvec", result.translation}, {"center", result.center}};
  }
  out["camera"] = {{"model", std::string(CameraModelName(result.camera.model_id))},
                   {"width", result.camera.width},
                   {"height", result.camera.height},
                   {"params", result.camera.params},
                   {"focal_estimated", result.focal_estimated},
                   {"calibration", std::string(CalibrationName(result.camera.calibration))},
                   {"intrinsics_source", std::string(IntrinsicsSourceName(result.camera.source))}};
  if (result.success) out["camera"]["distortion"] = DistortionToJson(result);
  if (const auto& coupling = result.focal_depth) {
    out["focal_depth"] = {
        {"correlation", coupling->correlation},
        {"focal_std_px", coupling->focal_std_px},
        {"depth_std", coupling->depth_std},
        {"weakly_constrained", WeaklyConstrained(*coupling, result.camera.params.at(0))}};
  }
  if (const auto& covariance = result.covariance) {
    out["covariance"] = CovarianceToJson(*covariance, result.covariance_calibration,
                                         result.enu_position_covariance);
  }
  if (result.geo) out["geo"] = GeoToJson(*result.geo);
  if (result.priors.position || result.priors.gravity) {
    nlohmann::ordered_json priors = nlohmann::ordered_json::object();
    if (const auto& p = result.priors.position) {
      priors["position"] = {
          {"latitude_deg", p->latitude_deg},
          {"longitude_deg", p->longitude_deg},
          {"height_m",
           p->height_m ? nlohmann::ordered_json(*p->height_m) : nlohmann::ordered_json()},
          {"radius_m", p->radius_m},
          {"source", std::string(kPriorSourceNames[static_cast<size_t>(p->source)])},
          {"clusters_in_radius", result.priors.clusters_in_radius}};
    }
    if (result.priors.gravity) {
      priors["gravity"] = {{"direction", *result.priors.gravity}};
      if (result.priors.gravity_error_deg)
        priors["gravity"]["error_deg"] = *result.priors.gravity_error_deg;
    }
    out["priors"] = priors;
  }
  // The result's numbers, each at its place (result_fields.inc).
#define CWLOC_RESULT_FIELD(name, type, group, key, help) \
  (*group ? out[group][key] : out[key]) = result.name;
#include "localizer/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  nlohmann::ordered_json ranked = nlohmann::ordered_json::array();
  for (const RankedImage& image : result.ranked_images) {
    ranked.push_back({{"image_id", image.image_id}, {"name", image.name}, {"votes", image.votes}});
  }
  out["ranked_images"] = ranked;
  const StageTimes& t = result.times;
  if (result.photo) {
    out["photo"] = {{"extraction_width", result.photo->extraction_width},
                    {"extraction_height", result.photo->extraction_height},
                    {"first_octave", result.photo->first_octave},
                    {"max_features", result.photo->max_features}};
  }
  if (const auto& tracking = result.tracking) {
    nlohmann::ordered_json& record = out["tracking"];
    record["mode"] = kTrackingModeNames[static_cast<size_t>(tracking->mode)];
    record["predicted_from"] = tracking->predicted_from.empty()
                                   ? nlohmann::ordered_json(nullptr)
                                   : nlohmann::ordered_json(tracking->predicted_from);
    if (tracking->prediction_error) {
      record["prediction_error"] = *tracking->prediction_error;
      record["prediction_error_deg"] = *tracking->prediction_error_deg;
    }
    record["time_ms"] = tracking->seconds * 1e3;
  }
  nlohmann::ordered_json& times_ms = out["times_ms"];
#define CWLOC_STAGE_TIME(name, help) times_ms[#name] = t.name * 1e3;
#include "localizer/stage_times.inc"
#undef CWLOC_STAGE_TIME
  if (options.localizer.budget_ms > 0) {
    out["budget"] = {{"ms", options.localizer.budget_ms}, {"cut", result.budget_cut}};
  }
  out["parameters"] = OptionsToJson(options);
  return out;
}

nlohmann::ordered_json ErrorToJson(const std::string& name, const std::string& error) {
  return {{"name", name}, {"success", false}, {"error", error}};
}

std::string PoseLine(const std::string& name, const CameraPose& cam_from_world) {
  const Eigen::Quaterniond& q = cam_from_world.rotation;
  const Eigen::Vector3d& t = cam_from_world.translation;
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer), "%s %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                name.c_str(), q.w(), q.x(), q.y(), q.z(), t.x(), t.y(), t.z());
  return buffer;
}

std::string PoseLine(const LocalizationResult& result) {
  const auto& q = result.rotation;
  const auto& t = result.translation;
  return PoseLine(result.name, CameraPose(Eigen::Quaterniond(q[0], q[1], q[2], q[3]),
                                          Eigen::Vector3d(t[0], t[1], t[2])));
}

nlohmann::ordered_json RigResultToJson(const RigLocalizationResult& result,
                                       const QueryOptions& options) {
  nlohmann::ordered_json out;
  out["name"] = result.name;
  out["success"] = result.success;
  if (!result.success) out["failure_reason"] = result.failure_reason;
  const RigImageResult& reference = result.images.front();
  if (result.success) out["pose"] = PoseToJson(*reference.cam_from_world);
  nlohmann::ordered_json& rig = out["rig"];
  rig["reference_image"] = reference.matched.name;
  if (result.success) rig["rig_from_world"] = PoseToJson(result.rig_from_world);
  rig["unknown_scale"] = result.unknown_scale;
  rig["scale"] = result.scale;
  if (result.scale_std) rig["scale_std"] = *result.scale_std;
  rig["num_inliers"] = result.num_inliers;
  rig["correspondences"] = result.correspondences;
  rig["ransac_iterations"] = result.ransac_iterations;
  rig["refined"] = result.refined;
  if (result.success) rig["mean_reprojection_error_px"] = result.mean_reprojection_error_px;
  if (result.covariance)
    out["covariance"] = CovarianceToJson(*result.covariance, result.covariance_calibration, {});
  if (result.geo) out["geo"] = GeoToJson(*result.geo);
  nlohmann::ordered_json& images = out["images"];
  images = nlohmann::ordered_json::array();
  for (const RigImageResult& image : result.images) {
    const LocalizationResult& matched = image.matched;
    nlohmann::ordered_json record;
    record["name"] = matched.name;
    const Eigen::Quaterniond& q = image.cam_from_rig.rotation;
    const Eigen::Vector3d& t = image.cam_from_rig.translation;
    record["cam_from_rig"] = {{"qvec", {q.w(), q.x(), q.y(), q.z()}},
                              {"tvec", {t.x(), t.y(), t.z()}}};
    if (image.cam_from_world) record["pose"] = PoseToJson(*image.cam_from_world);
    record["camera"] = CameraToJson(image.camera);
    record["num_inliers"] = image.num_inliers;
    record["matches"] = {{"features", matched.num_features},
                         {"forward", matched.forward_matches},
                         {"back", matched.back_matches},
                         {"correspondences", matched.correspondences}};
    images.push_back(std::move(record));
  }
  out["times_ms"] = {{"images", result.seconds_images * 1e3},
                     {"rig_pose", result.seconds_rig_pose * 1e3},
                     {"total", result.seconds_total * 1e3}};
  out["parameters"] = OptionsToJson(options);
  return out;
}

}  // namespace cwloc
