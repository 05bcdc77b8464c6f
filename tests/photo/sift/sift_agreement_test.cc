// Our SIFT against COLMAP 3.8's on the team's real photos (../shared/data/herz_jesu_p25,
// whose database.db holds the features COLMAP 3.8 extracted with max_num_features 6000).
#include <gtest/gtest.h>

#include <string>

#include "photo/sift/sift_extractor.h"
#include "tests/photo/sift/sift_agreement_util.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

constexpr const char* kDataset = "herz_jesu_p25";
const char* const kQueries[] = {"0002.jpg", "0007.jpg", "0012.jpg", "0017.jpg", "0022.jpg"};

// VLFeat called as COLMAP calls it: the very same features, in the same order.
TEST(SiftAgreementTest, VlfeatReproducesColmapExactly) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  SiftOptions options;
  options.max_num_features = 6000;
  options.implementation = SiftOptions::Implementation::kVlfeat;
  for (const char* name : kQueries) {
    SCOPED_TRACE(name);
    const SiftFeatures colmap = sift_bench::ReadColmapFeatures(data / "database.db", name);
    const SiftFeatures ours =
        ExtractSift(sift_bench::DecodeJpegLikeColmap(data / "query_images" / name), options);
    ASSERT_EQ(ours.size(), colmap.size());
    EXPECT_EQ(ours.descriptors, colmap.descriptors);
    size_t off = 0;
    for (size_t i = 0; i < ours.size(); ++i) {
      const SiftKeypoint& a = ours.keypoints[i];
      const SiftKeypoint& b = colmap.keypoints[i];
      // COLMAP stores the affine shape; scale and angle come back within float rounding.
      if (a.x != b.x || a.y != b.y || std::abs(a.scale - b.scale) > 1e-4f * b.scale) ++off;
    }
    EXPECT_EQ(off, 0u);
  }
}

}  // namespace
}  // namespace cwloc
