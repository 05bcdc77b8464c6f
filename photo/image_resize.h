#pragma once

#include <cstdint>

#include "photo/grey_image.h"

namespace cwloc {

// COLMAP's default --SiftExtraction.max_image_size: the longer side photos are shrunk to.
inline constexpr uint32_t kDefaultMaxImageSize = 3200;

struct ImageSize {
  uint32_t width = 0;
  uint32_t height = 0;
};

// The size COLMAP 3.8 extracts features at: unchanged when both sides fit max_image_size,
// else scaled by max_image_size / max(width, height) with each side truncated to an integer.
ImageSize ExtractionSize(uint32_t width, uint32_t height, uint32_t max_image_size);

// Resamples to width x height like FreeImage 3.18's FreeImage_Rescale with FILTER_BILINEAR,
// which COLMAP uses: a tent filter stretched by the shrink factor (so every source pixel
// contributes), weights normalised per output pixel, rows first into an 8-bit image, then
// columns; FreeImage stores images bottom-up, so columns are sampled from the bottom row.
GreyImage ResizeBilinear(const GreyImage& image, uint32_t width, uint32_t height);

}  // namespace cwloc
