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

}  // namespace

std::optional<ExifFocal> ReadExifFocal(std::span<const uint8_t> file_bytes, uint32_t width,
                                       uint32_t height) {
  ExifLoader* loader = exif_loader_new();
  if (loader == nullptr) return std::nullopt;
  // exif_loader_write only reads the buffer; its signature predates const.
  exif_loader_write(loader, const_cast<unsigned char*>(file_bytes.data()),
                    static_cast<unsigned int>(std::min<size_t>(file_bytes.size(), 0xffffffffu)));
  std::unique_ptr<ExifData, ExifDataDeleter> data(exif_loader_get_data(loader));
  exif_loader_unref(loader);
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
