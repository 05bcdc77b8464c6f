#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "base/huge_pages.h"
#include "colmap/database.h"
#include "colmap/reconstruction.h"
#include "format/index_sections.h"

namespace cwloc {

// Everything the index stores about the model, gathered from a COLMAP model and its database:
// only views that belong to a 3D point, grouped by image (images in id order), so that one
// image's views are contiguous.
struct ModelViews {
  std::vector<IndexCamera> cameras;
  std::vector<IndexImage> images;        // cluster left 0; filled by the clustering step
  std::string strings;                   // image names
  std::vector<IndexPoint> points;        // 3D points with at least one view, in id order
  std::vector<point3D_t> point_ids;      // COLMAP id of each point
  std::vector<PointColor> point_colors;  // each point's colour in the model
  std::vector<uint32_t> tracks;          // view indices, grouped by point
  // views x 128; rows GatherModelViews leaves unwritten are the caller's to fill or not read.
  std::vector<uint8_t, UnwrittenAllocator<uint8_t>> descriptors;
  std::vector<uint32_t> view_points;  // point index of each view
  std::vector<ViewKeypoint> view_keypoints;

  size_t num_views() const { return view_points.size(); }
  std::string_view ImageName(const IndexImage& image) const {
    return std::string_view(strings).substr(image.name_offset, image.name_size);
  }
};

// Reads each model image's descriptors from the database. Images of the database that are not
// in the model are ignored (they may be queries). Throws InputError when a model image is
// missing from the database, has another name there, or its descriptor count differs from its
// number of 2D points.
//
// `known_rows`, when given, spares reading descriptors the caller already has (`cwloc-index
// update`: an old image's, in the index): it returns true when it has the image's view rows
// (one 128-byte row per observation, in point2D order) for observations of the points
// `point_ids` in this order. Those rows are left unwritten (never touched, so a city's 1.4 GB
// of them costs nothing), and the database only confirms the image's descriptor count.
using KnownViewRows = std::function<bool(image_t image_id, std::span<const point3D_t> point_ids)>;
ModelViews GatherModelViews(const colmap::Reconstruction& model,
                            const colmap::DatabaseReader& database,
                            const KnownViewRows& known_rows = {});

// The views of the model without the images whose rows `left_out` marks, as `colmap
// image_deleter` takes images out of a model: their views go, and so does every 3D point left
// with fewer than two views (with its last view). Cameras stay, and the kept images' names;
// the images keep their clusters, renumbered densely in their order.
ModelViews WithoutImages(const ModelViews& views, const std::vector<bool>& left_out);

// An image name list (`cwloc-index extract --images`, `update --remove-images`): one name per
// line, surrounding blanks trimmed, blank lines and '#' comments skipped.
struct ListedImage {
  int line;  // 1-based, for messages
  std::string name;
};
std::vector<ListedImage> ReadImageNameList(const std::filesystem::path& path);

}  // namespace cwloc
