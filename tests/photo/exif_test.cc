#include "photo/exif.h"

#include <gtest/gtest.h>
#include <libexif/exif-data.h>

#include <cstdlib>

#include "photo/image_decode.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

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
  ExifEntry* Entry(ExifTag tag, ExifFormat format, unsigned size) {
    ExifEntry* entry = exif_entry_new();
    entry->tag = tag;
    entry->format = format;
    entry->components = 1;
    entry->size = size;
    entry->data = static_cast<unsigned char*>(std::calloc(1, size));
    exif_content_add_entry(data_->ifd[EXIF_IFD_EXIF], entry);
    exif_entry_unref(entry);
    return entry;
  }

  ExifData* data_;
};

TEST(ExifFocal, ThirtyFiveMillimetreEquivalentScalesTheLongerSide) {
  const auto jpeg = ExifBuilder().Short(EXIF_TAG_FOCAL_LENGTH_IN_35MM_FILM, 28).Jpeg();
  const auto focal = ReadExifFocal(jpeg, 4000, 3000);
  ASSERT_TRUE(focal);
  EXPECT_DOUBLE_EQ(focal->focal_length_px, 28.0 / 35.0 * 4000.0);
  EXPECT_EQ(focal->rule, "35mm-equivalent");
}

TEST(ExifFocal, FocalPlaneResolutionGivesTheSensorWidth) {
  // 5.85 mm lens, 2832 px across a sensor of 2832 / 4840 inch... in centimetres: 1905.5 px/cm.
  const auto jpeg = ExifBuilder()
                        .Rational(EXIF_TAG_FOCAL_LENGTH, 585, 100)
                        .Short(EXIF_TAG_PIXEL_X_DIMENSION, 2832)
                        .Rational(EXIF_TAG_FOCAL_PLANE_X_RESOLUTION, 38110, 20)
                        .Short(EXIF_TAG_FOCAL_PLANE_RESOLUTION_UNIT, 3)
                        .Jpeg();
  const auto focal = ReadExifFocal(jpeg, 2832, 2128);
  ASSERT_TRUE(focal);
  const double sensor_mm = 2832.0 / 1905.5 * 10.0;
  EXPECT_NEAR(focal->focal_length_px, 5.85 / sensor_mm * 2832.0, 1e-9);
  EXPECT_EQ(focal->rule, "focal-plane-resolution");
}

TEST(ExifFocal, MissingOrUnusableTagsGiveNothing) {
  EXPECT_FALSE(
      ReadExifFocal(ExifBuilder().Rational(EXIF_TAG_FOCAL_LENGTH, 585, 100).Jpeg(), 2832, 2128));
  EXPECT_FALSE(
      ReadExifFocal(ExifBuilder().Short(EXIF_TAG_FOCAL_LENGTH_IN_35MM_FILM, 0).Jpeg(), 2832, 2128));
  // An unknown resolution unit, a zero denominator.
  EXPECT_FALSE(ReadExifFocal(ExifBuilder()
                                 .Rational(EXIF_TAG_FOCAL_LENGTH, 585, 100)
                                 .Short(EXIF_TAG_PIXEL_X_DIMENSION, 2832)
                                 .Rational(EXIF_TAG_FOCAL_PLANE_X_RESOLUTION, 38110, 20)
                                 .Short(EXIF_TAG_FOCAL_PLANE_RESOLUTION_UNIT, 9)
                                 .Jpeg(),
                             2832, 2128));
  EXPECT_FALSE(ReadExifFocal(ExifBuilder().Rational(EXIF_TAG_FOCAL_LENGTH, 585, 0).Jpeg(), 10, 10));
  const std::vector<uint8_t> no_exif = {0xFF, 0xD8, 0xFF, 0xD9};
  EXPECT_FALSE(ReadExifFocal(no_exif, 100, 100));
  const std::vector<uint8_t> garbage(1000, 0xE1);
  EXPECT_FALSE(ReadExifFocal(garbage, 100, 100));
}

TEST(ExifFocal, RealCamerasGiveColmapsFocal) {
  CWLOC_REQUIRE_SHARED_DATA(sceaux, "sceaux_castle");
  // The database COLMAP made from these photos holds 2832 (its README).
  const auto castle =
      ReadExifFocal(ReadFileBytes(sceaux / "query_images/100_7101.JPG"), 2832, 2128);
  ASSERT_TRUE(castle);
  EXPECT_DOUBLE_EQ(castle->focal_length_px, 2832.0);
  const auto phones = test::SharedDataDir("exif_samples");
  if (!phones) GTEST_SKIP() << "shared data 'exif_samples' not found";
  const auto phone = ReadExifFocal(ReadFileBytes(*phones / "berlin_iphone4s/01.jpg"), 3264, 2448);
  ASSERT_TRUE(phone);
  EXPECT_DOUBLE_EQ(phone->focal_length_px, 3264.0);
}

}  // namespace
}  // namespace cwloc
