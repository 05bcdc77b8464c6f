#pragma once

#include <array>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "geo/georeference.h"
#include "tools/eval/geo_error.h"
#include "tools/eval/ground_truth.h"
#include "tools/eval/recognition.h"
#include "tools/eval/result_reader.h"

namespace cwloc::eval {

struct Quartiles {
  double q1 = 0;
  double median = 0;
  double q3 = 0;
};

// The p-quantile (0 <= p <= 1) of sorted values by linear interpolation between closest
// ranks, numpy's default: h = p (n - 1), Q = x[floor h] + (h - floor h) (x[floor h + 1] - x[floor
// h]).
double Quantile(const std::vector<double>& sorted, double p);

// Q1, median and Q3 as above; nullopt for no values.
std::optional<Quartiles> ComputeQuartiles(std::vector<double> values);

// Stage times also get the 90th percentile (the tail the scale benchmark reports).
struct TimeQuantiles : Quartiles {
  double p90 = 0;
};

// Q1, median, Q3 and Q(0.9) as above; nullopt for no values.
std::optional<TimeQuantiles> ComputeTimeQuantiles(std::vector<double> values);

// visuallocalization.net's (position, rotation) thresholds.
struct Threshold {
  double position;
  double rotation_deg;
};
inline constexpr std::array<Threshold, 3> kThresholds = {{{0.25, 2.0}, {0.5, 5.0}, {5.0, 10.0}}};

// --gt-geo's threshold: the share of queries whose "geo" lies within this 3D distance (metres)
// of the true position.
inline constexpr double kGeoWithinMetres = 0.5;

enum class QueryStatus { kLocalized, kNotLocalized, kError, kMissing };
const char* QueryStatusName(
    QueryStatus status);  // "localized", "not_localized", "error", "missing"

struct QueryOutcome {
  std::string name;
  QueryStatus status = QueryStatus::kMissing;
  double position_error = 0;      // in the report's unit; only when localized
  double rotation_error_deg = 0;  // only when localized
  // With a georeference (--index), when localized: the centres compared in its ENU frame.
  std::optional<GroundError> enu_error;
  // With true positions (--gt-geo), when localized and the result has "geo".
  std::optional<GroundError> geo_error;
  // When localized with a covariance: whether the true centre lies in its 95 % ellipsoid.
  std::optional<bool> inside95;
};

// A run's "geo" positions against the true positions (--gt-geo), metres.
struct GeoComparison {
  int compared = 0;     // localized queries whose result has "geo"
  int without_geo = 0;  // localized queries whose result has none: missing for this comparison
  std::optional<Quartiles> error;  // 3D distance, over the compared queries
  std::optional<Quartiles> ground_error;
  std::optional<Quartiles> height_error;
  int within = 0;  // compared queries with a 3D error <= kGeoWithinMetres
};

// A sequence's frames (results with "tracking", cwloc-localize --sequence or --video).
struct SequenceReport {
  int frames = 0;  // results with a tracking mode, in the file's order
  int tracked = 0, relocalized = 0, lost = 0;
  // Position errors of the ground-truth frames by the mode that gave their pose.
  std::optional<Quartiles> tracked_error;
  std::optional<Quartiles> relocalized_error;
  int longest_without_pose = 0;  // consecutive frames without a pose, the most
  double with_pose_share = 0;    // (tracked + relocalized) / frames
};

// Rig frames (cwloc-localize --rig, --frames): each frame's error is its reference camera's.
struct RigReport {
  int frames = 0;     // rig records, by their reference images in the ground truth
  int localized = 0;  // of those, with a pose
  std::optional<Quartiles> position_error;  // of the reference cameras
  std::optional<Quartiles> rotation_error_deg;
};

struct RunReport {
  std::string label;
  std::filesystem::path path;
  ResultFormat format = ResultFormat::kPoses;
  int queries = 0;  // ground-truth queries
  int localized = 0;
  int not_localized = 0;                    // "success": false without "error"
  int errors = 0;                           // error records
  int missing = 0;                          // ground-truth queries with no result
  int unknown_names = 0;                    // results for names not in the ground truth (ignored)
  std::optional<Quartiles> position_error;  // over localized queries
  std::optional<Quartiles> rotation_error_deg;   // over localized queries
  std::array<int, kThresholds.size()> within{};  // localized queries inside each threshold
  int timed_records = 0;                         // result records that carry times_ms
  std::optional<std::array<TimeQuantiles, kStageNames.size()>> times_ms;
  std::vector<QueryOutcome> per_query;           // in ground-truth order
  std::optional<RecognitionScores> recognition;  // with --model and query points
  // With a georeference (--index): ground and height errors (metres) over localized queries.
  bool enu_errors = false;
  std::optional<Quartiles> ground_error;
  std::optional<Quartiles> height_error;
  std::optional<GeoComparison> geo;  // with true positions (--gt-geo)
  // Localized queries whose result has a covariance, and those whose true centre lies inside
  // the 95 % ellipsoid it gives: the covariance's coverage.
  int with_covariance = 0;
  int inside95 = 0;
  std::optional<SequenceReport> sequence;  // when the results are a sequence's frames
  // When the results are rig frames; the counts and errors above are then every image's.
  std::optional<RigReport> rig;
};

struct EvalReport {
  std::filesystem::path ground_truth_path;
  int queries = 0;
  std::optional<std::filesystem::path> scale_path;
  double scale = 1.0;  // model units -> report unit
  std::vector<RunReport> runs;
  int recognition_min_shared = 0;  // set when location recognition was scored
  // --index: the georeferenced index whose scale and ENU frame the distances use.
  std::optional<std::filesystem::path> index_path = std::nullopt;
  std::optional<Georeference> georeference = std::nullopt;
  // --gt-geo: the true positions' file and how many it holds.
  std::optional<std::filesystem::path> geo_truth_path = std::nullopt;
  int geo_truth_positions = 0;

  bool Metric() const { return scale_path.has_value() || georeference.has_value(); }
  const char* Unit() const { return Metric() ? "m" : "model units"; }
};

// What a run is compared with on the ground, beyond the poses.
struct GeoTruth {
  // --index: centres are also compared in its ENU frame (ground and height errors); the scale
  // passed to EvaluateRun should be its scale.
  const Georeference* georeference = nullptr;
  // --gt-geo: the true position of every ground-truth query (TruePositionsOfQueries).
  const std::unordered_map<std::string, Geodetic>* true_positions = nullptr;
};

// Compares one run with the ground truth; distances are multiplied by scale.
RunReport EvaluateRun(const std::vector<NamedPose>& ground_truth, const RunResults& run,
                      double scale, const std::string& label, const GeoTruth& geo = {});

// The report as described by schemas/eval-report.schema.json.
nlohmann::ordered_json ReportToJson(const EvalReport& report);

// The human-readable table that cwloc-eval prints.
std::string FormatTable(const EvalReport& report);

}  // namespace cwloc::eval
