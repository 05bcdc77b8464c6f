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

// Where a photo was taken, from its EXIF GPS tags (docs/geo.md). photo/ cannot use geo/'s
// Geodetic (the same layer), hence its own struct.
struct ExifGps {
  double latitude_deg = 0;   // WGS84 (GPSMapDatum is not read), north positive, [-90, 90]
  double longitude_deg = 0;  // east positive, [-180, 180]
  // GPSAltitude with GPSAltitudeRef (0 or absent: above, 1: below, other: no altitude): metres
  // above MEAN SEA LEVEL, not the WGS84 ellipsoid (they differ by the geoid undulation, -106 to
  // +85 m).
  std::optional<double> altitude_m;
  // GPSHPositioningError: the horizontal error the device reports, metres.
  std::optional<double> horizontal_error_m;
};

// GPSLatitude/GPSLatitudeRef and GPSLongitude/GPSLongitudeRef (three RATIONALs: degrees,
// minutes, seconds; refs N/S and E/W), GPSAltitude/GPSAltitudeRef, GPSHPositioningError.
// nullopt without EXIF, without a position, or when the position is malformed (wrong type or
// count, zero denominator, a bad ref, out of range) or exactly 0, 0 (what some devices write
// without a fix). A malformed altitude or error alone leaves only that field empty. Never
// throws.
std::optional<ExifGps> ReadExifGps(std::span<const uint8_t> file_bytes);

}  // namespace cwloc
