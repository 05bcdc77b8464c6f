#include "format/index.h"

#include <algorithm>
#include <cmath>

#include "camera/camera_models.h"

namespace cwloc {
namespace {

// Checked at open (one element): the localizer converts positions through it on every query.
void ValidateGeoreference(const IndexGeoreference& g, const std::string& name) {
  auto fail = [&](const std::string& what) {
    throw InputError(name + ": section 'GEOR': " + what);
  };
  const double values[] = {
      g.origin_latitude_deg, g.origin_longitude_deg, g.origin_height_m, g.scale,
      g.rotation[0],         g.rotation[1],          g.rotation[2],     g.rotation[3],
      g.translation[0],      g.translation[1],       g.translation[2],  g.rms_residual_m};
  for (const double value : values) {
    if (!std::isfinite(value)) fail("a value is not finite");
  }
  if (std::abs(g.origin_latitude_deg) > 90 || g.origin_longitude_deg < -180 ||
      g.origin_longitude_deg >= 360)
    fail("origin latitude/longitude out of range");
  if (!(g.scale > 0)) fail("scale " + std::to_string(g.scale) + " is not positive");
  const double norm = std::sqrt(g.rotation[0] * g.rotation[0] + g.rotation[1] * g.rotation[1] +
                                g.rotation[2] * g.rotation[2] + g.rotation[3] * g.rotation[3]);
  if (std::abs(norm - 1) > 1e-6) fail("rotation is not a unit quaternion");
  if (g.source < static_cast<uint32_t>(GeoreferenceSource::kFile) ||
      g.source > static_cast<uint32_t>(GeoreferenceSource::kEnuModel))
    fail("unknown source " + std::to_string(g.source));
}

// Checked at open (one element): the localizer scales every covariance by it.
void ValidateCovarianceCalibration(const IndexCovarianceCalibration& c, const std::string& name) {
  for (int mode = 0; mode < 3; ++mode) {
    for (const float scale : {c.rotation_scale[mode], c.position_scale[mode]}) {
      if (!(std::isfinite(scale) && scale >= 0)) {
        throw InputError(name + ": section 'PCAL': scale " + std::to_string(scale) +
                         " is not a finite number >= 0");
      }
    }
    if (c.localized[mode] > c.sampled) {
      throw InputError(name + ": section 'PCAL': " + std::to_string(c.localized[mode]) +
                       " samples localized of " + std::to_string(c.sampled));
    }
  }
}

// Every section of the table that an index of its kind holds (a compact one has PCOD), borrowed
// in place; one the kind needs and the file lacks is refused, as is an element of another size.
IndexRows BorrowSections(const IndexFile& file) {
  const bool compact = file.FindSection(section::kPointCodes) != nullptr;
  IndexRows rows;
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    if (!spec.InIndexOfKind(compact)) continue;
    const SectionEntry* entry = file.FindSection(spec.tag);
    if (entry == nullptr && spec.optional()) continue;
    uint32_t element_bytes = spec.element_bytes;
    if (element_bytes == 0 && entry != nullptr) {  // PCOD: its code size is the element's
      if (!IsValidCodeBytes(entry->element_size)) {
        throw InputError(file.path().string() + ": section '" + SectionTagName(spec.tag) +
                         "' holds " + std::to_string(entry->element_size) +
                         "-byte codes; expected a divisor of 128 from 4 to 64");
      }
      element_bytes = rows.code_bytes = entry->element_size;
    }
    spec.borrow(file.SectionBytes(spec.tag, element_bytes), &rows);  // refuses a missing one
  }
  return rows;
}

// Each section's element count as the table says: one, or one per view or point.
void CheckCounts(const IndexFile& file, const IndexRows& rows, size_t points) {
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    const SectionEntry* entry = file.FindSection(spec.tag);
    if (entry == nullptr || !spec.InIndexOfKind(rows.compact())) continue;
    const std::string what = file.path().string() + ": section '" + SectionTagName(spec.tag) +
                             "' has " + std::to_string(entry->count) + " elements, expected ";
    const auto require_one_per = [&](size_t expected, const char* row) {
      if (entry->count != expected)
        throw InputError(what + "one per " + row + " (" + std::to_string(expected) + ")");
    };
    if (spec.count == SectionCount::kOne && entry->count != 1) throw InputError(what + "1");
    if (spec.count == SectionCount::kPerView) require_one_per(rows.num_views(), "view");
    if (spec.count == SectionCount::kPerPoint) require_one_per(points, "point");
  }
}

}  // namespace

