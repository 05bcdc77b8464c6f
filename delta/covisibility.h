#pragma once

#include <cstdint>
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

// `image_of_view[v]` is the image row of view v; tracks are CSR over points.
CovisibilityGraph BuildCovisibilityGraph(const std::vector<IndexImage>& images,
                                         const std::vector<IndexPoint>& points,
                                         const std::vector<uint32_t>& tracks,
                                         const std::vector<uint32_t>& view_points, int num_threads);

}  // namespace cwloc
