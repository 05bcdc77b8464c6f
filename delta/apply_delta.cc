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
#include "format/index_contents.h"
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

}  // namespace

struct AppliedDelta::Child {
  // A full child's descriptors are the parent's kept rows and the delta's new ones, read where
  // they are and written as runs of each. Only a forest rebuilt from scratch needs them in one
  // array (every byte written: no zero-filling of a gigabyte first).
  std::unique_ptr<uint8_t[]> descriptor_bytes;
  std::vector<std::span<const uint8_t>> descriptor_pieces;
  IndexPointOrigin origin{};  // a compact child's, which the rows written ahead point to
  std::unique_ptr<IndexFileWriter> writer;  // writing the descriptors while the rest is composed
  std::vector<uint32_t> view_points;
  std::vector<ViewKeypoint> view_keypoints;
  std::vector<float> neighbor_distances;
  std::vector<IndexPoint> points;
  std::vector<PointColor> point_colors;
  std::vector<uint64_t> point_ids;
  std::vector<uint32_t> tracks;
  CovisibilityGraph graph;
  KdForest forest;
  // A compact child: positions as offsets from the parent's origin, codes with its codebook,
  // and the codes decoded (the kd-forest's rows).
  std::vector<IndexPointOffset> point_offsets;
  std::vector<uint8_t> codes;
  std::vector<uint8_t> decoded;
};

namespace {

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
                                   const std::vector<uint32_t>& tracks,
                                   const std::vector<IndexPoint>& child_points,
                                   const std::vector<uint32_t>& view_points) {
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

}  // namespace

void CheckParentKdForest(const Index& parent) {
  std::string error;
  if (!ValidateKdForest(parent.kd_forest(), &error))
    throw InputError(FileName(parent) + ": " + error);
}

