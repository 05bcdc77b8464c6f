#include "io/result_json.h"

#include <cstdio>

#include "camera/camera_models.h"

namespace cwloc {

nlohmann::ordered_json OptionsToJson(const LocalizerOptions& options) {
  return {{"matcher", std::string(MatcherName(options.matcher))},
          {"k", options.k},
          {"checks", options.checks},
          {"ratio", options.ratio},
          {"forward_matches", options.forward_matches},
          {"back_matches", options.back_matches},
          {"max_back_matches", options.max_back_matches},
          {"max_back_images", options.max_back_clusters},
          {"min_matches_to_vote", options.min_matches_to_vote},
          {"query_tree_checks", options.query_tree_checks},
          {"back_matching", std::string(kBackMatchingNames[size_t(options.back_matching)])},
          {"guide_radius_px", options.guide_radius_px},
          {"budget_ms", options.budget_ms},
          {"min_inliers", options.pose.min_inliers},
          {"max_error_px", options.pose.max_error_px},
          {"min_ransac_iterations", options.pose.ransac.min_iterations},
          {"max_ransac_iterations", options.pose.ransac.max_iterations},
          {"ransac_confidence", options.pose.ransac.confidence},
          {"refine", options.pose.refine},
          {"refiner", std::string(PoseRefinerName(options.pose.refiner))},
          {"prior_gravity_sigma_deg", options.prior_gravity_sigma_deg},
          {"seed", options.seed}};
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
                                        const std::optional<Eigen::Matrix3d>& enu_position) {
  nlohmann::ordered_json out;
  out["pose"] = Rows(covariance.pose);
  out["position_radius95"] = Radius95(covariance.Position());
  if (covariance.focal_std_px) out["focal_std_px"] = *covariance.focal_std_px;
  if (enu_position) {
    out["enu_position"] = Rows(*enu_position);
    out["position_radius95_m"] = Radius95(*enu_position);
  }
  return out;
}

}  // namespace

nlohmann::ordered_json ResultToJson(const LocalizationResult& result,
                                    const LocalizerOptions& options) {
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
  if (const auto& coupling = result.focal_depth) {
    out["focal_depth"] = {
        {"correlation", coupling->correlation},
        {"focal_std_px", coupling->focal_std_px},
        {"depth_std", coupling->depth_std},
        {"weakly_constrained", WeaklyConstrained(*coupling, result.camera.params.at(0))}};
  }
  if (const auto& covariance = result.covariance) {
    out["covariance"] = CovarianceToJson(*covariance, result.enu_position_covariance);
  }
  if (result.geo) {
    const GeoPose& g = *result.geo;
    out["geo"] = {{"latitude_deg", g.latitude_deg}, {"longitude_deg", g.longitude_deg},
                  {"height_m", g.height_m},         {"enu", g.enu},
                  {"heading_deg", g.heading_deg},   {"pitch_deg", g.pitch_deg},
                  {"roll_deg", g.roll_deg}};
  }
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
  out["num_inliers"] = result.num_inliers;
  out["inlier_ratio"] = result.inlier_ratio;
  out["matches"] = {{"features", result.num_features},
                    {"features_searched", result.features_searched},
                    {"forward", result.forward_matches},
                    {"back", result.back_matches},
                    {"correspondences", result.correspondences},
                    {"back_matched_images", result.back_matched_clusters},
                    {"guided", result.guided},
                    {"ransac_iterations", result.ransac_iterations}};
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
  out["times_ms"] = {{"extraction", t.extraction * 1e3},
                     {"forward_knn", t.forward_knn * 1e3},
                     {"ratio_test", t.ratio_test * 1e3},
                     {"query_tree", t.query_tree * 1e3},
                     {"back_matching", t.back_matching * 1e3},
                     {"pose", t.pose * 1e3},
                     {"total", t.total * 1e3}};
  if (options.budget_ms > 0) {
    out["budget"] = {{"ms", options.budget_ms}, {"cut", result.budget_cut}};
  }
  out["parameters"] = OptionsToJson(options);
  return out;
}

nlohmann::ordered_json ErrorToJson(const std::string& name, const std::string& error) {
  return {{"name", name}, {"success", false}, {"error", error}};
}

std::string PoseLine(const LocalizationResult& result) {
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer), "%s %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                result.name.c_str(), result.rotation[0], result.rotation[1], result.rotation[2],
                result.rotation[3], result.translation[0], result.translation[1],
                result.translation[2]);
  return buffer;
}

}  // namespace cwloc
