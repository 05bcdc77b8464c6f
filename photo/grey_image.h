#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace cwloc {

// An 8-bit grey image, row-major, no padding: what SIFT extraction reads, as COLMAP hands
// VLFeat its grey bitmap.
struct GreyImage {
  uint32_t width = 0;
  uint32_t height = 0;
  std::vector<uint8_t> pixels;  // width * height

  uint8_t At(uint32_t x, uint32_t y) const { return pixels[size_t{y} * width + x]; }
};

// COLMAP's grey from 8-bit RGB, FreeImage's GREY(): Rec. 709 luma in single precision, rounded
// by truncating + 0.5.
inline uint8_t Luma709(uint8_t r, uint8_t g, uint8_t b) {
  const float luma = 0.2126F * float(r) + 0.7152F * float(g) + 0.0722F * float(b);
  return static_cast<uint8_t>(luma + 0.5F);
}

}  // namespace cwloc
