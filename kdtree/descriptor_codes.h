#pragma once

#include <cstdint>
#include <cstring>
#include <span>
#include <vector>

namespace cwloc {

// Descriptors stored as product-quantization codes (product_quantizer.h) with a uint8 codebook,
// as the compact index keeps them: row r's descriptor is the concatenation, over the
// code_bytes subspaces s, of centroid codes[r * code_bytes + s] of subspace s. Decoding gives a
// 128-byte descriptor, so coded rows are compared with the same integer distance kernels as
// exact ones. Borrowed views; the arrays usually live in the memory-mapped index file.
struct DescriptorCodes {
  static constexpr uint32_t kDims = 128;
  static constexpr uint32_t kCentroids = 256;
  static constexpr size_t kCodebookBytes = size_t{kCentroids} * kDims;

  // Centroid c of subspace s: codebook[(s * 256 + c) * (128 / code_bytes) ...]; kCodebookBytes.
  std::span<const uint8_t> codebook;
  std::span<const uint8_t> codes;  // rows x code_bytes
  uint32_t code_bytes = 0;         // divides 128; 0: no codes

  bool empty() const { return code_bytes == 0; }
  size_t NumRows() const { return code_bytes == 0 ? 0 : codes.size() / code_bytes; }
  const uint8_t* Code(size_t row) const { return codes.data() + row * code_bytes; }

  // Row `row` (< NumRows()) as 128 bytes into `out`. Runs in the kd-forest's leaves, so each
  // subspace width copies with a fixed-size memcpy (a single load and store).
  void Decode(size_t row, uint8_t* out) const {
    switch (code_bytes) {
      case 64:
        return DecodeParts<2>(Code(row), out);
      case 32:
        return DecodeParts<4>(Code(row), out);
      case 16:
        return DecodeParts<8>(Code(row), out);
      case 8:
        return DecodeParts<16>(Code(row), out);
      default:
        return DecodeParts<32>(Code(row), out);  // 4, the only other valid size
    }
  }

  // Every row decoded: NumRows() x 128 bytes (a kd-forest's rows over the codes).
  std::vector<uint8_t> DecodeAll() const {
    std::vector<uint8_t> out(NumRows() * kDims);
    for (size_t row = 0; row < NumRows(); ++row) Decode(row, &out[row * kDims]);
    return out;
  }

 private:
  template <uint32_t kPartDims>
  void DecodeParts(const uint8_t* code, uint8_t* out) const {
    constexpr uint32_t kParts = kDims / kPartDims;
    const uint8_t* centroids = codebook.data();
    for (uint32_t s = 0; s < kParts; ++s) {
      std::memcpy(out + s * kPartDims, centroids + (size_t{s} * kCentroids + code[s]) * kPartDims,
                  kPartDims);
    }
  }
};

// A code size the format accepts: a divisor of 128 from 4 to 64 bytes.
inline bool IsValidCodeBytes(uint32_t code_bytes) {
  return code_bytes >= 4 && code_bytes <= 64 && 128 % code_bytes == 0;
}

}  // namespace cwloc
