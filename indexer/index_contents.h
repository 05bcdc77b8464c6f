#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>
#include <string_view>

#include "format/index_sections.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {

// Every array an index file stores, borrowed: what `cwloc-index build` computes from a model
// and `cwloc-index extract` keeps of an index. A full index fills `points` and `descriptors`
// (neighbor_distances per view); a compact one the point origin, offsets, codebook and codes
// (neighbor_distances per point).
struct IndexContents {
  std::span<const IndexCamera> cameras;
  std::span<const IndexImage> images;
  std::string_view strings;
  std::span<const IndexPoint> points;
  const IndexPointOrigin* point_origin = nullptr;
  std::span<const IndexPointOffset> point_offsets;
  std::span<const uint32_t> tracks;
  std::span<const uint8_t> descriptors;
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
  const IndexGeoreference* georeference = nullptr;  // optional section
  const IndexCovarianceCalibration* covariance_calibration = nullptr;  // optional section
};

// Writes the sections atomically, `manifest` first with its format_version set from them.
void WriteIndex(const std::filesystem::path& path, const IndexContents& contents,
                nlohmann::ordered_json manifest);

// The global kd-forest over an index's rows (N x 128: views, or a compact index's decoded
// points), with a progress bar on a terminal.
KdForest BuildIndexForest(std::span<const uint8_t> rows, KdForestBuildOptions options,
                          uint64_t seed, int threads);

}  // namespace cwloc
