// The OSCP GeoPose request as real clients fill it (serve/geopose_protocol.h): encoded images
// known by their bytes whatever `imageFormat` says, raw RGBA32 and GRAY8 buffers of the stated
// size, and an accuracy of 0 taken as unknown.
#include "serve/geopose_protocol.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <string>

#include "app/query_priors.h"
#include "base/error.h"
#include "photo/grey_image.h"
#include "serve/base64.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using Json = nlohmann::json;

Json Request(const std::string& format, const std::string& bytes, int width, int height,
             const Json& accuracy) {
  Json fix = {{"latitude", 50.1}, {"longitude", 6.2}, {"altitude", 0.0}};
  if (!accuracy.is_null()) fix["accuracy"] = accuracy;
  return {{"id", "r"},
          {"sensorReadings",
           {{"cameraReadings",
             {{{"imageFormat", format},
               {"size", {width, height}},
               {"imageBytes", test::Base64(bytes)}}}},
            {"geolocationReadings", {fix}}}}};
}

GeoPoseRequest Parse(const Json& request, RequestInputs* inputs) {
  return ParseGeoPoseRequest(request.dump(), inputs);
}

TEST(GeoPoseRequest, AJpegLabelledRgba32IsReadAsAJpeg) {
  const std::string jpeg_start("\xff\xd8\xff\xe0rest of a JPEG", 17);
  RequestInputs inputs;
  const GeoPoseRequest parsed = Parse(Request("RGBA32", jpeg_start, 640, 480, 0.0), &inputs);
  EXPECT_FALSE(parsed.grey);
  EXPECT_EQ(parsed.image, jpeg_start);
}

TEST(GeoPoseRequest, RawRgba32BecomesTheGreyAPhotoWouldHave) {
  // 2 x 1 pixels: a red one and a grey one; alpha is ignored.
  const std::string rgba("\xff\x00\x00\x80\x40\x40\x40\xff", 8);
  RequestInputs inputs;
  const GeoPoseRequest parsed = Parse(Request("RGBA32", rgba, 2, 1, 5.0), &inputs);
  ASSERT_TRUE(parsed.grey);
  ASSERT_EQ(parsed.image.size(), 2u);
  EXPECT_EQ(static_cast<uint8_t>(parsed.image[0]), Luma709(255, 0, 0));
  EXPECT_EQ(static_cast<uint8_t>(parsed.image[0]), 54);
  EXPECT_EQ(static_cast<uint8_t>(parsed.image[1]), 64);
  ASSERT_TRUE(inputs.priors.position);
  EXPECT_DOUBLE_EQ(inputs.priors.position->radius_m, 5.0);
}

TEST(GeoPoseRequest, RawGray8IsTakenAsItIs) {
  RequestInputs inputs;
  const GeoPoseRequest parsed = Parse(Request("GRAY8", "abcdef", 3, 2, nullptr), &inputs);
  EXPECT_TRUE(parsed.grey);
  EXPECT_EQ(parsed.image, "abcdef");
  EXPECT_EQ(parsed.width, 3u);
  EXPECT_EQ(parsed.height, 2u);
}

TEST(GeoPoseRequest, AnAccuracyOfZeroOrLessIsUnknown) {
  for (const double accuracy : {0.0, -1.0}) {
    RequestInputs inputs;
    Parse(Request("GRAY8", "ab", 2, 1, accuracy), &inputs);
    ASSERT_TRUE(inputs.priors.position);
    EXPECT_DOUBLE_EQ(inputs.priors.position->radius_m, kDefaultExifGpsRadiusM) << accuracy;
    EXPECT_DOUBLE_EQ(inputs.priors.position->latitude_deg, 50.1);
  }
}

TEST(GeoPoseRequest, BuffersOfTheWrongSizeAndUnknownFormatsAreRefused) {
  const auto message = [](const Json& request) -> std::string {
    RequestInputs inputs;
    try {
      Parse(request, &inputs);
    } catch (const InputError& e) {
      return e.what();
    }
    return "accepted";
  };
  EXPECT_EQ(message(Request("RGBA32", "abcdefg", 2, 1, nullptr)),
            "geopose: 'cameraReadings'[0]: RGBA32 of 2 x 1 needs 8 bytes, got 7");
  EXPECT_EQ(message(Request("GRAY8", "abc", 2, 2, nullptr)),
            "geopose: 'cameraReadings'[0]: GRAY8 of 2 x 2 needs 4 bytes, got 3");
  EXPECT_EQ(message(Request("JPG", "abcd", 2, 2, nullptr)),
            "geopose: 'cameraReadings'[0]: 'imageBytes' are no JPEG or PNG (imageFormat JPG)");
  EXPECT_EQ(message(Request("DEPTH", "abcd", 2, 2, nullptr)),
            "geopose: 'cameraReadings'[0]: 'imageFormat' must be JPG, PNG, RGBA32 or GRAY8 "
            "(cwloc reads no other)");
}

// A session's id carries what opened it in base64url (serve/sessions.h).
TEST(Base64, UrlSafeEncodingRoundTripsEveryLength) {
  EXPECT_EQ(EncodeBase64Url(""), "");
  EXPECT_EQ(EncodeBase64Url("f"), "Zg");
  EXPECT_EQ(EncodeBase64Url("fo"), "Zm8");
  EXPECT_EQ(EncodeBase64Url("foo"), "Zm9v");
  EXPECT_EQ(EncodeBase64Url("\xfb\xff"), "-_8");  // '-' and '_', never '+' or '/'
  std::string bytes;
  for (int i = 0; i < 300; ++i) {
    bytes.push_back(static_cast<char>(i * 37));
    EXPECT_EQ(DecodeBase64(EncodeBase64Url(bytes), "test"), bytes) << i;
  }
}

}  // namespace
}  // namespace cwloc
