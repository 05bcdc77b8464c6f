#include "photo/exif.h"

#include <gtest/gtest.h>
#include <libexif/exif-data.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#include "photo/image_decode.h"
#include "tests/photo/exif_builder.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using test::ExifBuilder;

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
      ReadExifFocal(ReadPhotoFile(sceaux / "query_images/100_7101.JPG"), 2832, 2128);
  ASSERT_TRUE(castle);
  EXPECT_DOUBLE_EQ(castle->focal_length_px, 2832.0);
  const auto phones = test::SharedDataDir("exif_samples");
  if (!phones) GTEST_SKIP() << "shared data 'exif_samples' not found";
  const auto phone = ReadExifFocal(ReadPhotoFile(*phones / "berlin_iphone4s/01.jpg"), 3264, 2448);
  ASSERT_TRUE(phone);
  EXPECT_DOUBLE_EQ(phone->focal_length_px, 3264.0);
}

TEST(ExifGps, DegreesMinutesSecondsAndRefs) {
  const auto north_east =
      ReadExifGps(ExifBuilder().GpsPosition("N", 52, 31, 810, "E", 13, 24, 106).Jpeg());
  ASSERT_TRUE(north_east);
  EXPECT_DOUBLE_EQ(north_east->latitude_deg, 52 + 31 / 60.0 + 8.10 / 3600);
  EXPECT_DOUBLE_EQ(north_east->longitude_deg, 13 + 24 / 60.0 + 1.06 / 3600);
  EXPECT_FALSE(north_east->altitude_m);
  EXPECT_FALSE(north_east->horizontal_error_m);
  const auto south_west =
      ReadExifGps(ExifBuilder().GpsPosition("S", 33, 52, 1234, "W", 151, 12, 3000).Jpeg());
  ASSERT_TRUE(south_west);
  EXPECT_DOUBLE_EQ(south_west->latitude_deg, -(33 + 52 / 60.0 + 12.34 / 3600));
  EXPECT_DOUBLE_EQ(south_west->longitude_deg, -(151 + 12 / 60.0 + 30.0 / 3600));
  // Extremes: the pole, the antimeridian.
  const auto pole = ReadExifGps(ExifBuilder().GpsPosition("S", 90, 0, 0, "W", 180, 0, 0).Jpeg());
  ASSERT_TRUE(pole);
  EXPECT_EQ(pole->latitude_deg, -90);
  EXPECT_EQ(pole->longitude_deg, -180);
}

TEST(ExifGps, AltitudeAndHorizontalError) {
  const auto above = ReadExifGps(ExifBuilder()
                                     .GpsPosition("N", 1, 2, 3, "E", 4, 5, 6)
                                     .GpsRationals(EXIF_TAG_GPS_ALTITUDE, {{2715, 100}})
                                     .GpsRationals(EXIF_TAG_GPS_H_POSITIONING_ERROR, {{65, 10}})
                                     .Jpeg());
  ASSERT_TRUE(above);
  EXPECT_DOUBLE_EQ(*above->altitude_m, 27.15);
  EXPECT_DOUBLE_EQ(*above->horizontal_error_m, 6.5);
  const auto below = ReadExifGps(ExifBuilder()
                                     .GpsPosition("N", 31, 30, 0, "E", 35, 30, 0)
                                     .GpsByte(EXIF_TAG_GPS_ALTITUDE_REF, 1)
                                     .GpsRationals(EXIF_TAG_GPS_ALTITUDE, {{430, 1}})
                                     .Jpeg());
  ASSERT_TRUE(below);
  EXPECT_EQ(*below->altitude_m, -430);
  // An unknown altitude ref, a zero denominator: only that field is left out.
  const auto odd = ReadExifGps(ExifBuilder()
                                   .GpsPosition("N", 1, 2, 3, "E", 4, 5, 6)
                                   .GpsByte(EXIF_TAG_GPS_ALTITUDE_REF, 7)
                                   .GpsRationals(EXIF_TAG_GPS_ALTITUDE, {{430, 1}})
                                   .GpsRationals(EXIF_TAG_GPS_H_POSITIONING_ERROR, {{5, 0}})
                                   .Jpeg());
  ASSERT_TRUE(odd);
  EXPECT_FALSE(odd->altitude_m);
  EXPECT_FALSE(odd->horizontal_error_m);
}

