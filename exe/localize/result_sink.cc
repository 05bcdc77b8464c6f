#include "exe/localize/result_sink.h"

#include <cstdio>
#include <iostream>

#include "app/result_json.h"

namespace cwloc {
namespace {

// " f 1380.2 +- 9.7 px," for an estimated focal length, and what a weak constraint leaves.
std::string EstimatedFocalText(const LocalizationResult& result) {
  if (!result.focal_depth || result.camera.params.empty()) return "";
  const FocalDepth& uncertainty = *result.focal_depth;
  const double focal = result.camera.params[0];
  char text[160];
  if (uncertainty.weakly_constrained) {
    std::snprintf(text, sizeof(text), " f %.1f +- %.1f px, weakly constrained (depth +- %.3g),",
                  focal, uncertainty.focal_std_px, uncertainty.depth_std);
  } else {
    std::snprintf(text, sizeof(text), " f %.1f +- %.1f px,", focal, uncertainty.focal_std_px);
  }
  return text;
}

// " position +- 0.8 m (95 %)," in metres for a georeferenced index, else in model units.
std::string PositionRadiusText(const LocalizationResult& result) {
  if (!result.covariance) return "";
  char text[96];
  if (const auto& metres = result.covariance->position_radius95_m) {
    std::snprintf(text, sizeof(text), " position +- %.3g m (95 %%),", *metres);
  } else {
    std::snprintf(text, sizeof(text), " position +- %.3g model units (95 %%),",
                  result.covariance->position_radius95);
  }
  return text;
}

}  // namespace

void ResultSink::Write(const LocalizationResult& result, const QueryOptions& options,
                       FrameStamp stamp) {
  std::lock_guard lock(mutex_);
  if (closed_) return;  // a query abandoned by a stopped batch
  EmitJsonLine(ResultToJson(result, options).dump());
  // With the JSON in a file, stdout gets a readable line per query.
  if (json_file_ && !cli_.quiet) {
    // A frame of a sequence says how it got its pose.
    const char* how = result.tracking ? NameOf(result.tracking->mode).data() : "localized";
    if (result.success) {
      std::printf("%s: %s, %u inliers / %u correspondences,%s%s %.1f ms\n", result.name.c_str(),
                  how, result.num_inliers, result.correspondences,
                  PositionRadiusText(result).c_str(), EstimatedFocalText(result).c_str(),
                  result.times.total * 1e3);
    } else {
      std::printf("%s: not localized: %s\n", result.name.c_str(), result.failure_reason.c_str());
    }
    std::fflush(stdout);
  }
  if (poses_file_ && result.success) Append(*poses_file_, PoseLine(result));
  if (trajectory_file_ && result.success)
    Append(*trajectory_file_, TrajectoryLine(result, stamp, trajectory_format_));
}

void ResultSink::WriteRig(const RigResult& result, const QueryOptions& options) {
  std::lock_guard lock(mutex_);
  if (closed_) return;
  EmitJsonLine(RigResultToJson(result, options).dump());
  if (json_file_ && !cli_.quiet) {
    if (result.success) {
      char position[96] = "";
      if (result.covariance) {
        std::snprintf(position, sizeof(position), " position +- %.3g model units (95 %%),",
                      result.covariance->position_radius95);
      }
      std::printf("%s: rig localized, %u inliers over %zu images,%s %.1f ms\n", result.name.c_str(),
                  result.rig.num_inliers, result.images.size(), position, result.times.total * 1e3);
    } else {
      std::printf("%s: not localized: %s\n", result.name.c_str(), result.failure_reason.c_str());
    }
    std::fflush(stdout);
  }
  if (poses_file_ && result.success) {
    for (const RigImageResult& image : result.images)
      Append(*poses_file_, PoseLine(image.name, *image.pose));
  }
}

}  // namespace cwloc
