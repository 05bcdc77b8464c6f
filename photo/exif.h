#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <string>

namespace cwloc {

// A focal length read from a photo's EXIF, in pixels of the full image.
struct ExifFocal {
  double focal_length_px = 0.0;
  std::string rule;  // "35mm-equivalent" or "focal-plane-resolution"
};

// COLMAP 3.8's rule (Bitmap::ExifFocalLength), for a width x height photo:
// FocalLengthIn35mmFilm f35 gives f35 / 35 * max(width, height); else FocalLength (mm) with
// the sensor width PixelXDimension / FocalPlaneXResolution (in FocalPlaneResolutionUnit)
// gives focal_mm / sensor_width_mm * max(width, height). COLMAP's table of sensor widths by
// camera make and model is not reproduced. Nothing usable (or no EXIF): nullopt. Malformed
// EXIF is treated as absent; it never throws.
std::optional<ExifFocal> ReadExifFocal(std::span<const uint8_t> file_bytes, uint32_t width,
                                       uint32_t height);

}  // namespace cwloc
