#include "delta/tracks.h"

#include "base/huge_pages.h"

namespace cwloc {

OwnedRows<uint32_t> TracksOfViews(std::span<const uint32_t> view_points,
                                  std::span<IndexPoint> points) {
  // Counting sort: views keep their order within a point.
  std::vector<uint32_t> first(points.size() + 1, 0);
  for (uint32_t point : view_points) ++first[point + 1];
  for (size_t p = 0; p < points.size(); ++p) {
    points[p].first_track = first[p];
    points[p].track_length = first[p + 1];
    first[p + 1] += first[p];
  }
  OwnedRows<uint32_t> tracks;
  ReserveOnHugePages(&tracks, view_points.size());
  tracks.resize(view_points.size());
  for (uint32_t v = 0; v < view_points.size(); ++v) tracks[first[view_points[v]]++] = v;
  return tracks;
}

}  // namespace cwloc