Index Index::Open(const std::filesystem::path& path) {
  Index index(IndexFile::Open(path));
  const IndexFile& file = index.file_;
  const std::string name = path.string();
  const IndexRows& rows = index.rows_ = BorrowSections(file);
  const size_t views = rows.num_views();
  index.num_points_ = rows.compact() ? rows.point_offsets.size() : rows.points.size();
  CheckCounts(file, rows, index.num_points_);
  if (rows.compact()) {
    for (const double value : rows.point_origin[0].xyz) {
      if (!std::isfinite(value)) throw InputError(name + ": section 'PORG': a value is not finite");
    }
    if (rows.codebook.size() != DescriptorCodes::kCodebookBytes) {
      throw InputError(name + ": section 'PQCB' has " + std::to_string(rows.codebook.size()) +
                       " bytes, expected " + std::to_string(DescriptorCodes::kCodebookBytes));
    }
    index.codes_ = {rows.codebook, rows.codes, rows.code_bytes};
  }
  if (index.georeference() != nullptr) ValidateGeoreference(*index.georeference(), name);
  if (index.covariance_calibration() != nullptr)
    ValidateCovarianceCalibration(*index.covariance_calibration(), name);
  index.kd_forest_ = {rows.kd_nodes, rows.kd_roots, rows.kd_leaves, rows.descriptors, index.codes_};
  if (rows.covisibility_offsets.size() != rows.images.size() + 1) {
    throw InputError(name + ": section 'CVOF' has " +
                     std::to_string(rows.covisibility_offsets.size()) +
                     " elements, expected one per image plus one (" +
                     std::to_string(rows.images.size() + 1) + ")");
  }
  if (index.kd_forest_.roots.empty() ||
      index.kd_forest_.leaves.size() != index.kd_forest_.roots.size() * index.num_rows()) {
    throw InputError(name + ": sections 'KDRT'/'KDLF' hold " +
                     std::to_string(index.kd_forest_.roots.size()) + " trees and " +
                     std::to_string(index.kd_forest_.leaves.size()) +
                     " leaf slots, expected at least one tree and one slot per " +
                     (index.coded() ? "point" : "view") + " per tree");
  }
  if (views > UINT32_MAX || index.num_points_ > UINT32_MAX || rows.images.size() > UINT32_MAX) {
    throw InputError(name + ": more than 2^32 views, points or images");
  }
  return index;
}

std::string_view Index::ImageName(const IndexImage& image) const {
  if (image.name_offset > rows_.strings.size() ||
      image.name_size > rows_.strings.size() - image.name_offset)
    return {};
  return {rows_.strings.data() + image.name_offset, image.name_size};
}

uint32_t Index::ImageOfView(uint32_t view) const {
  const auto it =
      std::upper_bound(rows_.images.begin(), rows_.images.end(), view,
                       [](uint32_t v, const IndexImage& image) { return v < image.first_view; });
  if (it == rows_.images.begin()) return UINT32_MAX;
  const IndexImage& image = *(it - 1);
  if (view - image.first_view >= image.num_views) return UINT32_MAX;
  return static_cast<uint32_t>(it - 1 - rows_.images.begin());
}

uint32_t Index::PointOfRow(uint32_t row) const {
  if (coded()) return row < num_points_ ? row : UINT32_MAX;
  return row < rows_.view_points.size() ? rows_.view_points[row] : UINT32_MAX;
}

float Index::RowNeighborDistance(uint32_t row) const {
  const std::span<const float> distances =
      coded() ? rows_.point_neighbor_distances : rows_.view_neighbor_distances;
  return row < distances.size() ? distances[row] : 0.0f;
}

