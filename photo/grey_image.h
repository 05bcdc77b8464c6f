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

}  // namespace cwloc
