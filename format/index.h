#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <utility>

#include "format/index_file.h"
#include "format/index_rows.h"
#include "format/index_sections.h"
#include "kdtree/descriptor_codes.h"
#include "kdtree/kd_forest.h"

namespace cwloc {

// The typed, read-only view of an index file that the localizer and the tools use.
// Open() is O(number of sections): it checks that every section is present with the right
// element size and that the counts agree, and never walks the big arrays. Indices stored in
// those arrays are checked where they are used (the accessors below return an empty name or
// span, or UINT32_MAX, on a bad one) and all of them by Validate().
class Index {
 public:
  static Index Open(const std::filesystem::path& path);

  const IndexFile& file() const { return file_; }
  std::string_view manifest_json() const { return {rows_.manifest.data(), rows_.manifest.size()}; }
  // Every section of the table (format/index_section_table.inc) the file has, in place.
  const IndexRows& rows() const { return rows_; }

  std::span<const IndexCamera> cameras() const { return rows_.cameras; }
  std::span<const IndexImage> images() const { return rows_.images; }
  // PNTS of a full index; empty in a compact one, which keeps PORG + PNTF (use PointXyz).
  std::span<const IndexPoint> points() const { return rows_.points; }
  size_t num_points() const { return num_points_; }
  // PORG and PNTF of a compact index (empty / the zero origin in a full one).
  std::span<const IndexPointOffset> point_offsets() const { return rows_.point_offsets; }
  IndexPointOrigin point_origin() const {
    return rows_.point_origin.empty() ? IndexPointOrigin{} : rows_.point_origin[0];
  }
  // Point p's position (p < num_points()).
  std::array<double, 3> PointXyz(uint32_t p) const;
  std::span<const uint32_t> tracks() const { return rows_.tracks; }  // view indices
  // A full index: one 128-byte descriptor per view, and the kd-forest's rows are views.
  // A compact one (coded()): one product-quantization code per 3D point, and its rows are points.
  bool coded() const { return !codes_.empty(); }
  std::span<const uint8_t> descriptors() const { return rows_.descriptors; }  // empty when coded()
  const DescriptorCodes& codes() const { return codes_; }
  std::span<const uint32_t> view_points() const { return rows_.view_points; }
  // Empty unless the index was built with --keypoints.
  std::span<const ViewKeypoint> view_keypoints() const { return rows_.view_keypoints; }
  // Empty unless the index was built with --point-colors (format 1.4's optional PRGB).
  std::span<const PointColor> point_colors() const { return rows_.point_colors; }
  // Each point's COLMAP point3D id, ascending (format 1.5's optional PIDS); empty in older
  // indexes.
  std::span<const uint64_t> point_ids() const { return rows_.point_ids; }
  // v_NN per view (full) or per point (coded(): the nearest over the point's clusters).
  std::span<const float> view_neighbor_distances() const { return rows_.view_neighbor_distances; }
  std::span<const float> point_neighbor_distances() const { return rows_.point_neighbor_distances; }
  std::span<const uint32_t> covisibility_offsets() const { return rows_.covisibility_offsets; }
  std::span<const CovisibilityEdge> covisibility_edges() const { return rows_.covisibility_edges; }
  // nullptr unless the index was georeferenced (format 1.1's optional GEOR section).
  const IndexGeoreference* georeference() const { return FirstOrNull(rows_.georeference); }
  // nullptr unless the build calibrated the pose covariance (format 1.3's optional PCAL).
  const IndexCovarianceCalibration* covariance_calibration() const {
    return FirstOrNull(rows_.covariance_calibration);
  }

  // The global kd-forest over all view descriptors, searched in place.
  const KdForestView& kd_forest() const { return kd_forest_; }

  size_t num_views() const { return rows_.view_points.size(); }
  // Rows of the kd-forest: views, or points when coded().
  size_t num_rows() const { return coded() ? num_points_ : num_views(); }
  // The point a kd-forest row stands for; UINT32_MAX when out of range.
  uint32_t PointOfRow(uint32_t row) const;
  // The row's v_NN distance (VNND or PVNN); 0 when out of range.
  float RowNeighborDistance(uint32_t row) const;
  // The descriptor the localizer compares for a view (< num_views()) or a row (< num_rows()):
  // a pointer into DESC (scratch unused, may be null), or the point's code decoded into
  // `scratch` (128 bytes).
  const uint8_t* ViewDescriptor(uint32_t view, uint8_t* scratch) const;
  const uint8_t* RowDescriptor(uint32_t row, uint8_t* scratch) const;

  // Image name from the string pool; empty if the stored range is out of bounds.
  std::string_view ImageName(const IndexImage& image) const;
  // The image (row in IMGS) whose view range holds `view`; UINT32_MAX if none.
  uint32_t ImageOfView(uint32_t view) const;
  // Views of a point / edges of an image, empty when the stored range is out of bounds.
  std::span<const uint32_t> TrackOf(uint32_t point_index) const;
  std::span<const CovisibilityEdge> CovisibleImages(uint32_t image_index) const;

  // O(size) check of every stored index and range; throws InputError naming the section,
  // the element and the problem.
  void Validate() const;

 private:
  explicit Index(IndexFile file) : file_(std::move(file)) {}
  template <typename T>
  static const T* FirstOrNull(std::span<const T> one) {
    return one.empty() ? nullptr : one.data();
  }
  // Point p's stored track range, unchecked: PNTS's fields, or PNTF's first_track up to the
  // next point's (TRKS's end for the last).
  std::pair<uint64_t, uint64_t> StoredTrack(uint32_t p) const;

  IndexFile file_;
  IndexRows rows_;
  size_t num_points_ = 0;
  DescriptorCodes codes_;
  KdForestView kd_forest_;
};

}  // namespace cwloc