AppliedDelta::AppliedDelta(const Index& parent, const IndexDelta& delta,
                           const std::string& delta_name, const std::filesystem::path& output,
                           int threads, ParentForest parent_forest)
    : parent_(parent), delta_(delta), child_(std::make_unique<Child>()) {
  const std::string& name = delta_name;
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
  const DeltaHeader& header = delta.header;
  const bool coded = parent.coded();
  const uint32_t code_bytes = parent.codes().code_bytes;
  if (delta.code_bytes != code_bytes) {
    throw InputError(name + ": the delta's point codes are of " + std::to_string(delta.code_bytes) +
                     " bytes, " + FileName(parent) + "'s of " + std::to_string(code_bytes) +
                     " (0: a full index, which stores descriptors)");
  }
  size_t child_views = 0;
  CheckImages(delta, &child_views, name);
  // The rows the runs and the delta's new rows give, checked before any row map is allocated:
  // a delta describes no more rows than the parent and its own sections hold.
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
  const size_t new_views =
      coded ? delta.new_view_points.size() : delta.new_descriptors.size() / kDescriptorBytes;
  const size_t views_given = rows_given(delta.view_runs, parent.num_views(), new_views, "view");
  if (views_given != child_views) {
    throw InputError(name + ": the delta's runs and new views give " + std::to_string(views_given) +
                     " views, its images " + std::to_string(child_views));
  }
  const RowMaps views = MapRows(delta.view_runs, child_views, parent.num_views(), "view", name);
  const size_t child_points =
      rows_given(delta.point_runs, parent.num_points(), delta.new_points.size(), "point");
  const RowMaps points =
      MapRows(delta.point_runs, child_points, parent.num_points(), "point", name);
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
  const size_t neighbor_rows = coded ? child_points : child_views;
  CheckCount(delta.new_view_neighbors, coded ? points.num_new : views.num_new, "NVNN", name);
  const bool keypoints = !parent.view_keypoints().empty();
  if (keypoints && parent.view_keypoints().size() != parent.num_views())
    throw InputError(FileName(parent) + ": section 'VKXY' does not have one row per view");
  CheckCount(delta.new_view_keypoints, keypoints ? views.num_new : 0, "NVKP", name);
  const bool colors = !parent.point_colors().empty();
  CheckCount(delta.new_point_colors, colors ? points.num_new : 0, "NRGB", name);
  const bool ids = !parent.point_ids().empty();
  CheckCount(delta.new_point_ids, ids ? points.num_new : 0, "NPID", name);
  CheckChangedRows(delta.view_point_changes, child_views, "CV2P", name);
  CheckChangedRows(delta.view_neighbor_changes, neighbor_rows, "CVNN", name);
  CheckChangedRows(delta.point_moves, child_points, "CPNT", name);
  CheckChangedRows(delta.point_color_changes, colors ? child_points : 0, "CRGB", name);
  if (header.forest_leaf_size == 0 || header.forest_leaf_size > kMaxKdLeafSize) {
    throw InputError(name + ": the delta's kd leaf size " +
                     std::to_string(header.forest_leaf_size) + " is not in 1.." +
                     std::to_string(kMaxKdLeafSize));
  }

  Child& child = *child_;
  const bool forest_rebuilt = (header.flags & kDeltaForestRebuilt) != 0;
  uint8_t* composed = nullptr;
  if (!coded && forest_rebuilt) {
    child.descriptor_bytes =
        std::make_unique_for_overwrite<uint8_t[]>(child_views * kDescriptorBytes);
    composed = child.descriptor_bytes.get();
    AdviseHugePages(composed, child_views * kDescriptorBytes);
  }
  ReserveOnHugePages(&child.view_points, child_views);
  child.view_points.resize(child_views);
  // The rows checked, a full child's descriptors are known: on their way to the disk while the
  // rest is composed (the city's 1 % update: its write stage overlapped with the kd-forest's).
  // The other rows follow once composed, while the kd-forest and the graph are made.
  const bool background = threads > 1;
  std::vector<SectionData> leading;
  if (!coded) {
    child.descriptor_pieces = DescriptorPieces(parent, delta);
    leading.push_back(DescriptorSection(Contents(&child.origin)));
  }
  child.writer = std::make_unique<IndexFileWriter>(output, std::move(leading), background);
  ReserveOnHugePages(&child.neighbor_distances, neighbor_rows);
  child.neighbor_distances.resize(neighbor_rows);
  if (keypoints) {
    ReserveOnHugePages(&child.view_keypoints, child_views);
    child.view_keypoints.resize(child_views);
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
        child.neighbor_distances[v] = delta.new_view_neighbors[next_new];
      }
      point = delta.new_view_points[next_new];
      if (keypoints) child.view_keypoints[v] = delta.new_view_keypoints[next_new];
      ++next_new;
    } else {
      if (!coded) {
        if (composed) {
          std::memcpy(composed + size_t(v) * kDescriptorBytes,
                      &parent_descriptors[size_t(from) * kDescriptorBytes], kDescriptorBytes);
        }
        child.neighbor_distances[v] = parent.view_neighbor_distances()[from];
      }
      const uint32_t parent_point = parent.view_points()[from];
      point = parent_point < points.parent_to_child.size() ? points.parent_to_child[parent_point]
                                                           : kRemovedRow;
      if (keypoints) child.view_keypoints[v] = parent.view_keypoints()[from];
    }
    if (next_change < delta.view_point_changes.size() &&
        delta.view_point_changes[next_change].row == v) {
      point = delta.view_point_changes[next_change++].value;
    }
    if (point >= child_points) {
      throw InputError(name + ": the delta gives view " + std::to_string(v) +
                       " no point of the child's " + std::to_string(child_points));
    }
    child.view_points[v] = point;
  }

  ReserveOnHugePages(&child.points, child_points);
  child.points.resize(child_points);
  if (colors) child.point_colors.resize(child_points);
  if (ids) {
    ReserveOnHugePages(&child.point_ids, child_points);
    child.point_ids.resize(child_points);
  }
  next_new = 0;
  for (uint32_t p = 0; p < child_points; ++p) {
    const uint32_t from = points.child_to_parent[p];
    IndexPoint point{};
    if (from == kRemovedRow) {
      std::memcpy(point.xyz, delta.new_points[next_new].xyz, sizeof(point.xyz));
      if (colors) child.point_colors[p] = delta.new_point_colors[next_new];
      if (ids) child.point_ids[p] = delta.new_point_ids[next_new];
      if (coded) child.neighbor_distances[p] = delta.new_view_neighbors[next_new];
      ++next_new;
    } else {
      const std::array<double, 3> xyz = parent.PointXyz(from);
      std::copy(xyz.begin(), xyz.end(), point.xyz);
      if (colors) child.point_colors[p] = parent.point_colors()[from];
      if (ids) child.point_ids[p] = parent.point_ids()[from];
      if (coded) child.neighbor_distances[p] = parent.point_neighbor_distances()[from];
    }
    child.points[p] = point;
  }
  for (const RowChange<float>& change : delta.view_neighbor_changes)
    child.neighbor_distances[change.row] = change.value;
  for (const PointMove& move : delta.point_moves)
    std::memcpy(child.points[move.row].xyz, move.xyz, sizeof(move.xyz));
  for (const PointColorChange& change : delta.point_color_changes)
    child.point_colors[change.row] = change.color;
  child.tracks = TracksOfViews(child.view_points, child.points);
  for (uint32_t p = 0; p < child_points; ++p) {
    if (child.points[p].track_length == 0)
      throw InputError(name + ": the delta leaves point " + std::to_string(p) + " without views");
  }

  if (coded) ComposeCodes(parent, delta, points.child_to_parent);
  child.writer->WriteAhead(RowSections(Contents(&child.origin)), background);

  const std::vector<IndexImage> images = delta.images;
  const KeptCovisibilityRows kept_rows =
      KeptGraphRows(parent, images, views, points, child.tracks, child.points, child.view_points);
  child.graph = BuildCovisibilityGraph(images, child.points, child.tracks, child.view_points,
                                       threads, &kept_rows);
  // The kd-forest's rows: views, or a compact index's points decoded.
  const RowMaps& rows = coded ? points : views;
  if (forest_rebuilt) {
    KdForestBuildOptions options;
    options.num_trees = uint32_t(parent.kd_forest().NumTrees());
    options.max_leaf_size = header.forest_leaf_size;
    options.seed = header.forest_seed;
    options.num_threads = uint32_t(threads);
    child.forest =
        BuildKdForest(coded ? std::span<const uint8_t>(child.decoded)
                            : std::span<const uint8_t>(composed, child_views * kDescriptorBytes),
                      options);
  } else {
    if (parent_forest == ParentForest::kUnchecked) CheckParentKdForest(parent);
    std::vector<uint32_t> inserted;
    for (uint32_t row = 0; row < rows.child_to_parent.size(); ++row) {
      if (rows.child_to_parent[row] == kRemovedRow) inserted.push_back(row);
    }
    const KdForestChange change{rows.parent_to_child, inserted};
    // A full child's kept rows are read in the parent, its new ones in the delta.
    child.forest = coded ? UpdateKdForest(parent.kd_forest(), change, child.decoded,
                                          header.forest_leaf_size, header.forest_seed, threads)
                         : UpdateKdForest(parent.kd_forest(), change, parent.descriptors(),
                                          delta.new_descriptors, header.forest_leaf_size,
                                          header.forest_seed, threads);
  }
}

