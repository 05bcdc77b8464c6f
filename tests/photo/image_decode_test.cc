#include "photo/image_decode.h"

#include <gtest/gtest.h>

#include <fstream>

#include "base/error.h"
#include "format/xxhash64.h"
#include "photo/image_resize.h"
#include "tests/test_png.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

std::filesystem::path PhotoFixture(const std::string& name) {
  return test::SourceDir() / "tests/data/photos" / name;
}

GreyImage Decode(const std::filesystem::path& path, uint64_t max_pixels = kDefaultMaxImagePixels) {
  return DecodeGreyImage(ReadPhotoFile(path), path, max_pixels);
}

// The grey image COLMAP 3.8 extracts from: decoded, then shrunk to max_image_size.
GreyImage ColmapGrey(const std::filesystem::path& path, uint32_t max_image_size) {
  GreyImage image = Decode(path);
  const ImageSize size = ExtractionSize(image.width, image.height, max_image_size);
  if (size.width != image.width || size.height != image.height)
    image = ResizeBilinear(image, size.width, size.height);
  return image;
}

std::string ErrorOf(const std::function<void()>& run) {
  try {
    run();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

struct Expected {
  const char* file;
  uint32_t max_image_size;
  uint32_t width;
  uint32_t height;
  uint64_t hash;  // XxHash64 of the grey pixels FreeImage 3.18 produced (COLMAP's reader)
};

// Computed once with FreeImage_Load + ConvertTo24Bits/ConvertToGreyscale + FreeImage_Rescale
// (FILTER_BILINEAR), the calls COLMAP 3.8 makes. grey16.png has no FreeImage value (FreeImage
// cannot convert 16-bit grey); its high bytes equal grey8.png's pixels.
constexpr Expected kFreeImageGrey[] = {
    {"ga8.png", 3200, 40, 30, 0x66e11f3f04f8b5b3ULL},
    {"grey1.png", 3200, 40, 30, 0x7693e8bb2aa68853ULL},
    {"grey16.png", 3200, 40, 30, 0x66e11f3f04f8b5b3ULL},
    {"grey4.png", 3200, 40, 30, 0x5203b44dc4e47564ULL},
    {"grey8.png", 3200, 40, 30, 0x66e11f3f04f8b5b3ULL},
    {"pal8.png", 3200, 40, 30, 0x2b0e8cef4b5193edULL},
    {"palt.png", 3200, 40, 30, 0x2b0e8cef4b5193edULL},
    {"rgb16.png", 3200, 40, 30, 0xa59b041d0cd14b73ULL},
    {"rgb8.png", 3200, 40, 30, 0xa59b041d0cd14b73ULL},
    {"rgba8.png", 3200, 40, 30, 0xa59b041d0cd14b73ULL},
    {"rgbi.png", 3200, 40, 30, 0xa59b041d0cd14b73ULL},
    {"grey.jpg", 3200, 40, 30, 0xe6ce8de470227a7cULL},
    {"rgb.jpg", 3200, 40, 30, 0x6f32f43b45000c5cULL},
    {"ga8.png", 25, 25, 18, 0x51ff4db09f0777a4ULL},
    {"grey1.png", 25, 25, 18, 0x7268d21c0c7866e2ULL},
    {"grey4.png", 25, 25, 18, 0x9f1057b8696c409fULL},
    {"grey8.png", 25, 25, 18, 0x51ff4db09f0777a4ULL},
    {"pal8.png", 25, 25, 18, 0x7f6d26269361a42dULL},
    {"rgb16.png", 25, 25, 18, 0x81163a8b20c4d499ULL},
    {"rgb8.png", 25, 25, 18, 0x81163a8b20c4d499ULL},
    {"rgbi.png", 25, 25, 18, 0x81163a8b20c4d499ULL},
    {"grey.jpg", 25, 25, 18, 0x938bbf05d2772726ULL},
    {"rgb.jpg", 25, 25, 18, 0xa782867b454c7893ULL},
};

TEST(ImageDecode, EveryPixelEqualsFreeImages) {
  for (const Expected& e : kFreeImageGrey) {
    SCOPED_TRACE(std::string(e.file) + " at max size " + std::to_string(e.max_image_size));
    const GreyImage image = ColmapGrey(PhotoFixture(e.file), e.max_image_size);
    EXPECT_EQ(image.width, e.width);
    EXPECT_EQ(image.height, e.height);
    EXPECT_EQ(HashHex(XxHash64(image.pixels)), HashHex(e.hash));
  }
}

TEST(ImageDecode, RealPhotosEqualFreeImages) {
  CWLOC_REQUIRE_SHARED_DATA(herz_jesu, "herz_jesu_p25");
  const auto sceaux = test::SharedDataDir("sceaux_castle");
  if (!sceaux) GTEST_SKIP() << "shared data 'sceaux_castle' not found";
  // No resize for herz_jesu (1536 <= 1600); sceaux is shrunk from 2832 x 2128.
  const GreyImage hj = ColmapGrey(herz_jesu / "query_images/0002.jpg", 1600);
  EXPECT_EQ(hj.width, 1536u);
  EXPECT_EQ(HashHex(XxHash64(hj.pixels)), HashHex(0x817ba87a0205d0a9ULL));
  const GreyImage castle = ColmapGrey(*sceaux / "query_images/100_7101.JPG", 1600);
  EXPECT_EQ(castle.width, 1600u);
  EXPECT_EQ(castle.height, 1202u);
  EXPECT_EQ(HashHex(XxHash64(castle.pixels)), HashHex(0x9cfd39410f8ac87fULL));
}

TEST(ImageDecode, ExtractionSizeTruncatesLikeColmap) {
  EXPECT_EQ(ExtractionSize(2832, 2128, 1600).width, 1600u);
  EXPECT_EQ(ExtractionSize(2832, 2128, 1600).height, 1202u);
  EXPECT_EQ(ExtractionSize(1536, 1024, 1600).width, 1536u);
  EXPECT_EQ(ExtractionSize(1024, 4000, 3200).width, 819u);
  EXPECT_EQ(ExtractionSize(1024, 4000, 3200).height, 3200u);
}

class BadPhotoTest : public ::testing::Test {
 protected:
  std::filesystem::path Write(const std::string& name, const std::string& bytes) {
    const auto path = dir_ / name;
    std::ofstream(path, std::ios::binary) << bytes;
    return path;
  }
  static std::string Bytes(const std::filesystem::path& path) {
    const std::vector<uint8_t> bytes = ReadPhotoFile(path);
    return std::string(bytes.begin(), bytes.end());
  }
  std::filesystem::path WritePng(const std::string& name, uint32_t width, uint32_t height,
                                 uint8_t value, int bit_depth = 8) {
    const auto path = dir_ / name;
    test::WriteGreyPng(path, width, height, value, bit_depth);
    return path;
  }
  test::TempDir dir_;
};

TEST_F(BadPhotoTest, TruncatedJpegIsAnError) {
  const std::string jpeg = Bytes(PhotoFixture("rgb.jpg"));
  const auto path = Write("truncated.jpg", jpeg.substr(0, jpeg.size() / 2));
  EXPECT_EQ(ErrorOf([&] { Decode(path); }),
            path.string() + ": corrupt JPEG: Premature end of JPEG file");
}

TEST_F(BadPhotoTest, TruncatedPngIsAnError) {
  const std::string png = Bytes(PhotoFixture("rgb8.png"));
  const auto path = Write("truncated.png", png.substr(0, png.size() / 2));
  EXPECT_EQ(ErrorOf([&] { Decode(path); }), path.string() + ": corrupt PNG: the file is truncated");
}

TEST_F(BadPhotoTest, TextNamedJpgIsNotAnImage) {
  const auto path = Write("notes.jpg", "these are not pixels\n");
  EXPECT_EQ(ErrorOf([&] { Decode(path); }), path.string() + ": not a JPEG or PNG image");
}

TEST_F(BadPhotoTest, EmptyAndMissingFiles) {
  const auto empty = Write("empty.png", "");
  EXPECT_EQ(ErrorOf([&] { Decode(empty); }), empty.string() + ": the file is empty");
  const auto missing = dir_ / "missing.jpg";
  EXPECT_EQ(ErrorOf([&] { Decode(missing); }), missing.string() + ": cannot open the file");
}

// Issue #23: a device, a pipe or a file over the photo limit is refused before it is read
// (reading /dev/zero used to go on until memory ran out).
TEST_F(BadPhotoTest, DevicesDirectoriesAndHugeFilesAreRefusedUnread) {
  EXPECT_EQ(ErrorOf([] { ReadPhotoFile("/dev/zero"); }),
            "/dev/zero: not a regular file (a character device); an image must be a regular "
            "file, not a device, a pipe, a socket or /dev/stdin");
  EXPECT_EQ(ErrorOf([&] { Decode(dir_.path()); }),
            dir_.path().string() + ": is a directory, not an image");
  const auto huge = test::WriteSparseFile(dir_ / "huge.jpg", 512'000'001);
  EXPECT_EQ(ErrorOf([&] { Decode(huge); }),
            huge.string() + ": 512.000001 MB, more than the 512 MB limit for an image");
}

TEST_F(BadPhotoTest, TinyImageIsRefused) {
  const auto path = WritePng("one.png", 1, 1, 128);
  EXPECT_EQ(ErrorOf([&] { Decode(path); }),
            path.string() + ": the image is 1 x 1 pixels; SIFT needs at least 16 x 16");
}

TEST_F(BadPhotoTest, DecompressionBombIsRefusedFromItsHeader) {
  // A real 30000 x 30000 PNG (1-bit, so it is quick to write): 0.5 MB on disk, 900 MB as grey.
  const auto path = WritePng("bomb.png", 30000, 30000, 0, 1);
  EXPECT_LT(std::filesystem::file_size(path), 1u << 20);
  EXPECT_EQ(ErrorOf([&] { Decode(path); }),
            path.string() +
                ": the image is 30000 x 30000 pixels, more than the limit of 100000000 "
                "(--max-image-pixels)");
}

TEST_F(BadPhotoTest, CorruptPngChunkIsAnError) {
  std::string png = Bytes(PhotoFixture("rgb8.png"));
  png[40] ^= 0x55;  // inside IDAT: its CRC no longer matches
  const auto path = Write("flipped.png", png);
  const std::string error = ErrorOf([&] { Decode(path); });
  EXPECT_EQ(error.rfind(path.string() + ": corrupt PNG: ", 0), 0u) << error;
}

}  // namespace
}  // namespace cwloc