const uint8_t* Index::RowDescriptor(uint32_t row, uint8_t* scratch) const {
  if (!coded()) return rows_.descriptors.data() + size_t{row} * kDescriptorBytes;
  codes_.Decode(row, scratch);
  return scratch;
}

const uint8_t* Index::ViewDescriptor(uint32_t view, uint8_t* scratch) const {
  if (!coded()) return rows_.descriptors.data() + size_t{view} * kDescriptorBytes;
  const uint32_t point = view < rows_.view_points.size() ? rows_.view_points[view] : UINT32_MAX;
  if (point >= num_points_) {  // a corrupt view; verify names it
    std::fill_n(scratch, kDescriptorBytes, uint8_t{0});
    return scratch;
  }
  return RowDescriptor(point, scratch);  // a coded index's rows are its points
}

std::span<const uint32_t> Index::TrackOf(uint32_t point_index) const {
  if (point_index >= num_points_) return {};
  const auto [first, length] = StoredTrack(point_index);
  if (first > rows_.tracks.size() || length > rows_.tracks.size() - first) return {};
  return rows_.tracks.subspan(first, length);
}

std::pair<uint64_t, uint64_t> Index::StoredTrack(uint32_t p) const {
  if (rows_.point_offsets.empty())
    return {rows_.points[p].first_track, rows_.points[p].track_length};
  const uint64_t first = rows_.point_offsets[p].first_track;
  const uint64_t end = p + size_t{1} < rows_.point_offsets.size()
                           ? rows_.point_offsets[p + 1].first_track
                           : rows_.tracks.size();
  return {first, end >= first ? end - first : 0};  // a decreasing start: empty, verify names it
}

std::array<double, 3> Index::PointXyz(uint32_t p) const {
  if (rows_.point_offsets.empty())
    return {rows_.points[p].xyz[0], rows_.points[p].xyz[1], rows_.points[p].xyz[2]};
  const IndexPointOffset& point = rows_.point_offsets[p];
  return {rows_.point_origin[0].xyz[0] + point.offset[0],
          rows_.point_origin[0].xyz[1] + point.offset[1],
          rows_.point_origin[0].xyz[2] + point.offset[2]};
}

std::span<const CovisibilityEdge> Index::CovisibleImages(uint32_t image_index) const {
  if (image_index + size_t{1} >= rows_.covisibility_offsets.size()) return {};
  const uint32_t begin = rows_.covisibility_offsets[image_index];
  const uint32_t end = rows_.covisibility_offsets[image_index + 1];
  if (begin > end || end > rows_.covisibility_edges.size()) return {};
  return rows_.covisibility_edges.subspan(begin, end - begin);
}

