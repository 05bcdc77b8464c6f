#include "indexer/point_codes.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "base/parallel_for.h"
#include "indexer/neighbor_distances.h"
#include "kdtree/descriptor_codes.h"
#include "kdtree/product_quantizer.h"

namespace cwloc {
namespace {

constexpr size_t kDims = DescriptorCodes::kDims;
// Points k-means sees: enough for 256 centroids per subspace, seconds even for a city.
constexpr uint32_t kTrainingPoints = 100000;
constexpr uint32_t kTrainingIterations = 15;

// Point p's views' descriptors averaged and rounded.
void MeanDescriptor(const ModelViews& views, size_t p, uint8_t* mean) {
  const IndexPoint& point = views.points[p];
  uint32_t sum[kDims] = {};
  for (uint32_t t = point.first_track; t < point.first_track + point.track_length; ++t) {
    const uint8_t* descriptor = &views.descriptors[size_t{views.tracks[t]} * kDims];
    for (size_t d = 0; d < kDims; ++d) sum[d] += descriptor[d];
  }
  for (size_t d = 0; d < kDims; ++d)
    mean[d] = static_cast<uint8_t>((sum[d] + point.track_length / 2) /
                                   std::max<uint32_t>(point.track_length, 1));
}

std::vector<uint8_t> MeanDescriptors(const ModelViews& views, int num_threads) {
  std::vector<uint8_t> means(views.points.size() * kDims);
  ParallelFor(views.points.size(), num_threads,
              [&](size_t p) { MeanDescriptor(views, p, &means[p * kDims]); });
  return means;
}

}  // namespace

PointCodes CodePointDescriptors(const ModelViews& views, uint32_t code_bytes, uint64_t seed,
                                int num_threads) {
  const std::vector<uint8_t> means = MeanDescriptors(views, num_threads);
  ProductQuantizerOptions options;
  options.num_subspaces = code_bytes;
  options.iterations = kTrainingIterations;
  options.max_training = kTrainingPoints;
  options.seed = seed;
  options.threads = num_threads;
  const ProductQuantizer quantizer = ProductQuantizer::Train(means, options);

  PointCodes out;
  out.code_bytes = code_bytes;
  // Centroids are means of uint8 values; stored rounded, so decoding gives uint8 descriptors.
  const std::span<const float> centroids = quantizer.centroids();
  out.codebook.resize(DescriptorCodes::kCodebookBytes);
  for (size_t i = 0; i < centroids.size(); ++i)
    out.codebook[i] = static_cast<uint8_t>(std::clamp(std::lround(centroids[i]), 0L, 255L));
  const size_t num_points = views.points.size();
  out.codes.resize(num_points * code_bytes);
  ParallelFor(num_points, num_threads,
              [&](size_t p) { quantizer.Encode(&means[p * kDims], &out.codes[p * code_bytes]); });
  out.decoded = DescriptorCodes{out.codebook, out.codes, code_bytes}.DecodeAll();
  return out;
}

std::vector<uint8_t> CodePointsWithCodebook(const ModelViews& views, std::span<const uint32_t> rows,
                                            std::span<const uint8_t> codebook, uint32_t code_bytes,
                                            int num_threads) {
  const ProductQuantizer quantizer = ProductQuantizer::FromCodebook(codebook, code_bytes);
  std::vector<uint8_t> codes(rows.size() * code_bytes);
  ParallelFor(rows.size(), num_threads, [&](size_t i) {
    uint8_t mean[kDims];
    MeanDescriptor(views, rows[i], mean);
    quantizer.Encode(mean, &codes[i * code_bytes]);
  });
  return codes;
}

PointOffsets OffsetPoints(std::span<const IndexPoint> points) {
  PointOffsets out{};
  for (const IndexPoint& point : points)
    for (int i = 0; i < 3; ++i) out.origin.xyz[i] += point.xyz[i] / double(points.size());
  out.offsets.reserve(points.size());
  for (const IndexPoint& point : points) {
    IndexPointOffset& offset = out.offsets.emplace_back();
    for (int i = 0; i < 3; ++i) offset.offset[i] = float(point.xyz[i] - out.origin.xyz[i]);
    offset.first_track = point.first_track;
  }
  return out;
}

std::vector<float> ComputePointNeighborDistances(ModelViews* views,
                                                 std::span<const uint8_t> decoded,
                                                 const Clustering& clustering, int num_threads,
                                                 const std::vector<bool>* only_clusters) {
  for (size_t v = 0; v < views->num_views(); ++v) {
    std::copy_n(&decoded[size_t{views->view_points[v]} * kDims], kDims,
                &views->descriptors[v * kDims]);
  }
  const std::vector<float> per_view =
      ComputeViewNeighborDistances(*views, clustering, num_threads, only_clusters);
  std::vector<float> per_point(views->points.size(), std::numeric_limits<float>::infinity());
  for (size_t v = 0; v < per_view.size(); ++v) {
    float& distance = per_point[views->view_points[v]];
    distance = std::min(distance, per_view[v]);
  }
  return per_point;
}

}  // namespace cwloc
