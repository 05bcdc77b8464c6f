#pragma once

#include <filesystem>
#include <string>
#include <unordered_map>

#include "localizer/tracker.h"

namespace cwloc {

// cwloc-localize --motion: per frame, its camera's motion since the previous frame of the
// sequence (visual-inertial odometry), one line each: 'NAME QW QX QY QZ TX TY TZ
// [SIGMA_ROT_DEG SIGMA_POS]', the frame's camera from the previous frame's camera (COLMAP's
// convention), the translation in metres, and optionally its uncertainty (FrameMotion: one
// standard deviation per axis, degrees and metres; 0 for one the device does not know). '#'
// starts a comment line. Throws InputError naming the file and the line for a line that is not
// a name and seven or nine finite numbers, a negative sigma, a quaternion far from unit length,
// or a frame given twice.
struct MotionLine {
  FrameMotion motion;
  int line = 0;  // where it was read, for messages
};
std::unordered_map<std::string, MotionLine> ReadMotionFile(const std::filesystem::path& path);

}  // namespace cwloc
