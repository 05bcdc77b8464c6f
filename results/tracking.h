// How a frame of a sequence got its pose (results/describe.h; docs/algorithm.md, "Sequences").
#ifndef CWLOC_RESULTS_TRACKING_H_
#define CWLOC_RESULTS_TRACKING_H_

#include <optional>
#include <string>

#include "describe.h"

namespace cwloc {

enum class TrackingMode : int {
  kTracked = 0,      // matched near the pose predicted from the frames before it
  kRelocalized = 1,  // localized from scratch: the first frame, or tracking failed its checks
  kLost = 2,         // neither gave a pose
};
template <>
struct EnumNames<TrackingMode> {
  static constexpr std::array<std::string_view, 3> names = {"tracked", "relocalized", "lost"};
};

struct TrackingInfo {
  TrackingMode mode = TrackingMode::kLost;
  std::optional<std::string> predicted_from;
  // How far the pose is from the prediction; set when both exist.
  std::optional<double> prediction_error;
  std::optional<double> prediction_error_deg;
  double seconds = 0;
};

template <>
struct Description<TrackingInfo> {
  static constexpr std::string_view name = "Tracking";
  static constexpr std::string_view help =
      "How a frame of a sequence got its pose: tracked (matched near the pose predicted from the "
      "frames before it), relocalized (from scratch: the first frame, or tracking failed its "
      "checks) or lost (no pose)";
  static constexpr auto fields = std::tuple(
      MakeField(&TrackingInfo::mode, Info("mode").Json("mode")),
      MakeField(&TrackingInfo::predicted_from,
                Info("predicted_from")
                    .Json("predicted_from")
                    .Help("The frame whose pose the prediction started from; none for the first "
                          "frame and after a reset")
                    .NullWhenAbsent()),
      MakeField(&TrackingInfo::prediction_error,
                Info("prediction_error")
                    .Json("prediction_error")
                    .Unit("model units")
                    .Help("Between the frame's camera centre and the predicted one; when both "
                          "exist")),
      MakeField(&TrackingInfo::prediction_error_deg,
                Info("prediction_error_deg")
                    .Json("prediction_error_deg")
                    .Unit("deg")
                    .Help("Rotation between the frame's pose and the predicted one")),
      MakeField(&TrackingInfo::seconds,
                Info("seconds")
                    .Json("time_ms")
                    .Unit("s")
                    .Help("The tracker's time on the frame after its features, relocalization "
                          "included")
                    .Scale(1e3)));
};

}  // namespace cwloc

#endif  // CWLOC_RESULTS_TRACKING_H_
