#pragma once

#include <numbers>

namespace cwloc {

// One degree in radians: `30 * kDegree`.
inline constexpr double kDegree = std::numbers::pi / 180;

}  // namespace cwloc
