#include "photo/sift/sift_extractor.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <functional>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>

#include "format/xxhash64.h"
#include "photo/image_decode.h"
#include "photo/image_resize.h"
#include "photo/sift/sift_levels.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// A grey image with dark and bright Gaussian blobs of several sizes on a mid-grey ramp.
GreyImage BlobImage(uint32_t width, uint32_t height) {
  GreyImage image{width, height, std::vector<uint8_t>(size_t{width} * height)};
  struct Blob {
    double x, y, sigma, amplitude;
  };
  std::vector<Blob> blobs;
  for (int i = 0; i < 24; ++i) {
    blobs.push_back({20.0 + (i * 37) % (width - 40), 20.0 + (i * 53) % (height - 40),
                     2.0 + (i % 5) * 1.5, (i % 2 ? 90.0 : -90.0)});
  }
  for (uint32_t y = 0; y < height; ++y) {
    for (uint32_t x = 0; x < width; ++x) {
      double v = 100 + 40.0 * x / width;
      for (const Blob& b : blobs) {
        const double d2 = (x - b.x) * (x - b.x) + (y - b.y) * (y - b.y);
        v += b.amplitude * std::exp(-d2 / (2 * b.sigma * b.sigma));
      }
      image.pixels[size_t{y} * width + x] = static_cast<uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  }
  return image;
}

std::vector<SiftOptions::Implementation> Implementations() {
  if (!SiftVlfeatAvailable()) return {SiftOptions::Implementation::kCwloc};
  return {SiftOptions::Implementation::kCwloc, SiftOptions::Implementation::kVlfeat};
}

TEST(SiftOptionsTest, DefaultsAreColmaps) {
  const SiftOptions options;
  EXPECT_EQ(options.max_num_features, 8192);
  EXPECT_EQ(options.first_octave, -1);
  EXPECT_EQ(options.num_octaves, 4);
  EXPECT_EQ(options.octave_resolution, 3);
  EXPECT_DOUBLE_EQ(options.peak_threshold, 0.02 / 3);
  EXPECT_EQ(options.edge_threshold, 10.0);
  EXPECT_EQ(options.max_num_orientations, 2);
  EXPECT_FALSE(options.upright);
  EXPECT_EQ(options.normalization, SiftOptions::Normalization::kL1Root);
  EXPECT_NO_THROW(ValidateSiftOptions(options));
}

TEST(SiftOptionsTest, BadOptionsThrow) {
  const GreyImage image = BlobImage(64, 64);
  auto expect_throw = [&](auto mutate, const char* name) {
    SiftOptions options;
    mutate(options);
    try {
      ExtractSift(image, options);
      ADD_FAILURE() << name << " accepted";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
    }
  };
  expect_throw([](SiftOptions& o) { o.max_num_features = 0; }, "max_num_features");
  expect_throw([](SiftOptions& o) { o.num_octaves = 0; }, "num_octaves");
  expect_throw([](SiftOptions& o) { o.octave_resolution = 0; }, "octave_resolution");
  expect_throw([](SiftOptions& o) { o.peak_threshold = 0; }, "peak_threshold");
  expect_throw([](SiftOptions& o) { o.edge_threshold = -1; }, "edge_threshold");
  expect_throw([](SiftOptions& o) { o.max_num_orientations = 0; }, "max_num_orientations");
  expect_throw([](SiftOptions& o) { o.num_threads = 0; }, "num_threads");
  EXPECT_THROW(ExtractSift(GreyImage{}, SiftOptions{}), std::invalid_argument);
  EXPECT_THROW(ExtractSift(GreyImage{4, 4, std::vector<uint8_t>(15)}, SiftOptions{}),
               std::invalid_argument);
}

// A build without VLFeat rejects what only VLFeat computes, naming the option and the cure.
TEST(SiftOptionsTest, VlfeatOnlyOptionsNeedVlfeat) {
  SiftOptions reference;
  reference.implementation = SiftOptions::Implementation::kVlfeat;
  SiftOptions twice_upsampled;
  twice_upsampled.first_octave = -2;
  for (const auto& [options, name] :
       {std::pair{reference, "implementation"}, std::pair{twice_upsampled, "first_octave"}}) {
    SCOPED_TRACE(name);
    if (SiftVlfeatAvailable()) {
      EXPECT_NO_THROW(ValidateSiftOptions(options));
      continue;
    }
    try {
      ExtractSift(BlobImage(64, 64), options);
      ADD_FAILURE() << "accepted without VLFeat";
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(name), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("-DCWLOC_WITH_VLFEAT=ON"), std::string::npos)
          << e.what();
    }
  }
}

TEST(SiftLevelsTest, FirstLevelToKeepFollowsColmap) {
  using sift_internal::FirstLevelToKeep;
  // Coarse levels are at the end; the level that crosses the cap is kept whole.
  EXPECT_EQ(FirstLevelToKeep({10, 10, 10}, 100), 0u);  // under the cap: all
  EXPECT_EQ(FirstLevelToKeep({10, 10, 10}, 30), 0u);   // exactly the cap: all
  EXPECT_EQ(FirstLevelToKeep({10, 10, 10}, 29), 0u);   // level 0 crosses: kept
  EXPECT_EQ(FirstLevelToKeep({10, 10, 10}, 20), 0u);
  EXPECT_EQ(FirstLevelToKeep({10, 10, 10}, 19), 1u);
  EXPECT_EQ(FirstLevelToKeep({10, 10, 10}, 5), 2u);
  EXPECT_EQ(FirstLevelToKeep({}, 5), 0u);
}

