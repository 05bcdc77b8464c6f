#pragma once

#include <cstdint>
#include <filesystem>
#include <optional>

#include "geo/geo_region.h"

namespace cwloc {

// `cwloc-index extract`: a self-contained tile of an index for a device that knows roughly
// where it is. The tile keeps every cluster with a camera in the region (or holding a listed
// image), whole, and of them everything the parent stores: cameras, images, their views and
// descriptors or codes, the points they see (tracks cut to the kept views), each view's or
// point's v_NN as the parent measured it, the co-visibility edges between kept images, the
// codebook and the georeference. Only the kd-forest is built anew, over the kept rows with the
// parent's parameters. So a query localizes in the tile as in the parent searched with the
// same region as its position prior (docs/algorithm.md, "Tiles").
struct IndexExtractOptions {
  std::filesystem::path index_path;
  std::filesystem::path output_path;
  std::optional<GeoRegion> near;      // --near: clusters with a camera in this region
  std::filesystem::path images_file;  // --images: clusters holding these images (one per line)
  int threads = 0;                    // kd-forest build; 0 = all cores
  // --parent-tile: a tile of the index this one was updated from. The tile is then written as
  // that tile changed by a delta (`delta_path`, for devices that hold it: `cwloc-index apply`),
  // its kd-forest updated as `update` updates an index's; without a region, the parent tile's.
  std::filesystem::path parent_tile_path;
  std::filesystem::path delta_path;
};

struct IndexExtractReport {
  size_t num_cameras = 0, num_images = 0, num_points = 0, num_views = 0;
  size_t num_clusters = 0, num_covisibility_edges = 0;
  size_t parent_images = 0, parent_views = 0;
  uint64_t file_bytes = 0;
  uint64_t delta_bytes = 0;  // with a parent tile
  size_t parent_tile_views = 0;
  bool forest_rebuilt = false;  // with a parent tile: the balance bound was passed
  double seconds_total = 0;
};

// Verifies the parent (checksums and every stored index), selects, writes the tile atomically.
// Throws InputError on a bad parent, region or list, or when nothing is selected.
IndexExtractReport ExtractIndex(const IndexExtractOptions& options);

}  // namespace cwloc
