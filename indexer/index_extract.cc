#include "indexer/index_extract.h"

#include <algorithm>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "base/bounded_file.h"
#include "base/error.h"
#include "base/parallel_for.h"
#include "base/stopwatch.h"
#include "cwloc/version.h"
#include "delta/apply_delta.h"
#include "delta/make_delta.h"
#include "format/index.h"
#include "format/xxhash64.h"
#include "geo/index_georeference.h"
#include "indexer/index_update.h"
#include "indexer/index_writer.h"
#include "indexer/model_views.h"
#include "kdtree/kd_forest_update.h"

namespace cwloc {
namespace {

// Per parent cluster, 1 when it has a camera in the region.
std::vector<char> ClustersNear(const Index& parent, const GeoRegion& near) {
  if (parent.georeference() == nullptr) {
    throw InputError(parent.file().path().string() +
                     ": --near needs a georeferenced index (cwloc-index build --georef, "
                     "--georef-images or --model-frame)");
  }
  const GeoFrame frame(GeoreferenceOfSection(*parent.georeference()));
  const EnuRegion region(frame, near);
  std::vector<char> keep(parent.images().size(), 0);
  for (const IndexImage& image : parent.images()) {
    if (region.Contains(frame.georeference().ModelToEnu(CameraCenterOf(image))))
      keep[image.cluster] = 1;
  }
  return keep;
}

// Per parent cluster, 1 when it holds an image the list names ('#' comments, blank lines).
std::vector<char> ClustersOfListedImages(const Index& parent, const std::filesystem::path& list) {
  std::unordered_map<std::string_view, uint32_t> row_of_name;
  for (uint32_t i = 0; i < parent.images().size(); ++i)
    row_of_name.emplace(parent.ImageName(parent.images()[i]), i);
  std::vector<char> keep(parent.images().size(), 0);
  const std::vector<ListedImage> listed = ReadImageNameList(list);
  for (const ListedImage& image : listed) {
    const auto found = row_of_name.find(image.name);
    if (found == row_of_name.end()) {
      throw InputError(list.string() + ":" + std::to_string(image.line) + ": image '" + image.name +
                       "' is not in " + parent.file().path().string());
    }
    keep[parent.images()[found->second].cluster] = 1;
  }
  if (listed.empty()) throw InputError(list.string() + ": no image names");
  return keep;
}

// The tile's rows but the parent's whole sections and the kd-forest, owned.
struct Tile {
  OwnedIndexRows rows;
  std::vector<uint8_t> decoded;  // a compact tile's codes decoded: its kd-forest's rows
  uint32_t num_clusters = 0;
};

// The sections kept with their rows (the table's kKeptWithRow: descriptors or codes, v_NN,
// keypoints, colours, ids): each kept view's or point's element, in order, copied a run of
// consecutive rows at a time.
void KeepRowSections(const IndexRows& parent, std::span<const uint32_t> views,
                     std::span<const uint32_t> points, OwnedIndexRows* tile) {
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    const std::span<const uint8_t> from = spec.bytes(parent);
    if (spec.child != SectionInChild::kKeptWithRow || from.empty()) continue;
    const std::span<const uint32_t> rows = spec.count == SectionCount::kPerView ? views : points;
    const size_t element_bytes = spec.ElementBytes(parent);
    const std::span<uint8_t> to = spec.resize(rows.size(), element_bytes, tile);
    for (size_t i = 0, run = 1; i < rows.size(); i += run) {
      for (run = 1; i + run < rows.size() && rows[i + run] == rows[i] + run;) ++run;
      std::memcpy(&to[i * element_bytes], &from[size_t(rows[i]) * element_bytes],
                  run * element_bytes);
    }
  }
}

Tile CutTile(const Index& parent, const std::vector<char>& keep_cluster) {
  Tile tile;
  OwnedIndexRows& rows = tile.rows;
  const auto parent_images = parent.images();
  std::vector<uint32_t> cluster_of(keep_cluster.size(), UINT32_MAX);
  for (size_t c = 0; c < keep_cluster.size(); ++c) {
    if (keep_cluster[c]) cluster_of[c] = tile.num_clusters++;
  }
  std::vector<uint32_t> camera_of(parent.cameras().size(), UINT32_MAX);
  std::vector<uint32_t> image_of(parent_images.size(), UINT32_MAX);
  std::vector<uint32_t> view_of(parent.num_views(), UINT32_MAX);
  std::vector<uint32_t> parent_views;  // the tile's views, as parent views
  for (uint32_t i = 0; i < parent_images.size(); ++i) {
    if (!keep_cluster[parent_images[i].cluster]) continue;
    IndexImage image = parent_images[i];
    if (camera_of[image.camera_index] == UINT32_MAX) {
      camera_of[image.camera_index] = static_cast<uint32_t>(rows.cameras.size());
      rows.cameras.push_back(parent.cameras()[image.camera_index]);
    }
    const std::string_view name = parent.ImageName(image);
    image.camera_index = camera_of[image.camera_index];
    image.name_offset = static_cast<uint32_t>(rows.strings.size());
    rows.strings += name;
    image.cluster = cluster_of[image.cluster];
    image.first_view = static_cast<uint32_t>(parent_views.size());
    for (uint32_t v = 0; v < image.num_views; ++v) {
      view_of[parent_images[i].first_view + v] = static_cast<uint32_t>(parent_views.size());
      parent_views.push_back(parent_images[i].first_view + v);
    }
    image_of[i] = static_cast<uint32_t>(rows.images.size());
    rows.images.push_back(image);
  }

  // Points seen by a kept view, in the parent's order, with their kept views.
  const bool coded = parent.coded();
  rows.view_points.resize(parent_views.size());
  std::vector<uint32_t> parent_points;
  for (uint32_t p = 0; p < parent.num_points(); ++p) {
    const size_t first_track = rows.tracks.size();
    const auto point = static_cast<uint32_t>(parent_points.size());
    for (const uint32_t view : parent.TrackOf(p)) {
      if (view_of[view] == UINT32_MAX) continue;
      rows.tracks.push_back(view_of[view]);
      rows.view_points[view_of[view]] = point;
    }
    if (rows.tracks.size() == first_track) continue;
    parent_points.push_back(p);
    if (coded) {
      IndexPointOffset offset = parent.point_offsets()[p];
      offset.first_track = static_cast<uint32_t>(first_track);
      rows.point_offsets.push_back(offset);
    } else {
      IndexPoint copy = parent.points()[p];
      copy.first_track = static_cast<uint32_t>(first_track);
      copy.track_length = static_cast<uint32_t>(rows.tracks.size() - first_track);
      rows.points.push_back(copy);
    }
  }
  KeepRowSections(parent.rows(), parent_views, parent_points, &rows);
  if (coded) {
    const DescriptorCodes& codes = parent.codes();
    tile.decoded = DescriptorCodes{codes.codebook, rows.codes, codes.code_bytes}.DecodeAll();
  }

  // The parent's edges between kept images: the same shared-point counts (a point both see
  // keeps both views), still sorted, since image rows keep their order.
  rows.covisibility_offsets.push_back(0);
  for (uint32_t i = 0; i < parent_images.size(); ++i) {
    if (image_of[i] == UINT32_MAX) continue;
    for (const CovisibilityEdge& edge : parent.CovisibleImages(i)) {
      if (image_of[edge.image_index] != UINT32_MAX)
        rows.covisibility_edges.push_back({image_of[edge.image_index], edge.shared_points});
    }
    rows.covisibility_offsets.push_back(static_cast<uint32_t>(rows.covisibility_edges.size()));
  }
  return tile;
}

nlohmann::ordered_json RegionJson(const IndexExtractOptions& options) {
  if (!options.near) return {{"images", options.images_file.string()}};
  nlohmann::ordered_json near = {{"latitude_deg", options.near->latitude_deg},
                                 {"longitude_deg", options.near->longitude_deg}};
  if (options.near->height_m) near["height_m"] = *options.near->height_m;
  near["radius_m"] = options.near->radius_m;
  return {{"near", near}};
}

// The parent tile's region (its manifest's `extracted`), when the extract names none.
void RegionOfParentTile(const nlohmann::ordered_json& manifest, IndexExtractOptions* options) {
  const auto& region = manifest["extracted"]["region"];
  if (region.contains("images")) {
    options->images_file = region["images"].get<std::string>();
    return;
  }
  const auto& near = region.at("near");
  GeoRegion geo;
  geo.latitude_deg = near.at("latitude_deg").get<double>();
  geo.longitude_deg = near.at("longitude_deg").get<double>();
  if (near.contains("height_m")) geo.height_m = near["height_m"].get<double>();
  geo.radius_m = near.at("radius_m").get<double>();
  options->near = geo;
}

// The new tile as the parent tile and a delta: views matched within each image by point id (and
// descriptor, and keypoint), points by id (and, compact, code). Writes both.
void WriteTileByDelta(const IndexExtractOptions& options, const Index& old_tile,
                      const OwnedIndexRows& tile, const IndexPointOrigin& origin,
                      nlohmann::ordered_json manifest, IndexExtractReport* report) {
  const std::string old_name = options.parent_tile_path.string();
  const bool coded = old_tile.coded();
  if (old_tile.point_ids().empty() || tile.point_ids.empty()) {
    throw InputError(old_name +
                     ": a tile without point ids (PIDS, since format 1.5) takes no "
                     "delta; send the tile whole");
  }
  if (coded != !tile.codes.empty() ||
      (coded && (tile.codes.size() / tile.point_ids.size() != old_tile.codes().code_bytes))) {
    throw InputError(old_name +
                     ": cut from an index that stores descriptors otherwise (full or "
                     "compact, code size); send the tile whole");
  }
  const auto old_manifest = nlohmann::ordered_json::parse(old_tile.manifest_json());
  std::unordered_map<uint32_t, uint32_t> old_row_of_id;
  for (uint32_t i = 0; i < old_tile.images().size(); ++i)
    old_row_of_id[old_tile.images()[i].image_id] = i;

  std::vector<uint32_t> parent_of_point(tile.point_ids.size(), kRemovedRow);
  const std::span<const uint64_t> old_ids = old_tile.point_ids();
  const uint32_t code_bytes = old_tile.codes().code_bytes;
  for (uint32_t p = 0, q = 0; p < old_ids.size() && q < tile.point_ids.size();) {
    if (old_ids[p] != tile.point_ids[q]) {
      old_ids[p] < tile.point_ids[q] ? ++p : ++q;
      continue;
    }
    // A compact point whose code changed is new: apply takes kept points' codes from the tile.
    if (!coded ||
        std::memcmp(old_tile.codes().Code(p), &tile.codes[size_t(q) * code_bytes], code_bytes) == 0)
      parent_of_point[q] = p;
    ++p, ++q;
  }
  const bool keypoints = !old_tile.view_keypoints().empty();
  const auto same_view = [&](uint32_t v, uint32_t w) {
    if (old_ids[old_tile.view_points()[v]] != tile.point_ids[tile.view_points[w]]) return false;
    if (keypoints && std::memcmp(&old_tile.view_keypoints()[v], &tile.view_keypoints[w],
                                 sizeof(ViewKeypoint)) != 0)
      return false;
    return coded ||
           std::memcmp(&old_tile.descriptors()[size_t(v) * kDescriptorBytes],
                       &tile.descriptors[size_t(w) * kDescriptorBytes], kDescriptorBytes) == 0;
  };
  std::vector<uint32_t> parent_of_view(tile.view_points.size(), kRemovedRow);
  size_t images_added = 0, kept_images = 0;
  for (const IndexImage& image : tile.images) {
    const auto found = old_row_of_id.find(image.image_id);
    if (found == old_row_of_id.end()) {
      ++images_added;
      continue;
    }
    ++kept_images;
    const IndexImage& old_image = old_tile.images()[found->second];
    for (uint32_t a = 0, b = 0; a < old_image.num_views && b < image.num_views; ++a) {
      uint32_t w = b;
      while (w < image.num_views && !same_view(old_image.first_view + a, image.first_view + w)) ++w;
      if (w == image.num_views) continue;
      parent_of_view[image.first_view + w] = old_image.first_view + a;
      b = w + 1;
    }
  }

  DeltaChild child{tile.Borrow(), parent_of_view, parent_of_point};
  std::vector<IndexPoint> positions;  // a compact tile's points, from its offsets
  if (coded) {
    for (const IndexPointOffset& offset : tile.point_offsets) {
      positions.push_back({{origin.xyz[0] + offset.offset[0], origin.xyz[1] + offset.offset[1],
                            origin.xyz[2] + offset.offset[2]},
                           0,
                           0});
    }
    child.rows.points = positions;
  }
  IndexDelta delta = MakeDelta(old_tile, child);

  // The tile's kd-forest: updated until past the balance bound, as an index's.
  const auto& row_map = coded ? parent_of_point : parent_of_view;
  const ChildUpdate next =
      NextUpdate(old_manifest, old_tile, row_map.size(),
                 size_t(std::count(row_map.begin(), row_map.end(), kRemovedRow)), images_added,
                 old_tile.images().size() - kept_images, &delta.header);
  report->forest_rebuilt = next.forest_rebuilt;
  const AppliedDelta applied(old_tile, delta, "the tile's delta", options.output_path,
                             ResolveThreads(options.threads));

  manifest["counts"]["kd_nodes"] = applied.num_kd_nodes();
  manifest["update"] = next.record;
  delta.manifest = manifest.dump(2) + "\n";
  delta.header.child_checksum = applied.Write(delta.manifest, std::nullopt);
  delta.header.child_file_size = std::filesystem::file_size(options.output_path);
  WriteDelta(options.delta_path, delta);
  report->delta_bytes = std::filesystem::file_size(options.delta_path);
  report->parent_tile_views = old_tile.num_views();
}

}  // namespace

