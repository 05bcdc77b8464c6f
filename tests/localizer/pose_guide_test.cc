#include "localizer/pose_guide.h"

#include <gtest/gtest.h>

#include <optional>
#include <vector>

#include "tests/localizer/matching_fixture.h"

namespace cwloc {
namespace {

// A 1000 x 1000 pinhole camera 10 units in front of the scene's [-2, 2]^3 points, looking at
// them: every point projects into [375, 625]^2.
class PoseGuideTest : public test::MatchingFixture {
 protected:
  static constexpr double kRadius = 20;

  void SetUp() override {
    MatchingFixture::SetUp();
    hypothesis_.pose = CameraPose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 10));
    hypothesis_.model_id = CameraModelId::kSimplePinhole;
    hypothesis_.params = {500, 500, 500};
    query_.camera.width = query_.camera.height = 1000;
    // Clutter: random descriptors all over the image.
    for (int i = 0; i < 400; ++i) {
      const uint32_t f = AddFeature(&query_, RandomDescriptor());
      query_.keypoints[2 * f] = float(test::Rng()() % 1000);
      query_.keypoints[2 * f + 1] = float(test::Rng()() % 1000);
    }
  }

  std::array<double, 2> Projection(uint32_t view) const {
    const double* xyz = index_->points()[index_->view_points()[view]].xyz;
    return {500 + 500 * xyz[0] / (xyz[2] + 10), 500 + 500 * xyz[1] / (xyz[2] + 10)};
  }

  // A copy of the view's descriptor, `bump` added to its first byte, at its projection plus
  // (dx, dy).
  uint32_t AddCopy(uint32_t view, double dx, double dy, uint8_t bump = 0) {
    Descriptor descriptor = ViewDescriptor(view);
    descriptor[0] = uint8_t(descriptor[0] + bump);
    const uint32_t f = AddFeature(&query_, descriptor);
    const std::array<double, 2> pixel = Projection(view);
    query_.keypoints[2 * f] = float(pixel[0] + dx);
    query_.keypoints[2 * f + 1] = float(pixel[1] + dy);
    return f;
  }

  const IndexImage& Image() const { return index_->images()[0]; }

  PoseHypothesis hypothesis_;
  Query query_;
};

TEST_F(PoseGuideTest, FindsEachViewsCopyNearItsProjection) {
  std::vector<uint32_t> copies;
  for (uint32_t j = 0; j < Image().num_views; ++j)
    copies.push_back(AddCopy(Image().first_view + j, 3, -4));
  PoseGuide guide(query_, hypothesis_, kRadius);
  for (uint32_t j = 0; j < Image().num_views; ++j) {
    const std::optional<FeatureMatch> match = guide.Match(*index_, Image().first_view + j, 0.7);
    ASSERT_TRUE(match.has_value()) << "view " << j;
    EXPECT_EQ(match->feature, copies[j]);
    EXPECT_EQ(match->view, Image().first_view + j);
    EXPECT_EQ(match->distance, 0.0f);
  }
}

TEST_F(PoseGuideTest, IgnoresCopiesBeyondTheRadius) {
  const uint32_t view = Image().first_view;
  AddCopy(view, kRadius + 5, 0);
  PoseGuide guide(query_, hypothesis_, kRadius);
  EXPECT_FALSE(guide.Match(*index_, view, 0.7).has_value());
}

// A copy far away would make the full search's ratio test fail (it is nearer than the near
// one); guided, it is not a competitor.
TEST_F(PoseGuideTest, AFarDuplicateDoesNotCompete) {
  const uint32_t view = Image().first_view;
  const uint32_t near = AddCopy(view, 0, 0, 3);  // squared distance 9 from the view
  const std::array<double, 2> pixel = Projection(view);
  const uint32_t far = AddFeature(&query_, ViewDescriptor(view));
  query_.keypoints[2 * far] = float(pixel[0] > 500 ? 50 : 950);
  query_.keypoints[2 * far + 1] = float(pixel[1]);
  PoseGuide guide(query_, hypothesis_, kRadius);
  const std::optional<FeatureMatch> match = guide.Match(*index_, view, 0.7);
  ASSERT_TRUE(match.has_value());
  EXPECT_EQ(match->feature, near);
  // A similar feature beside it competes: 9 against 16 fails the ratio test (9 > 0.49 * 16).
  AddCopy(view, 2, 2, 4);
  PoseGuide crowded(query_, hypothesis_, kRadius);
  EXPECT_FALSE(crowded.Match(*index_, view, 0.7).has_value());
}

TEST_F(PoseGuideTest, SkipsPointsBehindTheCameraOrOutsideTheImage) {
  for (uint32_t j = 0; j < Image().num_views; ++j) AddCopy(Image().first_view + j, 0, 0);
  PoseHypothesis behind = hypothesis_;
  behind.pose.translation.z() = -10;  // the scene is behind the camera
  PoseGuide guide_behind(query_, behind, kRadius);
  PoseHypothesis aside = hypothesis_;
  aside.pose.translation.x() = 20;  // the scene projects 1000 px to the right, off the image
  PoseGuide guide_aside(query_, aside, kRadius);
  for (uint32_t j = 0; j < Image().num_views; ++j) {
    EXPECT_FALSE(guide_behind.Match(*index_, Image().first_view + j, 0.7).has_value());
    EXPECT_FALSE(guide_aside.Match(*index_, Image().first_view + j, 0.7).has_value());
  }
}

}  // namespace
}  // namespace cwloc
