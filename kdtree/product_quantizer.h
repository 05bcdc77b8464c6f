#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace cwloc {

// Product quantization of 128-byte SIFT descriptors (Jégou, Douze, Schmid, PAMI 2011): the
// descriptor is cut into `num_subspaces` equal parts, each replaced by the index of its nearest
// of 256 centroids learned by k-means on that part, so a descriptor becomes num_subspaces bytes.
// A query is compared with coded descriptors asymmetrically: its exact parts against the
// centroids, from a table of num_subspaces x 256 squared distances computed once per query.
//
// Issue #26 measures it as the compact index's descriptor code (bench/code_bench.cc,
// docs/kd_forest.md "Descriptor codes"); the index format does not store it yet.

struct ProductQuantizerOptions {
  uint32_t num_subspaces = 16;    // code bytes per descriptor; divides 128
  uint32_t iterations = 15;       // Lloyd iterations per subspace
  uint32_t max_training = 50000;  // descriptors k-means sees (an evenly spaced sample)
  uint64_t seed = 0;              // k-means++ seeding and re-seeding of empty clusters
  int threads = 1;                // subspaces trained at once (0 = all cores); same result
};

class ProductQuantizer {
 public:
  static constexpr uint32_t kDims = 128;
  static constexpr uint32_t kCentroids = 256;

  // Learns the centroids from N x 128 descriptors. Throws InputError for a num_subspaces that
  // does not divide 128, no iterations, or fewer than 256 descriptors. Deterministic for a seed
  // on every platform.
  static ProductQuantizer Train(std::span<const uint8_t> descriptors,
                                const ProductQuantizerOptions& options);
  // The same for N x 128 float vectors (e.g. the residuals another quantizer leaves).
  static ProductQuantizer Train(std::span<const float> vectors,
                                const ProductQuantizerOptions& options);

  // The quantizer of a stored uint8 codebook (DescriptorCodes layout): what `cwloc-index
  // update` codes a compact index's new points with, as the index decodes them.
  static ProductQuantizer FromCodebook(std::span<const uint8_t> codebook, uint32_t num_subspaces);

  uint32_t num_subspaces() const { return num_subspaces_; }
  uint32_t subspace_dims() const { return kDims / num_subspaces_; }

  // The nearest centroid of each part: num_subspaces bytes.
  void Encode(const uint8_t* descriptor, uint8_t* code) const;
  void Encode(const float* vector, uint8_t* code) const;
  // The descriptor a code stands for, 128 floats.
  void Decode(const uint8_t* code, float* descriptor) const;
  // table[s * 256 + c]: squared distance of the query's part s to centroid c of subspace s.
  void DistanceTable(const uint8_t* query, float* table) const;
  // The query's squared distance to Decode(code), summed from its table.
  float Distance(const float* table, const uint8_t* code) const;

  // Centroid c of subspace s: centroids()[(s * 256 + c) * subspace_dims() ...].
  std::span<const float> centroids() const { return centroids_; }

 private:
  template <typename T>
  static ProductQuantizer TrainOn(std::span<const T> descriptors,
                                  const ProductQuantizerOptions& options);
  template <typename T>
  void EncodeAny(const T* descriptor, uint8_t* code) const;

  ProductQuantizer(uint32_t num_subspaces, std::vector<float> centroids)
      : num_subspaces_(num_subspaces), centroids_(std::move(centroids)) {}

  uint32_t num_subspaces_;
  std::vector<float> centroids_;
};

}  // namespace cwloc
