#pragma once

#include <array>
#include <string>
#include <string_view>

#include "results/localization_result.h"

namespace cwloc {

// The trajectory files cwloc-localize --trajectory writes, one line per frame with a pose:
//   tum      "TIMESTAMP TX TY TZ QX QY QZ QW", world_from_camera (evo, rpg_trajectory_evaluation)
//   kapture  "TIMESTAMP, DEVICE_ID, QW, QX, QY, QZ, TX, TY, TZ", camera_from_world, as kapture's
//            trajectories.txt holds a device's pose
//   lamar    the same columns and then the pose's 6 x 6 covariance, row-major ("*covar"),
//            world_from_camera, as LaMAR's Capture format (scantools) holds them: the format
//            that inverts kapture's convention and perturbs the pose on the right
enum class TrajectoryFormat { kTum, kKapture, kLamar };
inline constexpr std::array<std::string_view, 3> kTrajectoryFormatNames = {"tum", "kapture",
                                                                           "lamar"};

// The format of that name; throws InputError naming --trajectory-format and the names.
TrajectoryFormat TrajectoryFormatNamed(std::string_view name);

// The device column of the kapture and LaMAR files: one camera.
inline constexpr std::string_view kTrajectoryDeviceId = "camera";

// When a frame was seen: seconds into a video, or its place in the sequence (0, 1, ...). TUM
// writes it as it is; kapture and LaMAR write integers: microseconds, or the place.
struct FrameStamp {
  double value = 0.0;
  bool seconds = false;
};

// The comment lines a file of the format starts with (none for TUM).
std::string TrajectoryHeader(TrajectoryFormat format);

// A localized frame's line, without the newline.
std::string TrajectoryLine(const LocalizationResult& result, FrameStamp stamp,
                           TrajectoryFormat format);

}  // namespace cwloc