void Index::Validate() const {
  const std::string name = file_.path().string();
  auto fail = [&](const std::string& what) { throw InputError(name + ": " + what); };
  const size_t views = num_views();

  for (size_t p = 1; p < rows_.point_ids.size(); ++p) {
    if (rows_.point_ids[p] <= rows_.point_ids[p - 1])
      fail("PIDS[" + std::to_string(p) + "]: point ids must ascend");
  }
  for (size_t i = 0; i < rows_.cameras.size(); ++i) {
    const IndexCamera& camera = rows_.cameras[i];
    const auto model = FindCameraModel(camera.model_id);
    if (!model)
      fail("CAMS[" + std::to_string(i) + "]: unknown camera model id " +
           std::to_string(camera.model_id));
    if (camera.num_params != static_cast<uint32_t>(model->num_params)) {
      fail("CAMS[" + std::to_string(i) + "]: " + std::string(model->name) + " has " +
           std::to_string(model->num_params) + " parameters, the file says " +
           std::to_string(camera.num_params));
    }
  }
  uint64_t next_view = 0;
  for (size_t i = 0; i < rows_.images.size(); ++i) {
    const IndexImage& image = rows_.images[i];
    const std::string what =
        "IMGS[" + std::to_string(i) + "] (image_id " + std::to_string(image.image_id) + ")";
    if (image.camera_index >= rows_.cameras.size())
      fail(what + ": camera index " + std::to_string(image.camera_index) + " out of range");
    if (image.name_offset > rows_.strings.size() ||
        image.name_size > rows_.strings.size() - image.name_offset) {
      fail(what + ": name range outside the string pool");
    }
    if (image.first_view != next_view) {
      fail(what + ": views start at " + std::to_string(image.first_view) + ", expected " +
           std::to_string(next_view));
    }
    next_view += image.num_views;
    if (image.cluster >= rows_.images.size())
      fail(what + ": cluster " + std::to_string(image.cluster) + " out of range");
  }
  if (next_view != views) {
    fail("IMGS: view ranges cover " + std::to_string(next_view) + " views, V2PT has " +
         std::to_string(views));
  }
  uint64_t next_track = 0;
  const char* points_tag = rows_.point_offsets.empty() ? "PNTS" : "PNTF";
  for (uint32_t p = 0; p < num_points_; ++p) {
    const auto [first_track, track_length] = StoredTrack(p);
    if (first_track != next_track || track_length == 0) {
      fail(std::string(points_tag) + "[" + std::to_string(p) + "]: track starts at " +
           std::to_string(first_track) + " with length " + std::to_string(track_length) +
           ", expected to start at " + std::to_string(next_track));
    }
    next_track += track_length;
    if (next_track > rows_.tracks.size())
      fail(std::string(points_tag) + "[" + std::to_string(p) + "]: track ends past TRKS");
    if (!rows_.point_offsets.empty()) {
      for (const float value : rows_.point_offsets[p].offset) {
        if (!std::isfinite(value)) fail("PNTF[" + std::to_string(p) + "]: an offset is not finite");
      }
    }
    for (uint64_t t = first_track; t < next_track; ++t) {
      const uint32_t view = rows_.tracks[t];
      if (view >= views || rows_.view_points[view] != p) {
        fail("TRKS[" + std::to_string(t) + "]: view " + std::to_string(view) +
             " is not a view of point " + std::to_string(p));
      }
    }
  }
  if (next_track != rows_.tracks.size())
    fail("TRKS: " + std::to_string(rows_.tracks.size()) + " entries, tracks use " +
         std::to_string(next_track));
  for (size_t v = 0; v < views; ++v) {
    if (rows_.view_points[v] >= num_points_)
      fail("V2PT[" + std::to_string(v) + "]: point " + std::to_string(rows_.view_points[v]) +
           " out of range");
  }
  const char* neighbor_tag = coded() ? "PVNN" : "VNND";
  const std::span<const float> neighbor_distances =
      coded() ? rows_.point_neighbor_distances : rows_.view_neighbor_distances;
  for (size_t r = 0; r < neighbor_distances.size(); ++r) {
    const float d = neighbor_distances[r];
    if (std::isnan(d) || d < 0)
      fail(std::string(neighbor_tag) + "[" + std::to_string(r) + "]: distance " +
           std::to_string(d) + " is not >= 0");
  }
  std::string forest_error;
  if (!ValidateKdForest(kd_forest_, &forest_error)) fail("kd-forest: " + forest_error);
  if (rows_.covisibility_offsets.front() != 0 ||
      rows_.covisibility_offsets.back() != rows_.covisibility_edges.size()) {
    fail("CVOF: offsets must run from 0 to the " + std::to_string(rows_.covisibility_edges.size()) +
         " edges of CVED");
  }
  for (size_t i = 0; i + 1 < rows_.covisibility_offsets.size(); ++i) {
    if (rows_.covisibility_offsets[i] > rows_.covisibility_offsets[i + 1])
      fail("CVOF[" + std::to_string(i) + "]: offsets decrease");
    for (const CovisibilityEdge& edge : CovisibleImages(static_cast<uint32_t>(i))) {
      if (edge.image_index >= rows_.images.size() || edge.image_index == i) {
        fail("CVED: image " + std::to_string(i) + " has an edge to image index " +
             std::to_string(edge.image_index));
      }
    }
  }
}

}  // namespace cwloc
