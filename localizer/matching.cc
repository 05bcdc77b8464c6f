#include "localizer/matching.h"

#include <algorithm>
#include <string>

#include "base/error.h"

namespace cwloc {

uint32_t ClusterOfView(const Index& index, uint32_t view) {
  const uint32_t image = index.ImageOfView(view);
  return image == UINT32_MAX ? UINT32_MAX : index.images()[image].cluster;
}

std::vector<uint64_t> AllowedRows(const Index& index, ClusterMask allowed) {
  if (allowed.empty()) return {};
  std::vector<uint64_t> bits((index.num_rows() + 63) / 64, 0);
  for (const IndexImage& image : index.images()) {
    if (!ClusterAllowed(allowed, image.cluster)) continue;
    const uint64_t end =
        std::min<uint64_t>(uint64_t{image.first_view} + image.num_views, index.num_views());
    for (uint64_t view = image.first_view; view < end; ++view) {
      const uint64_t row = index.coded() ? index.view_points()[view] : view;  // points or views
      if (row < index.num_rows()) bits[row / 64] |= uint64_t{1} << (row % 64);
    }
  }
  return bits;
}

ClusterMembers::ClusterMembers(const Index& index) {
  uint32_t num_clusters = 0;
  for (const IndexImage& image : index.images()) {
    // Cluster ids are dense and fewer than the images; anything else is a corrupt file.
    if (image.cluster >= index.images().size()) {
      throw InputError(index.file().path().string() + ": image " + std::to_string(image.image_id) +
                       " has cluster " + std::to_string(image.cluster) + ", beyond the " +
                       std::to_string(index.images().size()) +
                       " images; the file is corrupt (run cwloc-index verify)");
    }
    num_clusters = std::max(num_clusters, image.cluster + 1);
  }
  offsets.assign(num_clusters + 1, 0);
  for (const IndexImage& image : index.images()) ++offsets[image.cluster + 1];
  for (uint32_t c = 0; c < num_clusters; ++c) offsets[c + 1] += offsets[c];
  images.resize(index.images().size());
  std::vector<uint32_t> cursor(offsets.begin(), offsets.end() - 1);
  for (uint32_t i = 0; i < index.images().size(); ++i)
    images[cursor[index.images()[i].cluster]++] = i;
}

}  // namespace cwloc