TEST(ExifGps, MalformedOrMissingPositionsGiveNothing) {
  EXPECT_FALSE(ReadExifGps(ExifBuilder().Short(EXIF_TAG_FOCAL_LENGTH_IN_35MM_FILM, 28).Jpeg()));
  // No refs; a bad ref; a zero denominator; two components; out of range; 0, 0.
  EXPECT_FALSE(ReadExifGps(ExifBuilder()
                               .GpsRationals(EXIF_TAG_GPS_LATITUDE, {{1, 1}, {2, 1}, {3, 1}})
                               .GpsRationals(EXIF_TAG_GPS_LONGITUDE, {{1, 1}, {2, 1}, {3, 1}})
                               .Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder().GpsPosition("X", 1, 2, 3, "E", 4, 5, 6).Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder().GpsPosition("N", 1, 2, 3, "N", 4, 5, 6).Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder()
                               .GpsAscii(EXIF_TAG_GPS_LATITUDE_REF, "N")
                               .GpsRationals(EXIF_TAG_GPS_LATITUDE, {{1, 1}, {2, 0}, {3, 1}})
                               .GpsAscii(EXIF_TAG_GPS_LONGITUDE_REF, "E")
                               .GpsRationals(EXIF_TAG_GPS_LONGITUDE, {{1, 1}, {2, 1}, {3, 1}})
                               .Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder()
                               .GpsAscii(EXIF_TAG_GPS_LATITUDE_REF, "N")
                               .GpsRationals(EXIF_TAG_GPS_LATITUDE, {{1, 1}, {2, 1}})
                               .GpsAscii(EXIF_TAG_GPS_LONGITUDE_REF, "E")
                               .GpsRationals(EXIF_TAG_GPS_LONGITUDE, {{1, 1}, {2, 1}, {3, 1}})
                               .Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder().GpsPosition("N", 91, 0, 0, "E", 4, 5, 6).Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder().GpsPosition("N", 90, 0, 1, "E", 4, 5, 6).Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder().GpsPosition("N", 1, 0, 0, "W", 180, 1, 0).Jpeg()));
  EXPECT_FALSE(ReadExifGps(ExifBuilder().GpsPosition("N", 0, 0, 0, "E", 0, 0, 0).Jpeg()));
  const std::vector<uint8_t> no_exif = {0xFF, 0xD8, 0xFF, 0xD9};
  EXPECT_FALSE(ReadExifGps(no_exif));
  EXPECT_FALSE(ReadExifGps({}));
  const std::vector<uint8_t> garbage(1000, 0xE1);
  EXPECT_FALSE(ReadExifGps(garbage));
  // Every truncation of a valid EXIF block: nothing or the position, never a crash.
  const auto jpeg = ExifBuilder()
                        .GpsPosition("N", 52, 31, 810, "E", 13, 24, 106)
                        .GpsRationals(EXIF_TAG_GPS_ALTITUDE, {{27, 1}})
                        .Jpeg();
  for (size_t size = 0; size < jpeg.size(); ++size) {
    const auto gps = ReadExifGps(std::span(jpeg).first(size));
    if (gps) {
      EXPECT_NEAR(gps->latitude_deg, 52.518916667, 1e-9);
    }
  }
}

// kapture's Berlin sample (shared data exif_samples/README.txt): the degrees, minutes and
// seconds it lists, and records_gnss.txt's decimal degrees.
TEST(ExifGps, RealPhonePhotos) {
  CWLOC_REQUIRE_SHARED_DATA(samples, "exif_samples");
  struct ExpectedFix {
    const char* file;
    double lat_minutes, lat_seconds, lon_minutes, lon_seconds, altitude;
  };
  for (const ExpectedFix& e : {ExpectedFix{"01.jpg", 31, 8.10, 24, 1.06, 27},
                               ExpectedFix{"02.jpg", 31, 8.13, 24, 1.40, 30},
                               ExpectedFix{"03.jpg", 31, 8.57, 24, 1.61, 39}}) {
    SCOPED_TRACE(e.file);
    const auto gps = ReadExifGps(ReadPhotoFile(samples / "berlin_iphone4s" / e.file));
    ASSERT_TRUE(gps);
    EXPECT_NEAR(gps->latitude_deg, 52 + e.lat_minutes / 60 + e.lat_seconds / 3600, 1e-12);
    EXPECT_NEAR(gps->longitude_deg, 13 + e.lon_minutes / 60 + e.lon_seconds / 3600, 1e-12);
    ASSERT_TRUE(gps->altitude_m);
    EXPECT_DOUBLE_EQ(*gps->altitude_m, e.altitude);
    EXPECT_FALSE(gps->horizontal_error_m);  // an iPhone 4S writes none (only a DOP, 5)
  }
  const auto first = ReadExifGps(ReadPhotoFile(samples / "berlin_iphone4s/01.jpg"));
  ASSERT_TRUE(first);
  EXPECT_NEAR(first->latitude_deg, 52.518916667, 1e-9);
  EXPECT_NEAR(first->longitude_deg, 13.400294444, 1e-9);
}

}  // namespace
}  // namespace cwloc
