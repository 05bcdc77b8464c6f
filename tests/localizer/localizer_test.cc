#include "localizer/localizer.h"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "base/error.h"
#include "tests/indexer/indexer_fixture.h"

namespace cwloc {
namespace {

// Localize checks every query once, whatever it was read from; each problem gets its own
// message naming the query's source.
class LocalizerQueryCheckTest : public test::IndexerFixture {
 protected:
  void SetUp() override {
    IndexerFixture::SetUp();
    BuildFixtureIndex();
    index_.emplace(Index::Open(index_path_));
    localizer_.emplace(*index_);
    query_.name = "q.jpg";
    query_.camera.model_id = CameraModelId::kPinhole;
    query_.camera.width = 640;
    query_.camera.height = 480;
    query_.camera.params = {500, 500, 320, 240};
    query_.keypoints = {10, 20, 30, 40};
    query_.descriptors.assign(2 * 128, 7);
  }

  // The InputError's message, or "" when Localize accepted the query.
  std::string Error(const Query& query) const {
    try {
      localizer_->Localize(query, LocalizerOptions{});
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  }

  std::optional<Index> index_;
  std::optional<Localizer> localizer_;
  Query query_;
};

TEST_F(LocalizerQueryCheckTest, AWellFormedQueryIsAccepted) { EXPECT_EQ(Error(query_), ""); }

TEST_F(LocalizerQueryCheckTest, DescriptorCountMustMatchTheKeypoints) {
  query_.descriptors.resize(128);
  EXPECT_EQ(Error(query_), "query 'q.jpg': keypoint and descriptor counts differ");
}

TEST_F(LocalizerQueryCheckTest, AQueryWithoutFeaturesNamesItsSource) {
  query_.keypoints.clear();
  query_.descriptors.clear();
  query_.source = "db.db: image 'q.jpg'";
  EXPECT_EQ(Error(query_), "db.db: image 'q.jpg': the query has no features");
}

TEST_F(LocalizerQueryCheckTest, TheCameraNeedsAnImageSize) {
  query_.camera.height = 0;
  EXPECT_EQ(Error(query_), "query 'q.jpg': camera has no image size");
}

TEST_F(LocalizerQueryCheckTest, AnUnknownCameraModelIsNamedById) {
  query_.camera.model_id = static_cast<CameraModelId>(99);
  EXPECT_EQ(Error(query_), "query 'q.jpg': unknown camera model id 99");
  // With the focal length unknown only the image size is used, so the model does not matter.
  query_.camera.calibration = Calibration::kUnknown;
  EXPECT_EQ(Error(query_), "");
}

TEST_F(LocalizerQueryCheckTest, TheParameterCountMustFitTheModel) {
  query_.camera.params.pop_back();
  EXPECT_EQ(Error(query_), "query 'q.jpg': PINHOLE takes 4 parameters, got 3");
}

}  // namespace
}  // namespace cwloc
