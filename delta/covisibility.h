#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "format/index_sections.h"

namespace cwloc {

// The co-visibility graph in CSR form: image i's neighbours are
// edges[offsets[i] .. offsets[i+1]), sorted by image index, each with the number of 3D points
// both images see.
struct CovisibilityGraph {
  std::vector<uint32_t> offsets;
  std::vector<CovisibilityEdge> edges;
};

// Rows a child's graph takes from its parent's (`cwloc-index update` and `apply`): image i keeps
// parent image kept_from[i]'s row, its neighbours renumbered by child_of_parent_image, when its
// views and every track through them are the parent's; kNotKept: counted afresh. The caller
// checks that each kept row's neighbours are kept images (of which a row of a valid parent is).
struct KeptCovisibilityRows {
  static constexpr uint32_t kNotKept = UINT32_MAX;
  std::span<const uint32_t> offsets;
  std::span<const CovisibilityEdge> edges;
  std::vector<uint32_t> kept_from;
  std::vector<uint32_t> child_of_parent_image;
};

// Tracks are CSR over points; images' views are contiguous rows of `view_points`. With `kept`,
// the rows it keeps are copied, the same rows a count would give (a city's 1 % update: 0.6 s
// less).
CovisibilityGraph BuildCovisibilityGraph(std::span<const IndexImage> images,
                                         std::span<const IndexPoint> points,
                                         std::span<const uint32_t> tracks,
                                         std::span<const uint32_t> view_points, int num_threads,
                                         const KeptCovisibilityRows* kept = nullptr);

}  // namespace cwloc
