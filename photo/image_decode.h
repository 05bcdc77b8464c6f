#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "photo/grey_image.h"

namespace cwloc {

// The largest photo decoded by default, in pixels: a 100-megapixel JPEG needs 100 MB as grey
// plus its decoder's buffers. A decompression bomb (a small file claiming a huge image) is
// refused from its header, before any pixel buffer is allocated.
inline constexpr uint64_t kDefaultMaxImagePixels = 100'000'000;

// The smallest side SIFT can work on: VLFeat's coarsest octave must keep a few pixels.
inline constexpr uint32_t kMinImageSide = 16;

// A photo file's bytes, read whole through ReadFileBounded (base/bounded_file.h): a
// regular file of at most kPhotoFile.max_bytes; throws InputError naming it otherwise.
std::vector<uint8_t> ReadPhotoFile(const std::filesystem::path& path);

// Decodes a JPEG or PNG (recognised by its signature, not its name) to 8-bit grey exactly as
// COLMAP 3.8 reads images through FreeImage 3.18: JPEG with libjpeg's fast integer IDCT and
// without fancy chroma upsampling (FreeImage's default flags); 16-bit samples keep their high
// byte; palettes are expanded; alpha is dropped without compositing; colour becomes
// (uint8)(0.2126 R + 0.7152 G + 0.0722 B + 0.5). EXIF orientation is ignored, as COLMAP does.
// Throws InputError naming `path` for an unknown format, corrupt or truncated data, an image
// over max_pixels, or one smaller than kMinImageSide.
GreyImage DecodeGreyImage(std::span<const uint8_t> bytes, const std::filesystem::path& path,
                          uint64_t max_pixels = kDefaultMaxImagePixels);

}  // namespace cwloc
