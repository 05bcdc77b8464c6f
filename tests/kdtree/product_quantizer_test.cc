#include "kdtree/product_quantizer.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "base/error.h"
#include "base/split_mix64.h"

namespace cwloc {
namespace {

// n descriptors whose every 8-byte part is one of 256 distinct patterns plus noise of at most
// `noise` per byte: a 16-subspace quantizer can learn each part's patterns exactly.
std::vector<uint8_t> PatternDescriptors(size_t n, int noise, uint64_t seed) {
  SplitMix64 rng(seed);
  std::vector<uint8_t> patterns(16 * 256 * 8);
  for (uint8_t& byte : patterns) byte = static_cast<uint8_t>(20 + rng.Uniform(200));
  std::vector<uint8_t> out(n * 128);
  for (size_t i = 0; i < n; ++i) {
    for (uint32_t s = 0; s < 16; ++s) {
      const uint32_t pattern = rng.Uniform(256);
      for (uint32_t d = 0; d < 8; ++d) {
        const int jitter = noise > 0 ? static_cast<int>(rng.Uniform(2 * noise + 1)) - noise : 0;
        out[i * 128 + s * 8 + d] =
            static_cast<uint8_t>(patterns[(s * 256 + pattern) * 8 + d] + jitter);
      }
    }
  }
  return out;
}

float SquaredDistance(const uint8_t* a, const float* b) {
  float sum = 0;
  for (int d = 0; d < 128; ++d) sum += (a[d] - b[d]) * (a[d] - b[d]);
  return sum;
}

TEST(ProductQuantizer, AsymmetricDistanceIsTheDistanceToTheDecodedDescriptor) {
  const std::vector<uint8_t> data = PatternDescriptors(1100, 10, 1);
  for (const uint32_t m : {8u, 16u, 32u}) {
    ProductQuantizerOptions options;
    options.num_subspaces = m;
    options.iterations = 4;
    const ProductQuantizer pq = ProductQuantizer::Train(data, options);
    ASSERT_EQ(pq.num_subspaces(), m);
    std::vector<uint8_t> code(m);
    std::vector<float> table(m * 256), decoded(128);
    for (size_t i = 0; i < 50; ++i) {
      const uint8_t* query = &data[(i + 1000) * 128];
      pq.DistanceTable(query, table.data());
      pq.Encode(&data[i * 128], code.data());
      pq.Decode(code.data(), decoded.data());
      const float exact = SquaredDistance(query, decoded.data());
      EXPECT_NEAR(pq.Distance(table.data(), code.data()), exact, 1e-5f * exact) << m;
    }
  }
}

TEST(ProductQuantizer, EncodingPicksEachPartsNearestCentroid) {
  const std::vector<uint8_t> data = PatternDescriptors(1000, 20, 2);
  ProductQuantizerOptions options;
  options.iterations = 4;
  const ProductQuantizer pq = ProductQuantizer::Train(data, options);
  const uint32_t dims = pq.subspace_dims();
  std::vector<uint8_t> code(pq.num_subspaces());
  for (size_t i = 0; i < 20; ++i) {
    pq.Encode(&data[i * 128], code.data());
    for (uint32_t s = 0; s < pq.num_subspaces(); ++s) {
      const auto distance = [&](uint32_t c) {
        float sum = 0;
        for (uint32_t d = 0; d < dims; ++d) {
          const float diff =
              data[i * 128 + s * dims + d] - pq.centroids()[(s * 256 + c) * dims + d];
          sum += diff * diff;
        }
        return sum;
      };
      for (uint32_t c = 0; c < 256; ++c) EXPECT_LE(distance(code[s]), distance(c));
    }
  }
}

TEST(ProductQuantizer, LearnsPatternsThatExist) {
  // Without noise every part is one of 256 patterns: the codes reproduce most descriptors
  // exactly (k-means++ may merge two patterns of a part), and more code bytes quantize better.
  const std::vector<uint8_t> data = PatternDescriptors(4000, 0, 3);
  ProductQuantizerOptions options;
  options.num_subspaces = 16;
  options.iterations = 6;
  const ProductQuantizer pq = ProductQuantizer::Train(data, options);
  std::vector<uint8_t> code(16);
  std::vector<float> decoded(128);
  double error = 0;
  int exact = 0;
  for (size_t i = 0; i < 1000; ++i) {
    pq.Encode(&data[i * 128], code.data());
    pq.Decode(code.data(), decoded.data());
    const float e = SquaredDistance(&data[i * 128], decoded.data());
    error += e;
    exact += e == 0.0f;
  }
  EXPECT_GT(exact, 800);
  options.num_subspaces = 8;  // 16-byte parts: 256 centroids for 256^2 combinations
  const ProductQuantizer coarse = ProductQuantizer::Train(data, options);
  std::vector<uint8_t> coarse_code(8);
  double coarse_error = 0;
  for (size_t i = 0; i < 1000; ++i) {
    coarse.Encode(&data[i * 128], coarse_code.data());
    coarse.Decode(coarse_code.data(), decoded.data());
    coarse_error += SquaredDistance(&data[i * 128], decoded.data());
  }
  EXPECT_GT(coarse_error, 10 * error);
}

TEST(ProductQuantizer, TrainingIsDeterministicForASeed) {
  const std::vector<uint8_t> data = PatternDescriptors(1500, 15, 4);
  ProductQuantizerOptions options;
  options.iterations = 5;
  const ProductQuantizer a = ProductQuantizer::Train(data, options);
  const ProductQuantizer b = ProductQuantizer::Train(data, options);
  EXPECT_TRUE(std::equal(a.centroids().begin(), a.centroids().end(), b.centroids().begin()));
  options.seed = 7;
  const ProductQuantizer c = ProductQuantizer::Train(data, options);
  EXPECT_FALSE(std::equal(a.centroids().begin(), a.centroids().end(), c.centroids().begin()));
}

TEST(ProductQuantizer, FloatVectorsTrainAndEncodeAsTheirBytes) {
  // Residual codes train on floats; descriptors given as floats must give the same quantizer.
  const std::vector<uint8_t> data = PatternDescriptors(1000, 15, 6);
  const std::vector<float> as_float(data.begin(), data.end());
  ProductQuantizerOptions options;
  options.iterations = 4;
  const ProductQuantizer bytes = ProductQuantizer::Train(data, options);
  const ProductQuantizer floats =
      ProductQuantizer::Train(std::span<const float>(as_float), options);
  EXPECT_TRUE(
      std::equal(bytes.centroids().begin(), bytes.centroids().end(), floats.centroids().begin()));
  std::vector<uint8_t> a(16), b(16);
  for (size_t i = 0; i < 100; ++i) {
    bytes.Encode(&data[i * 128], a.data());
    floats.Encode(&as_float[i * 128], b.data());
    EXPECT_EQ(a, b);
  }
  EXPECT_THAT(
      [&] { ProductQuantizer::Train(std::span<const float>(as_float).first(100 * 128), options); },
      testing::ThrowsMessage<InputError>(
          "product quantizer: 100 training descriptors, need at least 256"));
}

TEST(ProductQuantizer, RefusesWhatItCannotTrain) {
  const std::vector<uint8_t> data = PatternDescriptors(300, 5, 5);
  ProductQuantizerOptions options;
  options.num_subspaces = 12;
  EXPECT_THAT([&] { ProductQuantizer::Train(data, options); },
              testing::ThrowsMessage<InputError>(
                  "product quantizer: 12 subspaces do not divide a 128-dimensional descriptor"));
  options.num_subspaces = 0;
  EXPECT_THROW(ProductQuantizer::Train(data, options), InputError);
  options.num_subspaces = 16;
  options.iterations = 0;
  EXPECT_THAT([&] { ProductQuantizer::Train(data, options); },
              testing::ThrowsMessage<InputError>("product quantizer: needs at least 1 iteration"));
  options.iterations = 3;
  EXPECT_THAT([&] { ProductQuantizer::Train(std::span(data).first(255 * 128), options); },
              testing::ThrowsMessage<InputError>(
                  "product quantizer: 255 training descriptors, need at least 256"));
  EXPECT_THAT([&] { ProductQuantizer::Train(std::span(data).first(300 * 128 - 1), options); },
              testing::Throws<InputError>());
}

}  // namespace
}  // namespace cwloc
