// A query's answer: what the localizer returns, the C++ API hands out (cwloc::api::Result), C
// reads by path, Python as cwloc.Result, and cwloc-localize writes as one JSON line
// (results/describe.h; schemas/localization-result.schema.json).
#ifndef CWLOC_RESULTS_LOCALIZATION_RESULT_H_
#define CWLOC_RESULTS_LOCALIZATION_RESULT_H_

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera.h"
#include "describe.h"
#include "geo_pose.h"
#include "pose.h"
#include "priors.h"
#include "tracking.h"

namespace cwloc {

// A model image and the co-visibility votes it got (docs/algorithm.md).
struct RankedImage {
  uint32_t image_id = 0;  // COLMAP's image id
  std::string name;
  uint32_t votes = 0;
};

// Wall-clock seconds per pipeline stage.
struct StageTimes {
  double extraction = 0;
  double forward_knn = 0;
  double ratio_test = 0;
  double query_tree = 0;
  double back_matching = 0;
  double pose = 0;
  double total = 0;
};

// How a photo query became features.
struct PhotoInfo {
  uint32_t extraction_width = 0;  // the image SIFT ran on, after --max-image-size
  uint32_t extraction_height = 0;
  int first_octave = -1;
  uint32_t max_features = 0;
};

// A latency budget (LocalizerOptions::budget_ms) and the stages it cut short.
struct Budget {
  double ms = 0;
  std::vector<std::string> cut;  // "forward", "back_matching", "ransac", "refinement"
};

// Why back-matching stopped (LocalizerOptions::back_matches and its neighbours).
enum class BackStop : int {
  kTarget,    // it had N_B back-matches (--nb-unknown-focal for an unknown focal length)
  kImages,    // it had back-matched --max-back-images clusters
  kNoVotes,   // no cluster it had not matched had votes left
  kDeadline,  // a latency budget ended it
  kNotRun,    // it did not run: another matcher, or nothing to start from
  kPinned,    // continued for an estimated focal length until a step shrank the position's
              // uncertainty by less than --pinned-shrink
  kBound,     // continued so, it reached --nb-max still shrinking
};
template <>
struct EnumNames<BackStop> {
  static constexpr std::array<std::string_view, 7> names = {
      "target", "images", "no-votes", "deadline", "not-run", "pinned", "bound"};
};

// A RANSAC inlier of the reported pose: which query feature saw which 3D point of the index.
struct Inlier {
  uint32_t feature = 0;             // row of the query's keypoints and descriptors
  std::array<float, 2> keypoint{};  // its pixel
  uint32_t point = 0;               // row of the index's points
  std::array<double, 3> xyz{};      // the point, model frame
  uint32_t view = 0;                // the model view (of that point) whose descriptor matched
};

struct LocalizationResult {
  std::string name;
  bool success = false;
  std::string failure_reason;  // empty on success
  // COLMAP's cam_from_world: X_cam = R(rotation) X_world + translation; rotation (w, x, y, z).
  std::array<double, 4> rotation{1, 0, 0, 0};
  std::array<double, 3> translation{};
  std::array<double, 3> center{};
  ResultCamera camera;
  std::optional<FocalDepth> focal_depth;
  std::optional<PoseCovariance> covariance;
  std::optional<GeoPose> geo;
  PriorsUsed priors;
  uint32_t num_inliers = 0;
  double inlier_ratio = 0;
  uint32_t num_features = 0;
  uint32_t features_searched = 0;
  uint32_t forward_matches = 0;
  uint32_t back_matches = 0;
  uint32_t correspondences = 0;
  uint32_t back_matched_clusters = 0;
  BackStop back_stop = BackStop::kNotRun;
  bool guided = false;
  uint32_t ransac_iterations = 0;
  std::vector<RankedImage> ranked_images;
  std::optional<PhotoInfo> photo;
  std::optional<TrackingInfo> tracking;
  StageTimes times;
  std::optional<Budget> budget;
  std::vector<Inlier> inliers;  // on success, in feature order
};

inline bool Failed(const LocalizationResult& result) { return !result.success; }
inline bool Localized(const LocalizationResult& result) { return result.success; }

template <>
struct Description<RankedImage> {
  static constexpr std::string_view name = "RankedImage";
  static constexpr std::string_view help = "A model image and the co-visibility votes it got";
  static constexpr auto fields = std::tuple(
      MakeField(&RankedImage::image_id,
                Info("image_id").Json("image_id").Help("COLMAP's image id")),
      MakeField(&RankedImage::name, Info("name").Json("name").Help("Its name in the model")),
      MakeField(&RankedImage::votes, Info("votes").Json("votes")));
};

namespace result_fields {
// A stage's seconds, which the record writes as milliseconds.
constexpr FieldInfo Stage(std::string_view name, std::string_view help) {
  return Info(name).Json(name).Unit("s").Help(help).Scale(1e3);
}
}  // namespace result_fields

template <>
struct Description<StageTimes> {
  static constexpr std::string_view name = "StageTimes";
  static constexpr std::string_view help = "Wall-clock time per pipeline stage";
  static constexpr auto fields = std::tuple(
      MakeField(&StageTimes::extraction,
                result_fields::Stage(
                    "extraction", "A photo's decoding and SIFT extraction; 0 for given features")),
      MakeField(&StageTimes::forward_knn,
                result_fields::Stage("forward_knn", "kd-forest searches of the query's features")),
      MakeField(&StageTimes::ratio_test,
                result_fields::Stage("ratio_test", "Cluster-wise ratio tests")),
      MakeField(
          &StageTimes::query_tree,
          result_fields::Stage("query_tree", "Building the kd-forest over the query's features")),
      MakeField(&StageTimes::back_matching,
                result_fields::Stage("back_matching",
                                     "Prioritized back-matching and co-visibility votes")),
      MakeField(&StageTimes::pose,
                result_fields::Stage(
                    "pose", "LO-RANSAC with the minimal solvers, then the final refinement")),
      MakeField(&StageTimes::total, result_fields::Stage("total", "The whole query")));
};

template <>
struct Description<PhotoInfo> {
  static constexpr std::string_view name = "PhotoInfo";
  static constexpr std::string_view help =
      "A photo query: the size of the image SIFT ran on (COLMAP's --max-image-size rule; "
      "keypoints are in the photo's own pixels) and the SIFT settings that made its features";
  static constexpr auto fields =
      std::tuple(MakeField(&PhotoInfo::extraction_width,
                           Info("extraction_width").Json("extraction_width").Unit("px")),
                 MakeField(&PhotoInfo::extraction_height,
                           Info("extraction_height").Json("extraction_height").Unit("px")),
                 MakeField(&PhotoInfo::first_octave,
                           Info("first_octave")
                               .Json("first_octave")
                               .Help("SIFT's first octave: -1 is COLMAP's, 0 and 1 the fast mode")),
                 MakeField(&PhotoInfo::max_features,
                           Info("max_features").Json("max_features").Help("SIFT's cap")));
};

template <>
struct Description<Budget> {
  static constexpr std::string_view name = "Budget";
  static constexpr std::string_view help =
      "A latency budget (--budget-ms) and the stages it cut short, in pipeline order";
  static constexpr auto fields = std::tuple(
      MakeField(&Budget::ms, Info("ms").Json("ms").Unit("ms")),
      MakeField(&Budget::cut, Info("cut").Json("cut").Help(
                                  "Of 'forward', 'back_matching', 'ransac', 'refinement'")));
};

template <>
struct Description<Inlier> {
  static constexpr std::string_view name = "Inlier";
  static constexpr std::string_view help = "A RANSAC inlier of the reported pose";
  static constexpr auto fields = std::tuple(
      MakeField(&Inlier::feature,
                Info("feature").Json("feature").Help("Row of the query's features")),
      MakeField(&Inlier::keypoint, Info("keypoint").Json("keypoint").Unit("px")),
      MakeField(&Inlier::point, Info("point").Json("point").Help("Row of the index's 3D points")),
      MakeField(&Inlier::xyz, Info("xyz").Json("xyz").Unit("model units").Help("The 3D point")),
      MakeField(&Inlier::view, Info("view").Json("view").Help(
                                   "Row of the index's views: the one whose descriptor matched")));
};

template <>
struct Description<LocalizationResult> {
  using R = LocalizationResult;
  static constexpr std::string_view name = "Result";
  static constexpr std::string_view help =
      "One query's answer. success False is no error: failure_reason says why. The pose is "
      "COLMAP's cam_from_world: X_cam = R X_world + t";
  static constexpr auto fields = std::tuple(
      MakeField(&R::name, Info("name").Json("name").Help("The query's name")),
      MakeField(&R::success, Info("success").Json("success")),
      MakeField(&R::failure_reason,
                Info("failure_reason").Json("failure_reason").Help("Why not localized"), &Failed),
      MakeField(&R::rotation,
                Info("rotation")
                    .Json("pose.qvec")
                    .Help("cam_from_world's unit quaternion (w, x, y, z), on success"),
                &Localized),
      MakeField(
          &R::translation,
          Info("translation").Json("pose.tvec").Help("cam_from_world's translation, on success"),
          &Localized),
      MakeField(&R::center,
                Info("center")
                    .Json("pose.center")
                    .Unit("model units")
                    .Help("The camera centre, model frame, on success"),
                &Localized),
      MakeField(&R::camera, Info("camera").Json("camera")),
      MakeField(&R::focal_depth,
                Info("focal_depth")
                    .Json("focal_depth")
                    .Help("A localized query whose focal length was estimated and refined")),
      MakeField(&R::covariance, Info("covariance")
                                    .Json("covariance")
                                    .Help("On success, unless the refinement problem is singular")),
      MakeField(&R::geo, Info("geo").Json("geo").Help("On success with a georeferenced index")),
      MakeField(&R::priors, Info("priors").Json("priors")),
      MakeField(&R::num_inliers, Info("num_inliers").Json("num_inliers").Help("RANSAC inliers")),
      MakeField(&R::inlier_ratio, Info("inlier_ratio")
                                      .Json("inlier_ratio")
                                      .Help("Inliers per 2D-3D correspondence given to RANSAC")),
      MakeField(&R::num_features,
                Info("num_features").Json("matches.features").Help("The query's")),
      MakeField(&R::features_searched,
                Info("features_searched")
                    .Json("matches.features_searched")
                    .Help("In the kd-forest (fewer when a latency budget cut it)")),
      MakeField(&R::forward_matches,
                Info("forward_matches")
                    .Json("matches.forward")
                    .Help("2D-3D matches of the forward search that passed the "
                          "ratio tests")),
      MakeField(&R::back_matches,
                Info("back_matches").Json("matches.back").Help("2D-3D matches of back-matching")),
      MakeField(&R::correspondences, Info("correspondences")
                                         .Json("matches.correspondences")
                                         .Help("Unique 2D-3D pairs given to RANSAC")),
      MakeField(&R::back_matched_clusters,
                Info("back_matched_clusters")
                    .Json("matches.back_matched_images")
                    .Help("Clusters back-matched (one model image each unless the "
                          "index was built with --clusters)")),
      MakeField(&R::back_stop,
                Info("back_stop").Json("matches.back_stop").Help("Why back-matching stopped")),
      MakeField(&R::guided, Info("guided")
                                .Json("matches.guided")
                                .Help("Whether a pose hypothesis guided "
                                      "back-matching")),
      MakeField(&R::ransac_iterations, Info("ransac_iterations")
                                           .Json("matches.ransac_iterations")
                                           .Help("RANSAC hypotheses drawn")),
      MakeField(&R::ranked_images, Info("ranked_images").Json("ranked_images").Help("By votes")),
      MakeField(&R::photo, Info("photo").Json("photo").Help("A photo query's")),
      MakeField(&R::tracking, Info("tracking").Json("tracking").Help("A frame of a sequence")),
      MakeField(&R::times, Info("times").Json("times_ms")),
      MakeField(&R::budget, Info("budget").Json("budget").Help("With a latency budget")),
      MakeField(&R::inliers,
                Info("inliers")
                    .Help("On success, in feature order")
                    .AsColumns()
                    .WhyNot("the JSON record: a line per query stays readable; a pose's "
                            "inliers are thousands of numbers (the C, C++ and Python APIs have "
                            "them)")));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_LOCALIZATION_RESULT_H_
