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
#include "format/index_rows.h"

namespace cwloc {

// Everything the index stores about the model, gathered from a COLMAP model and its database:
// only views that belong to a 3D point, grouped by image (images in id order), so that one
// image's views are contiguous. The gather fills cameras, images (cluster left 0, for the
// clustering step), strings, points (those with a view, in id order), point_ids, point_colors,
// tracks, descriptors (views x 128; rows GatherModelViews leaves unwritten are the caller's to fill
// or not read), view_points and view_keypoints: more than an index of any kind stores (a compact
// one has codes instead of descriptors, keypoints and colours are optional); the build's later
// stages compute the rest.
struct ModelViews : OwnedIndexRows {
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
