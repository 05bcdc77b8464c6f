#include "delta/covisibility.h"

#include <algorithm>

#include "base/parallel_for.h"

namespace cwloc {

CovisibilityGraph BuildCovisibilityGraph(std::span<const IndexImage> images,
                                         std::span<const IndexPoint> points,
                                         std::span<const uint32_t> tracks,
                                         std::span<const uint32_t> view_points, int num_threads,
                                         const KeptCovisibilityRows* kept) {
  // Image row of every view, from the contiguous view ranges.
  std::vector<uint32_t> image_of_view(view_points.size());
  for (uint32_t i = 0; i < images.size(); ++i) {
    std::fill_n(image_of_view.begin() + images[i].first_view, images[i].num_views, i);
  }

  // Each image counts, per other image, the points they share: a dense counter per thread
  // with a list of touched entries keeps this O(sum of track lengths over the image's views).
  std::vector<std::vector<CovisibilityEdge>> rows(images.size());
  const int threads = ResolveThreads(num_threads);
  std::vector<std::vector<uint32_t>> counters(threads, std::vector<uint32_t>(images.size(), 0));
  ParallelFor(images.size(), threads, [&](size_t i, int worker) {
    const uint32_t from = kept ? kept->kept_from[i] : KeptCovisibilityRows::kNotKept;
    if (from != KeptCovisibilityRows::kNotKept) {
      const auto parent_row =
          kept->edges.subspan(kept->offsets[from], kept->offsets[from + 1] - kept->offsets[from]);
      rows[i].reserve(parent_row.size());
      for (const CovisibilityEdge& edge : parent_row)
        rows[i].push_back({kept->child_of_parent_image[edge.image_index], edge.shared_points});
      return;
    }
    std::vector<uint32_t>& count = counters[worker];
    std::vector<uint32_t> touched;
    const IndexImage& image = images[i];
    // An image may observe a point twice (COLMAP allows it); the point counts once.
    std::vector<uint32_t> image_points(view_points.begin() + image.first_view,
                                       view_points.begin() + image.first_view + image.num_views);
    std::sort(image_points.begin(), image_points.end());
    image_points.erase(std::unique(image_points.begin(), image_points.end()), image_points.end());
    for (const uint32_t point_index : image_points) {
      const IndexPoint& point = points[point_index];
      uint32_t previous_image = UINT32_MAX;
      for (uint32_t t = point.first_track; t < point.first_track + point.track_length; ++t) {
        const uint32_t other = image_of_view[tracks[t]];
        // Track views are in image order, so a repeated image is the previous one.
        if (other == i || other == previous_image) continue;
        previous_image = other;
        if (count[other]++ == 0) touched.push_back(other);
      }
    }
    std::sort(touched.begin(), touched.end());
    rows[i].reserve(touched.size());
    for (uint32_t other : touched) {
      rows[i].push_back({other, count[other]});
      count[other] = 0;
    }
  });

  CovisibilityGraph graph;
  graph.offsets.reserve(images.size() + 1);
  graph.offsets.push_back(0);
  for (auto& row : rows) {
    graph.edges.insert(graph.edges.end(), row.begin(), row.end());
    graph.offsets.push_back(static_cast<uint32_t>(graph.edges.size()));
  }
  return graph;
}

}  // namespace cwloc
