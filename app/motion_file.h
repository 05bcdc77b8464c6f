#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <unordered_map>
#include <variant>

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
// A motion's seven or nine numbers "QW QX QY QZ TX TY TZ [SIGMA_ROT_DEG SIGMA_POS]" (a line's
// after its name, or cwloc-serve's `motion` option): the motion (MetricMotion's checks), or
// why not, "expected '<layout>' (seven or nine numbers)" when they are not seven or nine.
std::variant<FrameMotion, std::string> ParseMotion(const std::string& numbers,
                                                   std::string_view layout);

struct MotionLine {
  FrameMotion motion;
  int line = 0;  // where it was read, for messages
};
std::unordered_map<std::string, MotionLine> ReadMotionFile(const std::filesystem::path& path);

}  // namespace cwloc
