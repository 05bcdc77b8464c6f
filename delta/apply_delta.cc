#include "delta/apply_delta.h"

#include <cstring>
#include <string>
#include <vector>

#include "base/error.h"
#include "base/huge_pages.h"
#include "base/stopwatch.h"
#include "delta/covisibility.h"
#include "delta/make_delta.h"
#include "delta/tracks.h"
#include "format/index_rows.h"
#include "format/xxhash64.h"
#include "kdtree/kd_forest_update.h"

namespace cwloc {
namespace {

std::string FileName(const Index& index) { return index.file().path().string(); }

// Child row -> parent row (kRemovedRow: a new row) and parent row -> child row of a delta's
// runs; throws when the runs are not ascending, overlap, or leave either side's range.
struct RowMaps {
  std::vector<uint32_t> child_to_parent, parent_to_child;
  size_t num_new = 0;
};

RowMaps MapRows(const std::vector<RowRun>& runs, size_t child_rows, size_t parent_rows,
                const std::string& what, const std::string& name) {
  RowMaps maps;
  maps.child_to_parent.assign(child_rows, kRemovedRow);
  maps.parent_to_child.assign(parent_rows, kRemovedRow);
  uint64_t child_end = 0, parent_end = 0;
  for (const RowRun& run : runs) {
    const uint64_t child_last = uint64_t(run.child_first) + run.count;
    const uint64_t parent_last = uint64_t(run.parent_first) + run.count;
    if (run.count == 0 || run.child_first < child_end || run.parent_first < parent_end ||
        child_last > child_rows || parent_last > parent_rows) {
      throw InputError(name + ": the delta's " + what + " runs do not fit: a run of " +
                       std::to_string(run.count) + " from parent row " +
                       std::to_string(run.parent_first) + " to child row " +
                       std::to_string(run.child_first) + " (" + std::to_string(parent_rows) +
                       " parent and " + std::to_string(child_rows) +
                       " child rows; runs ascend without overlap)");
    }
    for (uint32_t i = 0; i < run.count; ++i) {
      maps.child_to_parent[run.child_first + i] = run.parent_first + i;
      maps.parent_to_child[run.parent_first + i] = run.child_first + i;
    }
    child_end = child_last;
    parent_end = parent_last;
  }
  for (uint32_t parent : maps.child_to_parent) maps.num_new += parent == kRemovedRow;
  return maps;
}

template <typename T>
void CheckCount(const std::vector<T>& rows, size_t expected, const char* tag,
                const std::string& name) {
  if (rows.size() != expected) {
    throw InputError(name + ": the delta's section '" + tag + "' has " +
                     std::to_string(rows.size()) + " rows, expected " + std::to_string(expected));
  }
}

template <typename Change>
void CheckChangedRows(const std::vector<Change>& changes, size_t rows, const char* tag,
                      const std::string& name) {
  for (size_t i = 0; i < changes.size(); ++i) {
    if (changes[i].row >= rows || (i > 0 && changes[i].row <= changes[i - 1].row)) {
      throw InputError(name + ": the delta's section '" + tag + "' names row " +
                       std::to_string(changes[i].row) + " (of " + std::to_string(rows) +
                       "; rows ascend)");
    }
  }
}

// Child row <-> parent row of the child's views and of its points.
struct ChildRowMaps {
  RowMaps views, points;
};

// The delta names this parent, and codes points as it does.
void CheckMadeFor(const Index& parent, const IndexDelta& delta, const std::string& name) {
  const FileHeader& parent_header = parent.file().header();
  if (delta.header.parent_checksum != parent_header.header_checksum ||
      delta.header.parent_file_size != parent_header.file_size) {
    throw InputError(name + ": made for the index with checksum " +
                     HashHex(delta.header.parent_checksum) + " (" +
                     std::to_string(delta.header.parent_file_size) + " bytes), and " +
                     FileName(parent) + " has " + HashHex(parent_header.header_checksum) + " (" +
                     std::to_string(parent_header.file_size) +
                     " bytes): apply a chain's deltas in order, each to the index the one "
                     "before made");
  }
  const uint32_t code_bytes = parent.codes().code_bytes;
  if (delta.code_bytes != code_bytes) {
    throw InputError(name + ": the delta's point codes are of " + std::to_string(delta.code_bytes) +
                     " bytes, " + FileName(parent) + "'s of " + std::to_string(code_bytes) +
                     " (0: a full index, which stores descriptors)");
  }
}

void CheckImages(const IndexDelta& delta, size_t* num_views, const std::string& name) {
  uint64_t next_view = 0;
  for (size_t i = 0; i < delta.images.size(); ++i) {
    const IndexImage& image = delta.images[i];
    if (image.first_view != next_view || image.camera_index >= delta.cameras.size() ||
        uint64_t(image.name_offset) + image.name_size > delta.strings.size() ||
        image.cluster >= delta.images.size()) {
      throw InputError(name + ": the delta's image " + std::to_string(i) +
                       " does not fit (its views must follow the previous image's, its camera, "
                       "name and cluster be in range)");
    }
    next_view += image.num_views;
  }
  if (next_view >= UINT32_MAX) throw InputError(name + ": the delta's images hold too many views");
  *num_views = next_view;
}

// A full child's descriptors where they are: runs of the parent's rows and the delta's new rows
// between them.
std::vector<std::span<const uint8_t>> DescriptorPieces(const Index& parent,
                                                       const IndexDelta& delta) {
  std::vector<std::span<const uint8_t>> pieces;
  const std::span<const uint8_t> kept = parent.descriptors();
  const std::span<const uint8_t> added = delta.new_descriptors;
  size_t next_added = 0;  // bytes
  const auto add_new_rows = [&](size_t rows) {
    if (rows == 0) return;
    pieces.push_back(added.subspan(next_added, rows * kDescriptorBytes));
    next_added += rows * kDescriptorBytes;
  };
  uint64_t child_row = 0;
  for (const RowRun& run : delta.view_runs) {
    add_new_rows(run.child_first - child_row);
    const size_t offset = size_t(run.parent_first) * kDescriptorBytes;
    pieces.push_back(kept.subspan(offset, size_t(run.count) * kDescriptorBytes));
    child_row = uint64_t(run.child_first) + run.count;
  }
  add_new_rows((added.size() - next_added) / kDescriptorBytes);
  return pieces;
}

// The rows of the parent's co-visibility graph the child keeps: an image's whose views are the
// parent image's, each on a point whose track is the parent point's, view for view (every
// view in the image it had). A parent row with an edge to an image the child lacks (an
// invalid parent) is counted afresh instead.
KeptCovisibilityRows KeptGraphRows(const Index& parent, std::span<const IndexImage> images,
                                   const RowMaps& views, const RowMaps& points,
                                   std::span<const uint32_t> tracks,
                                   std::span<const IndexPoint> child_points,
                                   std::span<const uint32_t> view_points) {
  constexpr uint32_t kNotKept = KeptCovisibilityRows::kNotKept;
  const std::span<const IndexImage> parent_images = parent.images();
  KeptCovisibilityRows kept;
  // Images by id, both in id order.
  std::vector<uint32_t> parent_of_image(images.size(), kNotKept);
  std::vector<uint32_t>& child_of_parent_image = kept.child_of_parent_image;
  child_of_parent_image.assign(parent_images.size(), kNotKept);
  for (uint32_t i = 0, p = 0; i < images.size() && p < parent_images.size();) {
    if (images[i].image_id < parent_images[p].image_id) {
      ++i;
    } else if (parent_images[p].image_id < images[i].image_id) {
      ++p;
    } else {
      parent_of_image[i] = p;
      child_of_parent_image[p] = i;
      ++i, ++p;
    }
  }
  // Views that are the parent's, in the parent image of their image.
  std::vector<bool> view_kept(view_points.size(), false);
  for (uint32_t i = 0; i < images.size(); ++i) {
    if (parent_of_image[i] == kNotKept) continue;
    const IndexImage& old_image = parent_images[parent_of_image[i]];
    for (uint32_t v = images[i].first_view; v < images[i].first_view + images[i].num_views; ++v) {
      const uint32_t from = views.child_to_parent[v];
      view_kept[v] = from != kRemovedRow && from >= old_image.first_view &&
                     from - old_image.first_view < old_image.num_views;
    }
  }
  std::vector<bool> track_kept(child_points.size(), false);
  for (uint32_t q = 0; q < child_points.size(); ++q) {
    const uint32_t from = points.child_to_parent[q];
    const IndexPoint& point = child_points[q];
    if (from == kRemovedRow || parent.TrackOf(from).size() != point.track_length) continue;
    bool same = true;
    for (uint32_t t = point.first_track; same && t < point.first_track + point.track_length; ++t) {
      const uint32_t v = tracks[t];
      same = view_kept[v] && parent.view_points()[views.child_to_parent[v]] == from;
    }
    track_kept[q] = same;
  }
  kept.offsets = parent.covisibility_offsets();
  kept.edges = parent.covisibility_edges();
  kept.kept_from.assign(images.size(), kNotKept);
  for (uint32_t i = 0; i < images.size(); ++i) {
    const uint32_t from = parent_of_image[i];
    if (from == kNotKept || parent_images[from].num_views != images[i].num_views) continue;
    bool same = true;
    for (uint32_t v = images[i].first_view; same && v < images[i].first_view + images[i].num_views;
         ++v)
      same = view_kept[v] && track_kept[view_points[v]];
    if (!same || from + size_t{1} >= kept.offsets.size() ||
        kept.offsets[from] > kept.offsets[from + 1] || kept.offsets[from + 1] > kept.edges.size())
      continue;
    for (const CovisibilityEdge& edge : parent.CovisibleImages(from)) {
      same = same && edge.image_index < parent_images.size() &&
             child_of_parent_image[edge.image_index] != kNotKept;
    }
    if (same) kept.kept_from[i] = from;
  }
  return kept;
}

// The child's rows from the delta's runs and new rows, checked before any row map is allocated:
// a delta describes no more rows than the parent and its own sections hold.
ChildRowMaps MapChildRows(const Index& parent, const IndexDelta& delta, const std::string& name) {
  size_t child_views = 0;
  CheckImages(delta, &child_views, name);
  const auto rows_given = [&](const std::vector<RowRun>& runs, size_t parent_rows, size_t new_rows,
                              const char* what) {
    uint64_t kept = 0;
    for (const RowRun& run : runs) kept += run.count;
    if (kept > parent_rows) {
      throw InputError(name + ": the delta's " + what + " runs keep " + std::to_string(kept) +
                       " rows of a parent with " + std::to_string(parent_rows));
    }
    return size_t(kept + new_rows);
  };
  // A compact index stores no view descriptors: its new views are their points.
  const size_t new_views = parent.coded() ? delta.new_view_points.size()
                                          : delta.new_descriptors.size() / kDescriptorBytes;
  const size_t views_given = rows_given(delta.view_runs, parent.num_views(), new_views, "view");
  if (views_given != child_views) {
    throw InputError(name + ": the delta's runs and new views give " + std::to_string(views_given) +
                     " views, its images " + std::to_string(child_views));
  }
  const size_t child_points =
      rows_given(delta.point_runs, parent.num_points(), delta.new_points.size(), "point");
  return {MapRows(delta.view_runs, child_views, parent.num_views(), "view", name),
          MapRows(delta.point_runs, child_points, parent.num_points(), "point", name)};
}

// Each of the delta's sections of new and changed rows holds as many rows as the runs leave, of
// the rows the parent stores.
void CheckNewRows(const Index& parent, const IndexDelta& delta, const ChildRowMaps& maps,
                  const std::string& name) {
  const bool coded = parent.coded();
  const uint32_t code_bytes = parent.codes().code_bytes;
  const RowMaps& views = maps.views;
  const RowMaps& points = maps.points;
  const size_t child_views = views.child_to_parent.size();
  const size_t child_points = points.child_to_parent.size();
  CheckCount(delta.new_points, points.num_new, "NPNT", name);
  if (delta.new_descriptors.size() != (coded ? 0 : views.num_new) * kDescriptorBytes) {
    throw InputError(name + ": the delta's section 'NDSC' has " +
                     std::to_string(delta.new_descriptors.size() / kDescriptorBytes) +
                     " rows, expected " + std::to_string(coded ? 0 : views.num_new));
  }
  if (delta.new_point_codes.size() != points.num_new * code_bytes) {
    throw InputError(name + ": the delta's section 'NCOD' has " +
                     std::to_string(coded ? delta.new_point_codes.size() / code_bytes : 0) +
                     " rows, expected " + std::to_string(points.num_new));
  }
  CheckCount(delta.new_view_points, views.num_new, "NV2P", name);
  // v_NN: per view in a full index, per point in a compact one.
  CheckCount(delta.new_view_neighbors, coded ? points.num_new : views.num_new, "NVNN", name);
  const bool keypoints = !parent.view_keypoints().empty();
  if (keypoints && parent.view_keypoints().size() != parent.num_views())
    throw InputError(FileName(parent) + ": section 'VKXY' does not have one row per view");
  CheckCount(delta.new_view_keypoints, keypoints ? views.num_new : 0, "NVKP", name);
  const bool colors = !parent.point_colors().empty();
  CheckCount(delta.new_point_colors, colors ? points.num_new : 0, "NRGB", name);
  CheckCount(delta.new_point_ids, parent.point_ids().empty() ? 0 : points.num_new, "NPID", name);
  CheckChangedRows(delta.view_point_changes, child_views, "CV2P", name);
  CheckChangedRows(delta.view_neighbor_changes, coded ? child_points : child_views, "CVNN", name);
  CheckChangedRows(delta.point_moves, child_points, "CPNT", name);
  CheckChangedRows(delta.point_color_changes, colors ? child_points : 0, "CRGB", name);
  const uint32_t leaf_size = delta.header.forest_leaf_size;
  if (leaf_size == 0 || leaf_size > kMaxKdLeafSize) {
    throw InputError(name + ": the delta's kd leaf size " + std::to_string(leaf_size) +
                     " is not in 1.." + std::to_string(kMaxKdLeafSize));
  }
}

// The child's views: each new one's rows from the delta, each kept one's from the parent, its
// point renumbered or changed. A full child's descriptors are written into `composed` when given
// (a kd-forest rebuilt from them), its v_NN kept per view.
void ComposeViews(const Index& parent, const IndexDelta& delta, const ChildRowMaps& maps,
                  uint8_t* composed, OwnedIndexRows* child, const std::string& name) {
  const bool coded = parent.coded();
  const RowMaps& views = maps.views;
  const size_t child_views = views.child_to_parent.size();
  const size_t child_points = maps.points.child_to_parent.size();
  const bool keypoints = !parent.view_keypoints().empty();
  ReserveOnHugePages(&child->view_points, child_views);
  child->view_points.resize(child_views);
  if (!coded) {
    ReserveOnHugePages(&child->view_neighbor_distances, child_views);
    child->view_neighbor_distances.resize(child_views);
  }
  if (keypoints) {
    ReserveOnHugePages(&child->view_keypoints, child_views);
    child->view_keypoints.resize(child_views);
  }
  const std::span<const uint8_t> parent_descriptors = parent.descriptors();
  size_t next_new = 0;
  size_t next_change = 0;
  for (uint32_t v = 0; v < child_views; ++v) {
    const uint32_t from = views.child_to_parent[v];
    uint32_t point;
    if (from == kRemovedRow) {
      if (!coded) {
        if (composed) {
          std::memcpy(composed + size_t(v) * kDescriptorBytes,
                      &delta.new_descriptors[next_new * kDescriptorBytes], kDescriptorBytes);
        }
        child->view_neighbor_distances[v] = delta.new_view_neighbors[next_new];
      }
      point = delta.new_view_points[next_new];
      if (keypoints) child->view_keypoints[v] = delta.new_view_keypoints[next_new];
      ++next_new;
    } else {
      if (!coded) {
        if (composed) {
          std::memcpy(composed + size_t(v) * kDescriptorBytes,
                      &parent_descriptors[size_t(from) * kDescriptorBytes], kDescriptorBytes);
        }
        child->view_neighbor_distances[v] = parent.view_neighbor_distances()[from];
      }
      const uint32_t parent_point = parent.view_points()[from];
      const std::vector<uint32_t>& child_of_point = maps.points.parent_to_child;
      point = parent_point < child_of_point.size() ? child_of_point[parent_point] : kRemovedRow;
      if (keypoints) child->view_keypoints[v] = parent.view_keypoints()[from];
    }
    if (next_change < delta.view_point_changes.size() &&
        delta.view_point_changes[next_change].row == v) {
      point = delta.view_point_changes[next_change++].value;
    }
    if (point >= child_points) {
      throw InputError(name + ": the delta gives view " + std::to_string(v) +
                       " no point of the child's " + std::to_string(child_points));
    }
    child->view_points[v] = point;
  }
}

// The child's points: each new one's rows from the delta, each kept one's from the parent, then
// the delta's changes (positions, colours, v_NN) and the tracks of the views composed before. A
// compact child's v_NN is per point.
void ComposePoints(const Index& parent, const IndexDelta& delta, const ChildRowMaps& maps,
                   OwnedIndexRows* child, const std::string& name) {
  const bool coded = parent.coded();
  const std::vector<uint32_t>& parent_of_point = maps.points.child_to_parent;
  const size_t child_points = parent_of_point.size();
  const bool colors = !parent.point_colors().empty();
  const bool ids = !parent.point_ids().empty();
  ReserveOnHugePages(&child->points, child_points);
  child->points.resize(child_points);
  if (colors) child->point_colors.resize(child_points);
  if (ids) {
    ReserveOnHugePages(&child->point_ids, child_points);
    child->point_ids.resize(child_points);
  }
  if (coded) {
    ReserveOnHugePages(&child->point_neighbor_distances, child_points);
    child->point_neighbor_distances.resize(child_points);
  }
  size_t next_new = 0;
  for (uint32_t p = 0; p < child_points; ++p) {
    const uint32_t from = parent_of_point[p];
    IndexPoint point{};
    if (from == kRemovedRow) {
      std::memcpy(point.xyz, delta.new_points[next_new].xyz, sizeof(point.xyz));
      if (colors) child->point_colors[p] = delta.new_point_colors[next_new];
      if (ids) child->point_ids[p] = delta.new_point_ids[next_new];
      if (coded) child->point_neighbor_distances[p] = delta.new_view_neighbors[next_new];
      ++next_new;
    } else {
      const std::array<double, 3> xyz = parent.PointXyz(from);
      std::copy(xyz.begin(), xyz.end(), point.xyz);
      if (colors) child->point_colors[p] = parent.point_colors()[from];
      if (ids) child->point_ids[p] = parent.point_ids()[from];
      if (coded) child->point_neighbor_distances[p] = parent.point_neighbor_distances()[from];
    }
    child->points[p] = point;
  }
  auto& neighbor_distances =
      coded ? child->point_neighbor_distances : child->view_neighbor_distances;
  for (const RowChange<float>& change : delta.view_neighbor_changes)
    neighbor_distances[change.row] = change.value;
  for (const PointMove& move : delta.point_moves)
    std::memcpy(child->points[move.row].xyz, move.xyz, sizeof(move.xyz));
  for (const PointColorChange& change : delta.point_color_changes)
    child->point_colors[change.row] = change.color;
  child->tracks = TracksOfViews(child->view_points, child->points);
  for (uint32_t p = 0; p < child_points; ++p) {
    if (child->points[p].track_length == 0)
      throw InputError(name + ": the delta leaves point " + std::to_string(p) + " without views");
  }
}

// A compact child's points: offsets from the parent's origin (a kept point that did not move
// keeps its offset's bits), codes (the parent's, or the delta's for new points). Returns the
// codes decoded: the kd-forest's rows.
std::vector<uint8_t> ComposeCodes(const Index& parent, const IndexDelta& delta,
                                  std::span<const uint32_t> parent_of_point,
                                  OwnedIndexRows* child) {
  const IndexPointOrigin origin = parent.point_origin();
  const DescriptorCodes& parent_codes = parent.codes();
  std::vector<bool> moved(child->points.size(), false);
  for (const PointMove& move : delta.point_moves) moved[move.row] = true;
  child->point_offsets.resize(child->points.size());
  for (uint32_t p = 0; p < child->points.size(); ++p) {
    const uint32_t from = parent_of_point[p];
    IndexPointOffset& offset = child->point_offsets[p];
    offset.first_track = child->points[p].first_track;
    const std::array<float, 3> moved_to = OffsetFrom(origin, child->points[p]);
    std::memcpy(
        offset.offset,
        from != kRemovedRow && !moved[p] ? parent.point_offsets()[from].offset : moved_to.data(),
        sizeof(offset.offset));
  }
  child->codes = ChildCodes(parent_codes, parent_of_point, delta.new_point_codes);
  return DescriptorCodes{parent_codes.codebook, child->codes, parent_codes.code_bytes}.DecodeAll();
}

// The child's co-visibility graph: the parent's rows of images whose views and tracks it kept,
// the others counted.
CovisibilityGraph ComposeGraph(const Index& parent, const IndexDelta& delta,
                               const ChildRowMaps& maps, const OwnedIndexRows& child, int threads) {
  const KeptCovisibilityRows kept_rows = KeptGraphRows(
      parent, delta.images, maps.views, maps.points, child.tracks, child.points, child.view_points);
  return BuildCovisibilityGraph(delta.images, child.points, child.tracks, child.view_points,
                                threads, &kept_rows);
}

// The child's kd-forest over `rows` (N x 128: views, or a compact child's points decoded): built
// afresh when the delta says so, else the parent's with its rows renumbered, removed and
// inserted (a full child's kept rows read in the parent, its new ones in the delta).
KdForest ComposeForest(const Index& parent, const IndexDelta& delta, const ChildRowMaps& maps,
                       std::span<const uint8_t> rows, int threads,
                       AppliedDelta::ParentForest parent_forest) {
  const DeltaHeader& header = delta.header;
  if ((header.flags & kDeltaForestRebuilt) != 0) {
    KdForestBuildOptions options;
    options.num_trees = uint32_t(parent.kd_forest().NumTrees());
    options.max_leaf_size = header.forest_leaf_size;
    options.seed = header.forest_seed;
    options.num_threads = uint32_t(threads);
    return BuildKdForest(rows, options);
  }
  if (parent_forest == AppliedDelta::ParentForest::kUnchecked) CheckParentKdForest(parent);
  const RowMaps& row_maps = parent.coded() ? maps.points : maps.views;
  std::vector<uint32_t> inserted;
  for (uint32_t row = 0; row < row_maps.child_to_parent.size(); ++row) {
    if (row_maps.child_to_parent[row] == kRemovedRow) inserted.push_back(row);
  }
  const KdForestChange change{row_maps.parent_to_child, inserted};
  return parent.coded() ? UpdateKdForest(parent.kd_forest(), change, rows, header.forest_leaf_size,
                                         header.forest_seed, threads)
                        : UpdateKdForest(parent.kd_forest(), change, parent.descriptors(),
                                         delta.new_descriptors, header.forest_leaf_size,
                                         header.forest_seed, threads);
}

}  // namespace

struct AppliedDelta::Child {
  OwnedIndexRows rows;  // what the child composes; Rows() adds what it borrows
  // A full child's descriptors are the parent's kept rows and the delta's new ones, read where
  // they are and written as runs of each. Only a forest rebuilt from scratch needs them in one
  // array (every byte written: no zero-filling of a gigabyte first).
  std::unique_ptr<uint8_t[]> descriptor_bytes;
  std::vector<std::span<const uint8_t>> descriptor_pieces;
  std::unique_ptr<IndexFileWriter> writer;  // writing the rows while the rest is composed
  CovisibilityGraph graph;
  KdForest forest;
  std::vector<uint8_t> decoded;  // a compact child's codes decoded: the kd-forest's rows
};

void CheckParentKdForest(const Index& parent) {
  std::string error;
  if (!ValidateKdForest(parent.kd_forest(), &error))
    throw InputError(FileName(parent) + ": " + error);
}

AppliedDelta::AppliedDelta(const Index& parent, const IndexDelta& delta,
                           const std::string& delta_name, const std::filesystem::path& output,
                           int threads, ParentForest parent_forest)
    : parent_(parent), delta_(delta), child_(std::make_unique<Child>()) {
  CheckMadeFor(parent, delta, delta_name);
  const ChildRowMaps maps = MapChildRows(parent, delta, delta_name);
  CheckNewRows(parent, delta, maps, delta_name);

  Child& child = *child_;
  const bool coded = parent.coded();
  const size_t child_views = maps.views.child_to_parent.size();
  if (!coded && (delta.header.flags & kDeltaForestRebuilt) != 0) {
    child.descriptor_bytes =
        std::make_unique_for_overwrite<uint8_t[]>(child_views * kDescriptorBytes);
    AdviseHugePages(child.descriptor_bytes.get(), child_views * kDescriptorBytes);
  }
  // The rows checked, a full child's descriptors are known: on their way to the disk while the
  // rest is composed (the city's 1 % update: its write stage overlapped with the kd-forest's).
  // The other rows follow once composed, while the kd-forest and the graph are made.
  const bool background = threads > 1;
  if (!coded) child.descriptor_pieces = DescriptorPieces(parent, delta);
  child.writer = std::make_unique<IndexFileWriter>(
      output, IndexSectionsOf(Rows(), SectionBatch::kDescriptorBatch), background);
  ComposeViews(parent, delta, maps, child.descriptor_bytes.get(), &child.rows, delta_name);
  ComposePoints(parent, delta, maps, &child.rows, delta_name);
  if (coded) child.decoded = ComposeCodes(parent, delta, maps.points.child_to_parent, &child.rows);
  child.writer->WriteAhead(IndexSectionsOf(Rows(), SectionBatch::kRowBatch), background);
  child.graph = ComposeGraph(parent, delta, maps, child.rows, threads);
  // The kd-forest's rows: a compact child's points decoded, or a full one's views, in one array
  // only for a forest rebuilt (an update reads them where they are).
  std::span<const uint8_t> forest_rows = child.decoded;
  if (child.descriptor_bytes)
    forest_rows = {child.descriptor_bytes.get(), child_views * kDescriptorBytes};
  child.forest = ComposeForest(parent, delta, maps, forest_rows, threads, parent_forest);
}

AppliedDelta::~AppliedDelta() = default;

size_t AppliedDelta::num_kd_nodes() const { return child_->forest.nodes.size(); }

size_t AppliedDelta::num_covisibility_edges() const { return child_->graph.edges.size(); }

IndexRows AppliedDelta::Rows() const {
  const Child& child = *child_;
  IndexRows rows = child.rows.Borrow();
  TakeParentsSections(parent_.rows(), &rows);
  rows.cameras = delta_.cameras;
  rows.images = delta_.images;
  rows.strings = delta_.strings;
  BorrowKdForest(child.forest, &rows);
  rows.covisibility_offsets = child.graph.offsets;
  rows.covisibility_edges = child.graph.edges;
  rows.descriptor_pieces = child.descriptor_pieces;
  return rows;
}

uint64_t AppliedDelta::Write(std::string_view manifest,
                             std::optional<uint64_t> expected_checksum) const {
  IndexRows rows = Rows();
  rows.manifest = manifest;
  return child_->writer->Finish(IndexSectionsOf(rows), kIndexContainer, 0, expected_checksum);
}

ApplyDeltaReport ApplyDelta(const std::filesystem::path& index_path,
                            const std::filesystem::path& delta_path,
                            const std::filesystem::path& output, int threads) {
  const Stopwatch stopwatch;
  const IndexDelta delta = ReadDelta(delta_path);
  const Index parent = Index::Open(index_path);
  parent.file().VerifyChecksums();
  parent.file().MapAllPages();
  AppliedDelta(parent, delta, delta_path.string(), output, threads)
      .Write(delta.manifest, delta.header.child_checksum);
  ApplyDeltaReport report;
  report.parent_views = parent.num_views();
  report.child_images = delta.images.size();
  for (const IndexImage& image : delta.images) report.child_views += image.num_views;
  report.file_bytes = std::filesystem::file_size(output);
  report.seconds = stopwatch.Seconds();
  return report;
}

}  // namespace cwloc
