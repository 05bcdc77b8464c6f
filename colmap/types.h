#pragma once

#include <cstdint>
#include <limits>

namespace cwloc {

// Identifier types follow COLMAP (util/types.h) so values read from its files keep their width.
using camera_t = uint32_t;
using image_t = uint32_t;
using point2D_t = uint32_t;
using point3D_t = uint64_t;
using rig_t = uint32_t;
using frame_t = uint32_t;

inline constexpr point3D_t kInvalidPoint3DId = std::numeric_limits<point3D_t>::max();

}  // namespace cwloc
