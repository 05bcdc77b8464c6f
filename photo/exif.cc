#include "photo/exif.h"

#include <libexif/exif-data.h>
#include <libexif/exif-loader.h>

#include <algorithm>
#include <cmath>
#include <memory>

namespace cwloc {
namespace {

struct ExifDataDeleter {
  void operator()(ExifData* data) const { exif_data_unref(data); }
};

using ExifDataPtr = std::unique_ptr<ExifData, ExifDataDeleter>;

// The EXIF of a JPEG (or a bare EXIF block); null when there is none or it does not parse.
ExifDataPtr LoadExif(std::span<const uint8_t> file_bytes) {
  ExifLoader* loader = exif_loader_new();
  if (loader == nullptr) return nullptr;
  // exif_loader_write only reads the buffer; its signature predates const.
  exif_loader_write(loader, const_cast<unsigned char*>(file_bytes.data()),
                    static_cast<unsigned int>(std::min<size_t>(file_bytes.size(), 0xffffffffu)));
  ExifDataPtr data(exif_loader_get_data(loader));
  exif_loader_unref(loader);
  return data;
}

// The value of a SHORT, LONG or RATIONAL tag as a double; nullopt when absent or malformed.
std::optional<double> NumberTag(ExifData* data, ExifTag tag) {
  ExifEntry* entry = exif_content_get_entry(data->ifd[EXIF_IFD_EXIF], tag);
  if (entry == nullptr || entry->data == nullptr || entry->components < 1) return std::nullopt;
  const ExifByteOrder order = exif_data_get_byte_order(data);
  const size_t size = exif_format_get_size(entry->format);
  if (size == 0 || entry->size < size) return std::nullopt;
  double value = 0.0;
  switch (entry->format) {
    case EXIF_FORMAT_SHORT:
      value = exif_get_short(entry->data, order);
      break;
    case EXIF_FORMAT_LONG:
      value = exif_get_long(entry->data, order);
      break;
    case EXIF_FORMAT_RATIONAL: {
      const ExifRational r = exif_get_rational(entry->data, order);
      if (r.denominator == 0) return std::nullopt;
      value = double(r.numerator) / double(r.denominator);
      break;
    }
    default:
      return std::nullopt;
  }
  if (!std::isfinite(value)) return std::nullopt;
  return value;
}

// Millimetres per FocalPlaneResolutionUnit (EXIF 2.3: 2 inch, 3 cm; 4 mm and 5 um are used
// by some cameras).
std::optional<double> MillimetresPerUnit(double unit) {
  if (unit == 2) return 25.4;
  if (unit == 3) return 10.0;
  if (unit == 4) return 1.0;
  if (unit == 5) return 0.001;
  return std::nullopt;
}

// The GPS IFD's entry for `tag` if it has `format` and at least `components` components whose
// bytes are all there; else null.
ExifEntry* GpsEntry(ExifData* data, int tag, ExifFormat format, unsigned long components) {
  ExifEntry* entry = exif_content_get_entry(data->ifd[EXIF_IFD_GPS], static_cast<ExifTag>(tag));
  if (entry == nullptr || entry->data == nullptr || entry->format != format ||
      entry->components < components || entry->size < components * exif_format_get_size(format)) {
    return nullptr;
  }
  return entry;
}

// The k-th RATIONAL of an entry; nullopt for a zero denominator.
std::optional<double> RationalAt(ExifData* data, ExifEntry* entry, unsigned k) {
  const ExifRational r = exif_get_rational(entry->data + 8 * k, exif_data_get_byte_order(data));
  if (r.denominator == 0) return std::nullopt;
  return double(r.numerator) / double(r.denominator);
}

// One RATIONAL tag's value; nullopt when absent or malformed.
std::optional<double> GpsRational(ExifData* data, int tag) {
  ExifEntry* entry = GpsEntry(data, tag, EXIF_FORMAT_RATIONAL, 1);
  if (entry == nullptr) return std::nullopt;
  return RationalAt(data, entry, 0);
}

// Degrees from the three RATIONALs (degrees, minutes, seconds) and the ref's sign; nullopt when
// malformed, a ref other than `positive` or `negative`, or beyond `limit`.
std::optional<double> GpsAngle(ExifData* data, int tag, int ref_tag, char positive, char negative,
                               double limit) {
  ExifEntry* ref = GpsEntry(data, ref_tag, EXIF_FORMAT_ASCII, 1);
  ExifEntry* angle = GpsEntry(data, tag, EXIF_FORMAT_RATIONAL, 3);
  if (ref == nullptr || angle == nullptr) return std::nullopt;
  const char r = static_cast<char>(ref->data[0]);
  if (r != positive && r != negative) return std::nullopt;
  double degrees = 0;
  for (unsigned k = 0; k < 3; ++k) {
    const auto part = RationalAt(data, angle, k);
    if (!part) return std::nullopt;
    degrees += *part / (k == 0 ? 1.0 : k == 1 ? 60.0 : 3600.0);
  }
  if (!std::isfinite(degrees) || degrees > limit) return std::nullopt;
  return r == negative ? -degrees : degrees;
}

}  // namespace

std::optional<ExifGps> ReadExifGps(std::span<const uint8_t> file_bytes) {
  const ExifDataPtr data = LoadExif(file_bytes);
  if (!data) return std::nullopt;
  const auto latitude =
      GpsAngle(data.get(), EXIF_TAG_GPS_LATITUDE, EXIF_TAG_GPS_LATITUDE_REF, 'N', 'S', 90);
  const auto longitude =
      GpsAngle(data.get(), EXIF_TAG_GPS_LONGITUDE, EXIF_TAG_GPS_LONGITUDE_REF, 'E', 'W', 180);
  if (!latitude || !longitude || (*latitude == 0 && *longitude == 0)) return std::nullopt;
  ExifGps gps;
  gps.latitude_deg = *latitude + 0.0;  // +0.0: no "-0" for a zero with ref S or W
  gps.longitude_deg = *longitude + 0.0;
  if (const auto altitude = GpsRational(data.get(), EXIF_TAG_GPS_ALTITUDE)) {
    ExifEntry* ref = GpsEntry(data.get(), EXIF_TAG_GPS_ALTITUDE_REF, EXIF_FORMAT_BYTE, 1);
    const int below = ref == nullptr ? 0 : ref->data[0];
    if (below == 0) gps.altitude_m = *altitude;
    if (below == 1) gps.altitude_m = -*altitude;
  }
  if (const auto error = GpsRational(data.get(), EXIF_TAG_GPS_H_POSITIONING_ERROR)) {
    gps.horizontal_error_m = *error;
  }
  return gps;
}

std::optional<ExifFocal> ReadExifFocal(std::span<const uint8_t> file_bytes, uint32_t width,
                                       uint32_t height) {
  const ExifDataPtr data = LoadExif(file_bytes);
  if (!data) return std::nullopt;

  const double max_size = std::max(width, height);
  if (const auto f35 = NumberTag(data.get(), EXIF_TAG_FOCAL_LENGTH_IN_35MM_FILM); f35 && *f35 > 0)
    return ExifFocal{*f35 / 35.0 * max_size, "35mm-equivalent"};

  const auto focal_mm = NumberTag(data.get(), EXIF_TAG_FOCAL_LENGTH);
  const auto pixels_x = NumberTag(data.get(), EXIF_TAG_PIXEL_X_DIMENSION);
  const auto resolution_x = NumberTag(data.get(), EXIF_TAG_FOCAL_PLANE_X_RESOLUTION);
  const auto unit = NumberTag(data.get(), EXIF_TAG_FOCAL_PLANE_RESOLUTION_UNIT);
  if (!focal_mm || !(*focal_mm > 0) || !pixels_x || !(*pixels_x > 0) || !resolution_x ||
      !(*resolution_x > 0) || !unit)
    return std::nullopt;
  const auto mm_per_unit = MillimetresPerUnit(*unit);
  if (!mm_per_unit) return std::nullopt;
  const double sensor_width_mm = *pixels_x / *resolution_x * *mm_per_unit;
  const double focal_px = *focal_mm / sensor_width_mm * max_size;
  if (!std::isfinite(focal_px) || !(focal_px > 0)) return std::nullopt;
  return ExifFocal{focal_px, "focal-plane-resolution"};
}

}  // namespace cwloc
