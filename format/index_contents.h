#pragma once

#include <span>
#include <string_view>
#include <vector>

#include "format/index_file.h"
#include "format/index_sections.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {

// Every array an index file stores, borrowed: what `cwloc-index build` computes from a model,
// `extract` keeps of an index and `apply` makes of an index and a delta. A full index fills
// `points` and `descriptors` (neighbor_distances per view); a compact one the point origin,
// offsets, codebook and codes (neighbor_distances per point).
struct IndexContents {
  std::span<const IndexCamera> cameras;
  std::span<const IndexImage> images;
  std::string_view strings;
  std::span<const IndexPoint> points;
  const IndexPointOrigin* point_origin = nullptr;
  std::span<const IndexPointOffset> point_offsets;
  std::span<const uint32_t> tracks;
  std::span<const uint8_t> descriptors;
  std::span<const std::span<const uint8_t>> descriptor_pieces;  // instead of `descriptors`
  std::span<const uint8_t> codebook;
  std::span<const uint8_t> codes;
  uint32_t code_bytes = 0;
  std::span<const uint32_t> view_points;
  std::span<const float> neighbor_distances;
  const KdForest* forest = nullptr;
  std::span<const uint32_t> covisibility_offsets;
  std::span<const CovisibilityEdge> covisibility_edges;
  std::span<const ViewKeypoint> view_keypoints;     // optional section; empty: not written
  std::span<const PointColor> point_colors;         // optional section; empty: not written
  std::span<const uint64_t> point_ids;              // optional section; empty: not written
  const IndexGeoreference* georeference = nullptr;  // optional section
  const IndexCovarianceCalibration* covariance_calibration = nullptr;  // optional section
};

class Index;
// What a child of `parent` (a tile, an applied delta) keeps of a compact parent: its codebook,
// code size and point origin, copied into `origin`, which `contents` then points to.
void KeepParentCoding(const Index& parent, IndexPointOrigin* origin, IndexContents* contents);

// The sections of an index file with these contents, in the file's order: first a full index's
// DescriptorSection and the RowSections, which an IndexFileWriter can write ahead, then
// `manifest` (JSON text, borrowed) and the sections made last (kd-forest, co-visibility graph).
// Its format version is FormatMinorOf the result.
std::vector<SectionData> IndexSectionsOf(const IndexContents& contents, std::string_view manifest);
// The sections of rows of points and views but the descriptors, which need neither the
// manifest nor the kd-forest nor the co-visibility graph.
std::vector<SectionData> RowSections(const IndexContents& contents);
// A full index's DESC section: `descriptor_pieces` (or `descriptors`), a row per view_points.
SectionData DescriptorSection(const IndexContents& contents);

}  // namespace cwloc