IndexExtractReport ExtractIndex(const IndexExtractOptions& given) {
  const Stopwatch total;
  IndexExtractOptions options = given;
  std::optional<Index> old_tile;
  if (!options.parent_tile_path.empty()) {
    if (options.delta_path.empty())
      throw InputError("extract: --parent-tile needs --delta (the file devices apply)");
    old_tile.emplace(Index::Open(options.parent_tile_path));
    old_tile->file().VerifyChecksums();
    old_tile->Validate();
    const auto old_manifest =
        nlohmann::ordered_json::parse(old_tile->manifest_json(), nullptr, false);
    if (old_manifest.is_discarded())
      throw InputError(options.parent_tile_path.string() + ": section 'MANI' is not valid JSON");
    if (!old_manifest.contains("extracted")) {
      throw InputError(options.parent_tile_path.string() +
                       ": not a tile (cwloc-index extract); --parent-tile takes one");
    }
    if (!options.near && options.images_file.empty()) RegionOfParentTile(old_manifest, &options);
  } else if (!options.delta_path.empty()) {
    throw InputError("extract: --delta needs --parent-tile (the tile the delta changes)");
  }
  if (options.near.has_value() == !options.images_file.empty())
    throw InputError("extract: give one of --near or --images");
  std::error_code same_error;
  if (std::filesystem::equivalent(options.index_path, options.output_path, same_error)) {
    throw InputError(options.output_path.string() +
                     ": the output is the index being extracted from; write the tile elsewhere");
  }
  const Index parent = Index::Open(options.index_path);
  parent.file().VerifyChecksums();
  parent.Validate();
  auto manifest = nlohmann::ordered_json::parse(parent.manifest_json(), nullptr,
                                                /*allow_exceptions=*/false);
  if (manifest.is_discarded())
    throw InputError(options.index_path.string() + ": section 'MANI' is not valid JSON");

  const std::vector<char> keep = options.near ? ClustersNear(parent, *options.near)
                                              : ClustersOfListedImages(parent, options.images_file);
  if (std::find(keep.begin(), keep.end(), char{1}) == keep.end()) {
    const GeoRegion& r = *options.near;  // a list always keeps a cluster
    char where[160];
    std::snprintf(where, sizeof(where), "no camera lies within %.10g m of %.10g, %.10g", r.radius_m,
                  r.latitude_deg, r.longitude_deg);
    throw InputError(options.index_path.string() + ": " + where + "; nothing to extract");
  }
  const Tile tile = CutTile(parent, keep);
  const OwnedIndexRows& rows = tile.rows;

  // Built anew, unless the tile is its parent tile changed by a delta.
  KdForest forest;
  if (!old_tile) {
    const auto& parameters = manifest["build_parameters"];
    KdForestBuildOptions forest_options;
    forest_options.num_trees = parameters["kd_trees"].get<uint32_t>();
    forest_options.max_leaf_size = parameters["kd_leaf_size"].get<uint32_t>();
    forest = BuildIndexForest(parent.coded() ? std::span<const uint8_t>(tile.decoded)
                                             : std::span<const uint8_t>(rows.descriptors),
                              forest_options, parameters["seed"].get<uint64_t>(),
                              ResolveThreads(options.threads));
  }

  IndexExtractReport report;
  report.num_cameras = rows.cameras.size();
  report.num_images = rows.images.size();
  report.num_points = parent.coded() ? rows.point_offsets.size() : rows.points.size();
  report.num_views = rows.view_points.size();
  report.num_clusters = tile.num_clusters;
  report.num_covisibility_edges = rows.covisibility_edges.size();
  report.parent_images = parent.images().size();
  report.parent_views = parent.num_views();

  const nlohmann::ordered_json parent_counts = manifest["counts"];
  manifest["tool_version"] = kToolVersion;
  manifest["counts"] = {
      {"cameras", report.num_cameras},   {"images", report.num_images},
      {"points", report.num_points},     {"views", report.num_views},
      {"clusters", report.num_clusters}, {"covisibility_edges", report.num_covisibility_edges},
      {"kd_nodes", forest.nodes.size()}};
  manifest["build_parameters"]["clustering"]["num_clusters"] = tile.num_clusters;
  manifest["extracted"] = {{"from",
                            {{"path", options.index_path.string()},
                             {"file_bytes", parent.file().header().file_size},
                             {"counts", parent_counts}}},
                           {"region", RegionJson(options)}};
  manifest.erase("update");  // the index's own; a tile's record its own updates
  if (old_tile) {
    IndexPointOrigin origin = parent.point_origin();
    WriteTileByDelta(options, *old_tile, rows, origin, std::move(manifest), &report);
    report.file_bytes = std::filesystem::file_size(options.output_path);
    report.seconds_total = total.Seconds();
    return report;
  }

  IndexRows tile_rows = rows.Borrow();
  TakeParentsSections(parent.rows(), &tile_rows);
  BorrowKdForest(forest, &tile_rows);
  WriteIndex(options.output_path, tile_rows, std::move(manifest));
  report.file_bytes = std::filesystem::file_size(options.output_path);
  report.seconds_total = total.Seconds();
  return report;
}

}  // namespace cwloc
