#include "kdtree/product_quantizer.h"

#include <algorithm>
#include <limits>
#include <string>

#include "base/error.h"
#include "base/parallel_for.h"
#include "base/split_mix64.h"

namespace cwloc {
namespace {

float SquaredDistance(const float* a, const float* b, uint32_t dims) {
  float sum = 0.0f;
  for (uint32_t i = 0; i < dims; ++i) {
    const float d = a[i] - b[i];
    sum += d * d;
  }
  return sum;
}

uint32_t Nearest(const float* point, const float* centroids, uint32_t dims, float* distance) {
  uint32_t best = 0;
  float best_distance = std::numeric_limits<float>::max();
  for (uint32_t c = 0; c < ProductQuantizer::kCentroids; ++c) {
    const float d = SquaredDistance(point, centroids + size_t{c} * dims, dims);
    if (d < best_distance) {
      best_distance = d;
      best = c;
    }
  }
  if (distance != nullptr) *distance = best_distance;
  return best;
}

// k-means++ seeding, then Lloyd iterations; an emptied cluster takes the point farthest from
// its centroid. points: n x dims.
std::vector<float> KMeans(const std::vector<float>& points, size_t n, uint32_t dims,
                          uint32_t iterations, SplitMix64& rng) {
  constexpr uint32_t k = ProductQuantizer::kCentroids;
  std::vector<float> centroids(size_t{k} * dims);
  std::vector<float> nearest(n, std::numeric_limits<float>::max());
  size_t first = rng.Uniform(static_cast<uint32_t>(n));
  std::copy_n(&points[first * dims], dims, &centroids[0]);
  for (uint32_t c = 1; c < k; ++c) {
    double total = 0.0;
    for (size_t i = 0; i < n; ++i) {
      nearest[i] = std::min(
          nearest[i], SquaredDistance(&points[i * dims], &centroids[size_t{c - 1} * dims], dims));
      total += nearest[i];
    }
    // The next seed with probability proportional to its squared distance.
    double target = total * (static_cast<double>(rng.Next() >> 11) * 0x1.0p-53);
    size_t chosen = n - 1;
    for (size_t i = 0; i < n; ++i) {
      target -= nearest[i];
      if (target < 0.0) {
        chosen = i;
        break;
      }
    }
    std::copy_n(&points[chosen * dims], dims, &centroids[size_t{c} * dims]);
  }
  std::vector<uint32_t> assignment(n);
  std::vector<float> distance(n);
  std::vector<double> sums(size_t{k} * dims);
  std::vector<uint32_t> counts(k);
  for (uint32_t iteration = 0; iteration < iterations; ++iteration) {
    for (size_t i = 0; i < n; ++i)
      assignment[i] = Nearest(&points[i * dims], centroids.data(), dims, &distance[i]);
    std::fill(sums.begin(), sums.end(), 0.0);
    std::fill(counts.begin(), counts.end(), 0u);
    for (size_t i = 0; i < n; ++i) {
      ++counts[assignment[i]];
      for (uint32_t d = 0; d < dims; ++d)
        sums[size_t{assignment[i]} * dims + d] += points[i * dims + d];
    }
    for (uint32_t c = 0; c < k; ++c) {
      if (counts[c] == 0) {
        const size_t farthest = static_cast<size_t>(
            std::max_element(distance.begin(), distance.end()) - distance.begin());
        std::copy_n(&points[farthest * dims], dims, &centroids[size_t{c} * dims]);
        distance[farthest] = 0.0f;
        continue;
      }
      for (uint32_t d = 0; d < dims; ++d)
        centroids[size_t{c} * dims + d] =
            static_cast<float>(sums[size_t{c} * dims + d] / counts[c]);
    }
  }
  return centroids;
}

}  // namespace

template <typename T>
ProductQuantizer ProductQuantizer::TrainOn(std::span<const T> descriptors,
                                           const ProductQuantizerOptions& options) {
  const uint32_t m = options.num_subspaces;
  if (m == 0 || kDims % m != 0) {
    throw InputError("product quantizer: " + std::to_string(m) +
                     " subspaces do not divide a 128-dimensional descriptor");
  }
  if (options.iterations == 0) throw InputError("product quantizer: needs at least 1 iteration");
  const size_t total = descriptors.size() / kDims;
  if (descriptors.size() % kDims != 0 || total < kCentroids) {
    throw InputError("product quantizer: " + std::to_string(total) +
                     " training descriptors, need at least 256");
  }
  const size_t n = std::min<size_t>(total, std::max<uint32_t>(options.max_training, kCentroids));
  const uint32_t dims = kDims / m;
  std::vector<float> centroids(size_t{m} * kCentroids * dims);
  // Subspaces are independent (each seeded by its number), so threads do not change the result.
  ParallelFor(m, options.threads, [&](size_t s) {
    std::vector<float> points(n * dims);
    for (size_t i = 0; i < n; ++i) {
      const T* descriptor = &descriptors[(i * total / n) * kDims + s * dims];
      for (uint32_t d = 0; d < dims; ++d) points[i * dims + d] = descriptor[d];
    }
    SplitMix64 rng(options.seed + s);
    const std::vector<float> part = KMeans(points, n, dims, options.iterations, rng);
    std::copy(part.begin(), part.end(), &centroids[s * kCentroids * dims]);
  });
  return ProductQuantizer(m, std::move(centroids));
}

ProductQuantizer ProductQuantizer::Train(std::span<const uint8_t> descriptors,
                                         const ProductQuantizerOptions& options) {
  return TrainOn(descriptors, options);
}

ProductQuantizer ProductQuantizer::Train(std::span<const float> vectors,
                                         const ProductQuantizerOptions& options) {
  return TrainOn(vectors, options);
}

void ProductQuantizer::Encode(const uint8_t* descriptor, uint8_t* code) const {
  EncodeAny(descriptor, code);
}

ProductQuantizer ProductQuantizer::FromCodebook(std::span<const uint8_t> codebook,
                                                uint32_t num_subspaces) {
  if (num_subspaces == 0 || kDims % num_subspaces != 0 ||
      codebook.size() != size_t{kCentroids} * kDims) {
    throw InputError("a codebook of " + std::to_string(codebook.size()) + " bytes for " +
                     std::to_string(num_subspaces) + " subspaces: expected " +
                     std::to_string(kCentroids * kDims) + " bytes and a divisor of 128");
  }
  return ProductQuantizer(num_subspaces, std::vector<float>(codebook.begin(), codebook.end()));
}

void ProductQuantizer::Encode(const float* vector, uint8_t* code) const { EncodeAny(vector, code); }

template <typename T>
void ProductQuantizer::EncodeAny(const T* descriptor, uint8_t* code) const {
  const uint32_t dims = subspace_dims();
  float part[kDims];
  for (uint32_t s = 0; s < num_subspaces_; ++s) {
    for (uint32_t d = 0; d < dims; ++d) part[d] = descriptor[s * dims + d];
    code[s] = static_cast<uint8_t>(
        Nearest(part, &centroids_[size_t{s} * kCentroids * dims], dims, nullptr));
  }
}

void ProductQuantizer::Decode(const uint8_t* code, float* descriptor) const {
  const uint32_t dims = subspace_dims();
  for (uint32_t s = 0; s < num_subspaces_; ++s) {
    std::copy_n(&centroids_[(size_t{s} * kCentroids + code[s]) * dims], dims,
                descriptor + s * dims);
  }
}

void ProductQuantizer::DistanceTable(const uint8_t* query, float* table) const {
  const uint32_t dims = subspace_dims();
  float part[kDims];
  for (uint32_t s = 0; s < num_subspaces_; ++s) {
    for (uint32_t d = 0; d < dims; ++d) part[d] = query[s * dims + d];
    for (uint32_t c = 0; c < kCentroids; ++c) {
      table[s * kCentroids + c] =
          SquaredDistance(part, &centroids_[(size_t{s} * kCentroids + c) * dims], dims);
    }
  }
}

float ProductQuantizer::Distance(const float* table, const uint8_t* code) const {
  float sum = 0.0f;
  for (uint32_t s = 0; s < num_subspaces_; ++s) sum += table[s * kCentroids + code[s]];
  return sum;
}

}  // namespace cwloc
