#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/index_rows.h"

namespace cwloc {

// The TRKS section of views whose points are `view_points` (each < points.size()): view rows
// grouped by point, ascending within a point; sets each point's first_track and track_length.
// The build and every delta's apply make the tracks with it.
OwnedRows<uint32_t> TracksOfViews(std::span<const uint32_t> view_points,
                                  std::span<IndexPoint> points);

}  // namespace cwloc
