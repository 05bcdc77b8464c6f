#pragma once
// Test photos with chosen EXIF tags (libexif), for the EXIF reader's tests and for tests that
// need photos with GPS positions (georeferencing from EXIF).

#include <libexif/exif-data.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

namespace cwloc::test {

// A JPEG prefix holding only an APP1 EXIF segment with the given tags: what the EXIF reader
// scans (it needs no pixels).
class ExifBuilder {
 public:
  ExifBuilder() : data_(exif_data_new()) { exif_data_set_byte_order(data_, EXIF_BYTE_ORDER_INTEL); }
  ~ExifBuilder() { exif_data_unref(data_); }

  ExifBuilder& Rational(ExifTag tag, uint32_t numerator, uint32_t denominator) {
    exif_set_rational(Entry(tag, EXIF_FORMAT_RATIONAL, 8)->data, EXIF_BYTE_ORDER_INTEL,
                      {numerator, denominator});
    return *this;
  }
  ExifBuilder& Short(ExifTag tag, uint16_t value) {
    exif_set_short(Entry(tag, EXIF_FORMAT_SHORT, 2)->data, EXIF_BYTE_ORDER_INTEL, value);
    return *this;
  }

  // GPS IFD entries (their tag numbers overlap the other IFDs').
  ExifBuilder& GpsAscii(int tag, const char* text) {
    const unsigned size = static_cast<unsigned>(std::strlen(text)) + 1;
    ExifEntry* entry =
        Entry(static_cast<ExifTag>(tag), EXIF_FORMAT_ASCII, size, size, EXIF_IFD_GPS);
    std::memcpy(entry->data, text, size);
    return *this;
  }
  ExifBuilder& GpsRationals(int tag, std::vector<ExifRational> values) {
    const unsigned n = static_cast<unsigned>(values.size());
    ExifEntry* entry =
        Entry(static_cast<ExifTag>(tag), EXIF_FORMAT_RATIONAL, 8 * n, n, EXIF_IFD_GPS);
    for (unsigned k = 0; k < n; ++k)
      exif_set_rational(entry->data + 8 * k, EXIF_BYTE_ORDER_INTEL, values[k]);
    return *this;
  }
  ExifBuilder& GpsByte(int tag, uint8_t value) {
    Entry(static_cast<ExifTag>(tag), EXIF_FORMAT_BYTE, 1, 1, EXIF_IFD_GPS)->data[0] = value;
    return *this;
  }
  // A position in degrees, minutes and seconds (hundredths).
  ExifBuilder& GpsPosition(const char* lat_ref, uint32_t lat_d, uint32_t lat_m,
                           uint32_t lat_centi_s, const char* lon_ref, uint32_t lon_d,
                           uint32_t lon_m, uint32_t lon_centi_s) {
    return GpsAscii(EXIF_TAG_GPS_LATITUDE_REF, lat_ref)
        .GpsRationals(EXIF_TAG_GPS_LATITUDE, {{lat_d, 1}, {lat_m, 1}, {lat_centi_s, 100}})
        .GpsAscii(EXIF_TAG_GPS_LONGITUDE_REF, lon_ref)
        .GpsRationals(EXIF_TAG_GPS_LONGITUDE, {{lon_d, 1}, {lon_m, 1}, {lon_centi_s, 100}});
  }

  std::vector<uint8_t> Jpeg() const {
    unsigned char* blob = nullptr;
    unsigned int size = 0;
    exif_data_save_data(data_, &blob, &size);
    std::vector<uint8_t> jpeg;
    jpeg.reserve(size + 8);
    for (const unsigned byte : {0xFFu, 0xD8u, 0xFFu, 0xE1u, (size + 2) >> 8, (size + 2) & 0xFFu})
      jpeg.push_back(static_cast<uint8_t>(byte));
    for (unsigned i = 0; i < size; ++i) jpeg.push_back(blob[i]);
    jpeg.push_back(0xFF);
    jpeg.push_back(0xD9);
    std::free(blob);
    return jpeg;
  }

 private:
  ExifEntry* Entry(ExifTag tag, ExifFormat format, unsigned size, unsigned components = 1,
                   ExifIfd ifd = EXIF_IFD_EXIF) {
    ExifEntry* entry = exif_entry_new();
    entry->tag = tag;
    entry->format = format;
    entry->components = components;
    entry->size = size;
    entry->data = static_cast<unsigned char*>(std::calloc(1, size));
    exif_content_add_entry(data_->ifd[ifd], entry);
    exif_entry_unref(entry);
    return entry;
  }

  ExifData* data_;
};

}  // namespace cwloc::test