TEST(SiftLevelsTest, FinishDescriptorIsRootSiftInUbcOrder) {
  std::vector<float> vl(kSiftDescriptorDim, 0.0f);
  vl[0] = 1.0f;      // cell 0, angle 0 stays at 0
  vl[1] = 1.0f;      // cell 0, angle 1 goes to UBC bin 7
  vl[8 + 3] = 2.0f;  // cell 1, angle 3 goes to UBC bin 5
  uint8_t out[kSiftDescriptorDim];
  sift_internal::FinishDescriptor(vl.data(), SiftOptions::Normalization::kL1Root, out);
  // L1 norm 4: sqrt(1/4) * 512 = 256 -> clamped to 255; sqrt(2/4) * 512 = 362 -> 255.
  EXPECT_EQ(out[0], 255);
  EXPECT_EQ(out[7], 255);
  EXPECT_EQ(out[1], 0);
  EXPECT_EQ(out[8 + 5], 255);
  EXPECT_EQ(std::accumulate(out, out + kSiftDescriptorDim, 0), 3 * 255);
  vl.assign(kSiftDescriptorDim, 1.0f);  // sqrt(1/128) * 512 = 45.25 -> 45 everywhere
  sift_internal::FinishDescriptor(vl.data(), SiftOptions::Normalization::kL1Root, out);
  for (int i = 0; i < kSiftDescriptorDim; ++i) EXPECT_EQ(out[i], 45);
  sift_internal::FinishDescriptor(vl.data(), SiftOptions::Normalization::kL2, out);
  for (int i = 0; i < kSiftDescriptorDim; ++i) EXPECT_EQ(out[i], 45);
}

class SiftImplementationTest : public testing::TestWithParam<SiftOptions::Implementation> {};

TEST_P(SiftImplementationTest, FindsBlobsWithWellFormedDescriptors) {
  const GreyImage image = BlobImage(320, 240);
  SiftOptions options;
  options.implementation = GetParam();
  const SiftFeatures features = ExtractSift(image, options);
  ASSERT_GT(features.size(), 10u);
  ASSERT_EQ(features.descriptors.size(), features.size() * kSiftDescriptorDim);
  for (size_t i = 0; i < features.size(); ++i) {
    const SiftKeypoint& k = features.keypoints[i];
    EXPECT_GE(k.x, 0.0f);
    EXPECT_LE(k.x, 320.0f);
    EXPECT_GE(k.y, 0.0f);
    EXPECT_LE(k.y, 240.0f);
    EXPECT_GT(k.scale, 0.5f);
    // RootSIFT: the squares of v / 512 sum to 1 before rounding and clamping.
    double sum = 0;
    for (int j = 0; j < kSiftDescriptorDim; ++j) {
      const double v = features.Descriptor(i)[j] / 512.0;
      sum += v * v;
    }
    EXPECT_NEAR(sum, 1.0, 0.1) << "keypoint " << i;
  }
}

TEST_P(SiftImplementationTest, CapKeepsCoarseLevelsWhole) {
  const GreyImage image = BlobImage(320, 240);
  SiftOptions options;
  options.implementation = GetParam();
  const SiftFeatures all = ExtractSift(image, options);
  options.max_num_features = 5;
  const SiftFeatures capped = ExtractSift(image, options);
  ASSERT_GT(capped.size(), 0u);
  ASSERT_LT(capped.size(), all.size());
  // The kept features are the last (coarsest) ones of the uncapped run, in the same order.
  const size_t offset = all.size() - capped.size();
  for (size_t i = 0; i < capped.size(); ++i) {
    EXPECT_EQ(capped.keypoints[i].x, all.keypoints[offset + i].x);
    EXPECT_EQ(capped.keypoints[i].scale, all.keypoints[offset + i].scale);
  }
}

TEST_P(SiftImplementationTest, ThreadsDoNotChangeResults) {
  const GreyImage image = BlobImage(320, 240);
  SiftOptions options;
  options.implementation = GetParam();
  const SiftFeatures one = ExtractSift(image, options);
  options.num_threads = 3;
  const SiftFeatures three = ExtractSift(image, options);
  ASSERT_EQ(one.size(), three.size());
  EXPECT_EQ(one.descriptors, three.descriptors);
  for (size_t i = 0; i < one.size(); ++i) {
    EXPECT_EQ(one.keypoints[i].x, three.keypoints[i].x);
    EXPECT_EQ(one.keypoints[i].orientation, three.keypoints[i].orientation);
  }
}

TEST_P(SiftImplementationTest, UprightGivesZeroOrientation) {
  SiftOptions options;
  options.implementation = GetParam();
  options.upright = true;
  const SiftFeatures features = ExtractSift(BlobImage(160, 120), options);
  ASSERT_GT(features.size(), 0u);
  for (const SiftKeypoint& k : features.keypoints) EXPECT_EQ(k.orientation, 0.0f);
}

