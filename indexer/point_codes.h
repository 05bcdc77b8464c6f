#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "indexer/clustering.h"
#include "indexer/model_views.h"

namespace cwloc {

// The compact index's descriptors (docs/algorithm.md, "The compact index"): each 3D point's
// views are replaced by one descriptor, the rounded mean of its views' (Active Search's
// per-point descriptor), stored as a product-quantization code.
struct PointCodes {
  uint32_t code_bytes = 0;
  std::vector<uint8_t> codebook;  // DescriptorCodes layout, 256 x 128
  std::vector<uint8_t> codes;     // points x code_bytes
  std::vector<uint8_t> decoded;   // points x 128: what the localizer compares
};

// Learns the quantizer on the points' mean descriptors and codes them. Deterministic for a seed.
PointCodes CodePointDescriptors(const ModelViews& views, uint32_t code_bytes, uint64_t seed,
                                int num_threads);

// Codes the points `rows` (their views' mean descriptors) with a stored codebook: a compact
// index's new and changed points in `cwloc-index update`. rows.size() x code_bytes.
std::vector<uint8_t> CodePointsWithCodebook(const ModelViews& views, std::span<const uint32_t> rows,
                                            std::span<const uint8_t> codebook, uint32_t code_bytes,
                                            int num_threads);

// PORG and PNTF: the points as float offsets from their mean position, with their tracks.
struct PointOffsets {
  IndexPointOrigin origin;
  std::vector<IndexPointOffset> offsets;
};
PointOffsets OffsetPoints(std::span<const IndexPoint> points);

// PVNN: per point, the distance from its decoded descriptor to the nearest other point's, over
// every cluster that sees it (the smallest of ComputeViewNeighborDistances over its views when
// each view carries its point's decoded descriptor). Replaces views->descriptors by those.
// `decoded`: points x 128. With `only_clusters`, a point gets the smallest over its views in
// the flagged clusters (+infinity without one): exact for a point whose clusters are all flagged.
std::vector<float> ComputePointNeighborDistances(ModelViews* views,
                                                 std::span<const uint8_t> decoded,
                                                 const Clustering& clustering, int num_threads,
                                                 const std::vector<bool>* only_clusters = nullptr);

}  // namespace cwloc
