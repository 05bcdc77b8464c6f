#include "format/index.h"

#include <algorithm>
#include <cmath>

#include "camera/camera_models.h"

namespace cwloc {
namespace {

// DESC rows are read as raw bytes; the element type only fixes the size check.
struct DescriptorRow {
  uint8_t bytes[kDescriptorBytes];
};

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

}  // namespace

Index Index::Open(const std::filesystem::path& path) {
  Index index(IndexFile::Open(path));
  const IndexFile& file = index.file_;
  const std::string name = path.string();
  index.cameras_ = file.Section<IndexCamera>(section::kCameras);
  index.images_ = file.Section<IndexImage>(section::kImages);
  index.strings_ = file.Section<char>(section::kStrings);
  if (file.FindSection(section::kPointOffsets) != nullptr) {
    const auto origin = file.Section<IndexPointOrigin>(section::kPointOrigin);
    if (origin.size() != 1) {
      throw InputError(name + ": section 'PORG' has " + std::to_string(origin.size()) +
                       " elements, expected 1");
    }
    for (const double value : origin[0].xyz) {
      if (!std::isfinite(value)) throw InputError(name + ": section 'PORG': a value is not finite");
    }
    index.point_origin_ = origin.data();
    index.point_offsets_ = file.Section<IndexPointOffset>(section::kPointOffsets);
    index.num_points_ = index.point_offsets_.size();
  } else {
    index.points_ = file.Section<IndexPoint>(section::kPoints);
    index.num_points_ = index.points_.size();
  }
  index.tracks_ = file.Section<uint32_t>(section::kTracks);
  index.view_points_ = file.Section<uint32_t>(section::kViewPoint);
  const size_t views = index.view_points_.size();
  auto require_count = [&](const char* tag, size_t count, size_t expected, const char* what) {
    if (count != expected) {
      throw InputError(name + ": section '" + tag + "' has " + std::to_string(count) +
                       " elements, expected one per " + what + " (" + std::to_string(expected) +
                       ")");
    }
  };
  if (file.FindSection(section::kPointCodes) != nullptr) {
    const auto codebook = file.Section<uint8_t>(section::kCodebook);
    if (codebook.size() != DescriptorCodes::kCodebookBytes) {
      throw InputError(name + ": section 'PQCB' has " + std::to_string(codebook.size()) +
                       " bytes, expected " + std::to_string(DescriptorCodes::kCodebookBytes));
    }
    const SectionEntry& codes = *file.FindSection(section::kPointCodes);
    if (!IsValidCodeBytes(codes.element_size)) {
      throw InputError(name + ": section 'PCOD' holds " + std::to_string(codes.element_size) +
                       "-byte codes; expected a divisor of 128 from 4 to 64");
    }
    index.codes_ = {codebook, file.bytes().subspan(codes.offset, codes.size), codes.element_size};
    require_count("PCOD", codes.count, index.num_points_, "point");
    index.point_neighbor_distances_ = file.Section<float>(section::kPointNeighbor);
    require_count("PVNN", index.point_neighbor_distances_.size(), index.num_points_, "point");
  } else {
    const auto rows = file.Section<DescriptorRow>(section::kDescriptors);
    index.descriptors_ = {reinterpret_cast<const uint8_t*>(rows.data()),
                          rows.size() * kDescriptorBytes};
    require_count("DESC", rows.size(), views, "view");
    index.view_neighbor_distances_ = file.Section<float>(section::kViewNeighbor);
    require_count("VNND", index.view_neighbor_distances_.size(), views, "view");
  }
  if (file.FindSection(section::kViewKeypoints) != nullptr) {
    index.view_keypoints_ = file.Section<ViewKeypoint>(section::kViewKeypoints);
  }
  if (file.FindSection(section::kPointColors) != nullptr) {
    index.point_colors_ = file.Section<PointColor>(section::kPointColors);
    require_count("PRGB", index.point_colors_.size(), index.num_points_, "point");
  }
  if (file.FindSection(section::kPointIds) != nullptr) {
    index.point_ids_ = file.Section<uint64_t>(section::kPointIds);
    require_count("PIDS", index.point_ids_.size(), index.num_points_, "point");
  }
  index.covisibility_offsets_ = file.Section<uint32_t>(section::kCovisOffsets);
  index.covisibility_edges_ = file.Section<CovisibilityEdge>(section::kCovisEdges);
  file.Section<char>(section::kManifest);
  if (file.FindSection(section::kGeoreference) != nullptr) {
    const auto georeference = file.Section<IndexGeoreference>(section::kGeoreference);
    if (georeference.size() != 1) {
      throw InputError(name + ": section 'GEOR' has " + std::to_string(georeference.size()) +
                       " elements, expected 1");
    }
    ValidateGeoreference(georeference[0], name);
    index.georeference_ = georeference.data();
  }
  if (file.FindSection(section::kCovarianceCalibration) != nullptr) {
    const auto calibration =
        file.Section<IndexCovarianceCalibration>(section::kCovarianceCalibration);
    if (calibration.size() != 1) {
      throw InputError(name + ": section 'PCAL' has " + std::to_string(calibration.size()) +
                       " elements, expected 1");
    }
    ValidateCovarianceCalibration(calibration[0], name);
    index.covariance_calibration_ = calibration.data();
  }
  index.kd_forest_ = {file.Section<KdNode>(section::kKdNodes),
                      file.Section<uint32_t>(section::kKdRoots),
                      file.Section<uint32_t>(section::kKdLeaves), index.descriptors_, index.codes_};

  if (!index.view_keypoints_.empty())
    require_count("VKXY", index.view_keypoints_.size(), views, "view");
  require_count("TRKS", index.tracks_.size(), views, "view");
  if (index.covisibility_offsets_.size() != index.images_.size() + 1) {
    throw InputError(name + ": section 'CVOF' has " +
                     std::to_string(index.covisibility_offsets_.size()) +
                     " elements, expected one per image plus one (" +
                     std::to_string(index.images_.size() + 1) + ")");
  }
  if (index.kd_forest_.roots.empty() ||
      index.kd_forest_.leaves.size() != index.kd_forest_.roots.size() * index.num_rows()) {
    throw InputError(name + ": sections 'KDRT'/'KDLF' hold " +
                     std::to_string(index.kd_forest_.roots.size()) + " trees and " +
                     std::to_string(index.kd_forest_.leaves.size()) +
                     " leaf slots, expected at least one tree and one slot per " +
                     (index.coded() ? "point" : "view") + " per tree");
  }
  if (views > UINT32_MAX || index.num_points_ > UINT32_MAX || index.images_.size() > UINT32_MAX) {
    throw InputError(name + ": more than 2^32 views, points or images");
  }
  return index;
}

std::string_view Index::manifest_json() const {
  const auto manifest = file_.Section<char>(section::kManifest);
  return {manifest.data(), manifest.size()};
}

std::string_view Index::ImageName(const IndexImage& image) const {
  if (image.name_offset > strings_.size() || image.name_size > strings_.size() - image.name_offset)
    return {};
  return {strings_.data() + image.name_offset, image.name_size};
}

uint32_t Index::ImageOfView(uint32_t view) const {
  const auto it =
      std::upper_bound(images_.begin(), images_.end(), view,
                       [](uint32_t v, const IndexImage& image) { return v < image.first_view; });
  if (it == images_.begin()) return UINT32_MAX;
  const IndexImage& image = *(it - 1);
  if (view - image.first_view >= image.num_views) return UINT32_MAX;
  return static_cast<uint32_t>(it - 1 - images_.begin());
}

uint32_t Index::PointOfRow(uint32_t row) const {
  if (coded()) return row < num_points_ ? row : UINT32_MAX;
  return row < view_points_.size() ? view_points_[row] : UINT32_MAX;
}

float Index::RowNeighborDistance(uint32_t row) const {
  const std::span<const float> distances =
      coded() ? point_neighbor_distances_ : view_neighbor_distances_;
  return row < distances.size() ? distances[row] : 0.0f;
}

const uint8_t* Index::RowDescriptor(uint32_t row, uint8_t* scratch) const {
  if (!coded()) return descriptors_.data() + size_t{row} * kDescriptorBytes;
  codes_.Decode(row, scratch);
  return scratch;
}

const uint8_t* Index::ViewDescriptor(uint32_t view, uint8_t* scratch) const {
  if (!coded()) return descriptors_.data() + size_t{view} * kDescriptorBytes;
  const uint32_t point = view < view_points_.size() ? view_points_[view] : UINT32_MAX;
  if (point >= num_points_) {  // a corrupt view; verify names it
    std::fill_n(scratch, kDescriptorBytes, uint8_t{0});
    return scratch;
  }
  return RowDescriptor(point, scratch);  // a coded index's rows are its points
}

std::span<const uint32_t> Index::TrackOf(uint32_t point_index) const {
  if (point_index >= num_points_) return {};
  const auto [first, length] = StoredTrack(point_index);
  if (first > tracks_.size() || length > tracks_.size() - first) return {};
  return tracks_.subspan(first, length);
}

std::pair<uint64_t, uint64_t> Index::StoredTrack(uint32_t p) const {
  if (point_offsets_.empty()) return {points_[p].first_track, points_[p].track_length};
  const uint64_t first = point_offsets_[p].first_track;
  const uint64_t end =
      p + size_t{1} < point_offsets_.size() ? point_offsets_[p + 1].first_track : tracks_.size();
  return {first, end >= first ? end - first : 0};  // a decreasing start: empty, verify names it
}

std::array<double, 3> Index::PointXyz(uint32_t p) const {
  if (point_offsets_.empty()) return {points_[p].xyz[0], points_[p].xyz[1], points_[p].xyz[2]};
  const IndexPointOffset& point = point_offsets_[p];
  return {point_origin_->xyz[0] + point.offset[0], point_origin_->xyz[1] + point.offset[1],
          point_origin_->xyz[2] + point.offset[2]};
}

std::span<const CovisibilityEdge> Index::CovisibleImages(uint32_t image_index) const {
  if (image_index + size_t{1} >= covisibility_offsets_.size()) return {};
  const uint32_t begin = covisibility_offsets_[image_index];
  const uint32_t end = covisibility_offsets_[image_index + 1];
  if (begin > end || end > covisibility_edges_.size()) return {};
  return covisibility_edges_.subspan(begin, end - begin);
}

void Index::Validate() const {
  const std::string name = file_.path().string();
  auto fail = [&](const std::string& what) { throw InputError(name + ": " + what); };
  const size_t views = num_views();

  for (size_t p = 1; p < point_ids_.size(); ++p) {
    if (point_ids_[p] <= point_ids_[p - 1])
      fail("PIDS[" + std::to_string(p) + "]: point ids must ascend");
  }
  for (size_t i = 0; i < cameras_.size(); ++i) {
    const IndexCamera& camera = cameras_[i];
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
  for (size_t i = 0; i < images_.size(); ++i) {
    const IndexImage& image = images_[i];
    const std::string what =
        "IMGS[" + std::to_string(i) + "] (image_id " + std::to_string(image.image_id) + ")";
    if (image.camera_index >= cameras_.size())
      fail(what + ": camera index " + std::to_string(image.camera_index) + " out of range");
    if (image.name_offset > strings_.size() ||
        image.name_size > strings_.size() - image.name_offset) {
      fail(what + ": name range outside the string pool");
    }
    if (image.first_view != next_view) {
      fail(what + ": views start at " + std::to_string(image.first_view) + ", expected " +
           std::to_string(next_view));
    }
    next_view += image.num_views;
    if (image.cluster >= images_.size())
      fail(what + ": cluster " + std::to_string(image.cluster) + " out of range");
  }
  if (next_view != views) {
    fail("IMGS: view ranges cover " + std::to_string(next_view) + " views, V2PT has " +
         std::to_string(views));
  }
  uint64_t next_track = 0;
  const char* points_tag = point_offsets_.empty() ? "PNTS" : "PNTF";
  for (uint32_t p = 0; p < num_points_; ++p) {
    const auto [first_track, track_length] = StoredTrack(p);
    if (first_track != next_track || track_length == 0) {
      fail(std::string(points_tag) + "[" + std::to_string(p) + "]: track starts at " +
           std::to_string(first_track) + " with length " + std::to_string(track_length) +
           ", expected to start at " + std::to_string(next_track));
    }
    next_track += track_length;
    if (next_track > tracks_.size())
      fail(std::string(points_tag) + "[" + std::to_string(p) + "]: track ends past TRKS");
    if (!point_offsets_.empty()) {
      for (const float value : point_offsets_[p].offset) {
        if (!std::isfinite(value)) fail("PNTF[" + std::to_string(p) + "]: an offset is not finite");
      }
    }
    for (uint64_t t = first_track; t < next_track; ++t) {
      const uint32_t view = tracks_[t];
      if (view >= views || view_points_[view] != p) {
        fail("TRKS[" + std::to_string(t) + "]: view " + std::to_string(view) +
             " is not a view of point " + std::to_string(p));
      }
    }
  }
  if (next_track != tracks_.size())
    fail("TRKS: " + std::to_string(tracks_.size()) + " entries, tracks use " +
         std::to_string(next_track));
  for (size_t v = 0; v < views; ++v) {
    if (view_points_[v] >= num_points_)
      fail("V2PT[" + std::to_string(v) + "]: point " + std::to_string(view_points_[v]) +
           " out of range");
  }
  const char* neighbor_tag = coded() ? "PVNN" : "VNND";
  const std::span<const float> neighbor_distances =
      coded() ? point_neighbor_distances_ : view_neighbor_distances_;
  for (size_t r = 0; r < neighbor_distances.size(); ++r) {
    const float d = neighbor_distances[r];
    if (std::isnan(d) || d < 0)
      fail(std::string(neighbor_tag) + "[" + std::to_string(r) + "]: distance " +
           std::to_string(d) + " is not >= 0");
  }
  std::string forest_error;
  if (!ValidateKdForest(kd_forest_, &forest_error)) fail("kd-forest: " + forest_error);
  if (covisibility_offsets_.front() != 0 ||
      covisibility_offsets_.back() != covisibility_edges_.size()) {
    fail("CVOF: offsets must run from 0 to the " + std::to_string(covisibility_edges_.size()) +
         " edges of CVED");
  }
  for (size_t i = 0; i + 1 < covisibility_offsets_.size(); ++i) {
    if (covisibility_offsets_[i] > covisibility_offsets_[i + 1])
      fail("CVOF[" + std::to_string(i) + "]: offsets decrease");
    for (const CovisibilityEdge& edge : CovisibleImages(static_cast<uint32_t>(i))) {
      if (edge.image_index >= images_.size() || edge.image_index == i) {
        fail("CVED: image " + std::to_string(i) + " has an edge to image index " +
             std::to_string(edge.image_index));
      }
    }
  }
}

}  // namespace cwloc