// Ours and VLFeat with `options` give the same features: the same descriptor bytes and the
// same keypoint fields bit for bit, in the same order.
void ExpectOursEqualVlfeat(const GreyImage& image, SiftOptions options) {
  options.implementation = SiftOptions::Implementation::kVlfeat;
  const SiftFeatures vlfeat = ExtractSift(image, options);
  options.implementation = SiftOptions::Implementation::kCwloc;
  const SiftFeatures ours = ExtractSift(image, options);
  ASSERT_EQ(ours.size(), vlfeat.size());
  EXPECT_EQ(ours.descriptors, vlfeat.descriptors);
  auto bits = [](float v) { return std::bit_cast<uint32_t>(v); };
  for (size_t i = 0; i < ours.size(); ++i) {
    EXPECT_EQ(bits(ours.keypoints[i].x), bits(vlfeat.keypoints[i].x)) << i;
    EXPECT_EQ(bits(ours.keypoints[i].y), bits(vlfeat.keypoints[i].y)) << i;
    EXPECT_EQ(bits(ours.keypoints[i].scale), bits(vlfeat.keypoints[i].scale)) << i;
    EXPECT_EQ(bits(ours.keypoints[i].orientation), bits(vlfeat.keypoints[i].orientation)) << i;
  }
}

// Ours reproduces VLFeat bit for bit, for other options too.
TEST(SiftCwlocTest, EqualsVlfeatForVariousOptions) {
  if (!SiftVlfeatAvailable()) GTEST_SKIP() << "built without VLFeat";
  const GreyImage image = BlobImage(301, 203);  // odd sizes: odd octave sides
  std::vector<std::function<void(SiftOptions&)>> variants = {
      [](SiftOptions&) {},
      [](SiftOptions& o) { o.first_octave = 0; },
      [](SiftOptions& o) { o.first_octave = 1; },
      [](SiftOptions& o) { o.first_octave = -2; },
      [](SiftOptions& o) { o.octave_resolution = 4, o.peak_threshold = 0.02 / 4; },
      [](SiftOptions& o) { o.num_octaves = 6; },
      [](SiftOptions& o) { o.max_num_features = 20; },
      [](SiftOptions& o) { o.max_num_orientations = 4; },
      [](SiftOptions& o) { o.edge_threshold = 3; },
      [](SiftOptions& o) { o.normalization = SiftOptions::Normalization::kL2; },
      [](SiftOptions& o) { o.upright = true; },
  };
  for (size_t v = 0; v < variants.size(); ++v) {
    SCOPED_TRACE("variant " + std::to_string(v));
    SiftOptions options;
    variants[v](options);
    ExpectOursEqualVlfeat(image, options);
  }
}

// COLMAP's cap decides which levels are described, and ours describes the first octave's from
// a level it kept whole when the cap keeps none below it: every cap, on a real photo, from
// the coarsest levels only to all of them, gives VLFeat's features.
TEST(SiftCwlocTest, EqualsVlfeatAtEveryCap) {
  if (!SiftVlfeatAvailable()) GTEST_SKIP() << "built without VLFeat";
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  const std::filesystem::path path = data / "query_images" / "0007.jpg";
  GreyImage image = DecodeGreyImage(ReadPhotoFile(path), path);
  const ImageSize size = ExtractionSize(image.width, image.height, 480);
  image = ResizeBilinear(image, size.width, size.height);
  for (const int cap : {100, 600, 1000, 8192}) {  // octave -1: none, level 2, 1-2, all
    SCOPED_TRACE("cap " + std::to_string(cap));
    SiftOptions options;
    options.max_num_features = cap;
    ExpectOursEqualVlfeat(image, options);
  }
}

// The same photo gives the same features on every platform (a fused multiply-add or another
// summation order would move them): ours on a real photo, shrunk as COLMAP shrinks it. The
// hash was taken on x86-64, where ours equals VLFeat bit for bit.
TEST(SiftCwlocTest, SameFeaturesOnEveryPlatform) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  const std::filesystem::path path = data / "query_images" / "0002.jpg";
  GreyImage image = DecodeGreyImage(ReadPhotoFile(path), path);
  const ImageSize size = ExtractionSize(image.width, image.height, 640);
  image = ResizeBilinear(image, size.width, size.height);
  const SiftFeatures features = ExtractSift(image, SiftOptions{});
  std::vector<uint8_t> bytes = features.descriptors;
  const auto* keypoints = reinterpret_cast<const uint8_t*>(features.keypoints.data());
  bytes.insert(bytes.end(), keypoints, keypoints + features.size() * sizeof(SiftKeypoint));
  EXPECT_EQ(features.size(), 3727u);
  EXPECT_EQ(HashHex(XxHash64(bytes)), HashHex(0xadc72d0fc82e8908ULL));
}

INSTANTIATE_TEST_SUITE_P(All, SiftImplementationTest, testing::ValuesIn(Implementations()));

}  // namespace
}  // namespace cwloc
