#pragma once

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "geo/georeference.h"
#include "tools/eval/pose_error.h"

namespace cwloc::eval {

// The per-stage times of cwloc-localize's "times_ms", in the schema's order. "extraction"
// (a photo's SIFT) is absent from results written before photo queries existed: read as 0.
inline constexpr std::array<const char*, 7> kStageNames = {
    "extraction", "forward_knn", "ratio_test", "query_tree", "back_matching", "pose", "total"};
using StageTimes = std::array<double, kStageNames.size()>;

enum class ResultStatus { kLocalized, kNotLocalized, kError };

// One query of a run, whatever file it came from.
struct QueryResult {
  std::string name;
  ResultStatus status = ResultStatus::kNotLocalized;
  std::optional<Pose> pose;  // set when localized
  // The camera centre on the globe ("geo": latitude_deg, longitude_deg, height_m), which
  // cwloc-localize writes when its index is georeferenced; never from a poses file.
  std::optional<Geodetic> geo;
  std::optional<StageTimes> times_ms;
  // The camera centre's covariance (the lower-right 3 x 3 of "covariance.pose"), model units.
  std::optional<Eigen::Matrix3d> position_covariance;
  std::vector<uint32_t> ranked_image_ids;  // "ranked_images", best first (JSON lines only)
  std::string tracking_mode;               // a sequence frame's "tracking.mode"; empty otherwise
  // An image of a rig frame's record (cwloc-localize --rig, --frames): the frame's name, and
  // whether the image is its reference camera, whose error is the frame's.
  std::string rig_frame;
  bool rig_reference = false;
  int line = 0;
};

enum class ResultFormat { kJsonLines, kPoses };
const char* ResultFormatName(ResultFormat format);  // "json-lines" / "poses"

struct RunResults {
  std::filesystem::path path;
  ResultFormat format = ResultFormat::kPoses;
  std::vector<QueryResult> queries;
};

// Reads cwloc-localize JSON lines or a poses file, telling them apart by content: the first
// line that is not blank or a '#' comment starts with '{' for JSON lines. A rig frame's record
// gives one result per image, named by the image, with the pose the rig gave it. Throws InputError
// naming the file and line for malformed input and for a query name given twice.
RunResults ReadResults(const std::filesystem::path& path);

}  // namespace cwloc::eval