// A compact child's points: offsets from the parent's origin (a kept point that did not move
// keeps its offset's bits), codes (the parent's, or the delta's for new points), decoded.
void AppliedDelta::ComposeCodes(const Index& parent, const IndexDelta& delta,
                                const std::vector<uint32_t>& parent_of_point) {
  Child& child = *child_;
  const IndexPointOrigin origin = parent.point_origin();
  const DescriptorCodes& parent_codes = parent.codes();
  std::vector<bool> moved(child.points.size(), false);
  for (const PointMove& move : delta.point_moves) moved[move.row] = true;
  child.point_offsets.resize(child.points.size());
  for (uint32_t p = 0; p < child.points.size(); ++p) {
    const uint32_t from = parent_of_point[p];
    IndexPointOffset& offset = child.point_offsets[p];
    offset.first_track = child.points[p].first_track;
    const std::array<float, 3> moved_to = OffsetFrom(origin, child.points[p]);
    std::memcpy(
        offset.offset,
        from != kRemovedRow && !moved[p] ? parent.point_offsets()[from].offset : moved_to.data(),
        sizeof(offset.offset));
  }
  child.codes = ChildCodes(parent_codes, parent_of_point, delta.new_point_codes);
  child.decoded =
      DescriptorCodes{parent_codes.codebook, child.codes, parent_codes.code_bytes}.DecodeAll();
}

AppliedDelta::~AppliedDelta() = default;

size_t AppliedDelta::num_kd_nodes() const { return child_->forest.nodes.size(); }

size_t AppliedDelta::num_covisibility_edges() const { return child_->graph.edges.size(); }

IndexContents AppliedDelta::Contents(IndexPointOrigin* origin) const {
  const Child& child = *child_;
  IndexContents contents;
  contents.cameras = delta_.cameras;
  contents.images = delta_.images;
  contents.strings = delta_.strings;
  if (parent_.coded()) {
    KeepParentCoding(parent_, origin, &contents);
    contents.point_offsets = child.point_offsets;
    contents.codes = child.codes;
  } else {
    contents.points = child.points;
  }
  contents.tracks = child.tracks;
  contents.view_points = child.view_points;
  contents.neighbor_distances = child.neighbor_distances;
  contents.forest = &child.forest;
  contents.covisibility_offsets = child.graph.offsets;
  contents.covisibility_edges = child.graph.edges;
  contents.view_keypoints = child.view_keypoints;
  contents.point_colors = child.point_colors;
  contents.point_ids = child.point_ids;
  contents.georeference = parent_.georeference();
  contents.covariance_calibration = parent_.covariance_calibration();
  contents.descriptor_pieces = child.descriptor_pieces;
  return contents;
}

uint64_t AppliedDelta::Write(std::string_view manifest,
                             std::optional<uint64_t> expected_checksum) const {
  const Child& child = *child_;
  IndexPointOrigin origin{};
  const IndexContents contents = Contents(&origin);
  const std::vector<SectionData> sections = IndexSectionsOf(contents, manifest);
  return child.writer->Finish(sections, kIndexContainer, 0, expected_checksum);
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
