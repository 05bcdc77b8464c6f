#include <gmock/gmock.h>

#include <fstream>

#include "app/camera_spec.h"
#include "app/feature_file.h"
#include "app/option_table.h"
#include "app/photo_query.h"
#include "base/error.h"
#ifdef CWLOC_WITH_COLMAP_DB
#include "app/database/database_queries.h"
#include "colmap/database.h"
#endif
#include "tests/test_util.h"

namespace cwloc {
namespace {

using test::InputErrorOf;
using testing::HasSubstr;

TEST(CameraSpec, ParsesEveryFieldOfAColmapCameraLine) {
  const QueryCamera camera =
      ParseCameraSpec("SIMPLE_RADIAL 1536 1024 1375.77 768 512 -0.0008", "--camera");
  EXPECT_EQ(camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(camera.width, 1536u);
  EXPECT_EQ(camera.height, 1024u);
  EXPECT_EQ(camera.params, (std::vector<double>{1375.77, 768, 512, -0.0008}));
  EXPECT_EQ(camera.calibration, Calibration::kKnown);
}

TEST(CameraSpec, BadSpecsNameTheProblem) {
  EXPECT_EQ(InputErrorOf([] { ParseCameraSpec("PINHOLE 640 480 500 500 320", "--camera"); }),
            "--camera: PINHOLE takes 4 parameters, got 3");
  EXPECT_EQ(InputErrorOf([] { ParseCameraSpec("PINHOLE -640 480 500 500 320 240", "--camera"); }),
            "--camera: expected a positive image width (at most 1000000)");
  EXPECT_EQ(InputErrorOf([] { ParseCameraSpec("PINHOLE 640 480 500 abc 320 240", "--camera"); }),
            "--camera: camera parameters must be numbers");
  EXPECT_EQ(InputErrorOf([] { ParseCameraSpec("SIMPLE_PINHOLE 640 480 -5 320 240", "--camera"); }),
            "--camera: the focal length must be positive");
  EXPECT_THAT(InputErrorOf([] { ParseCameraSpec("", "--camera"); }), HasSubstr("empty camera"));
}

TEST(CameraSpec, ImageSizeMeansUnknownFocalWithCentredPrincipalPoint) {
  const QueryCamera camera = ParseImageSize("1536x1024", "--image-size");
  EXPECT_EQ(camera.calibration, Calibration::kUnknown);
  EXPECT_EQ(camera.width, 1536u);
  EXPECT_EQ(camera.params[1], 768.0);
  EXPECT_EQ(InputErrorOf([] { ParseImageSize("1536 1024 7", "--image-size"); }),
            "--image-size: expected 'WIDTH HEIGHT', got extra '7'");
}

class FeatureFileTest : public testing::Test {
 protected:
  std::string Write(const std::string& text) {
    const auto path = dir_ / "features.txt";
    std::ofstream(path) << text;
    return path.string();
  }
  static std::string Descriptor(int value) {
    std::string values;
    for (int i = 0; i < 128; ++i) {
      values += ' ';  // not " " + std::to_string(...): a GCC 12 -Wrestrict false positive
      values += std::to_string((value + i) % 256);
    }
    return values;
  }
  test::TempDir dir_;
};

// What only VLFeat computes is a usage error in a build without it (docs/devices.md).
TEST(PhotoOptions, VlfeatOnlySiftOptionsNeedVlfeat) {
  QueryOptions options;
  options.photo.sift.first_octave = -2;
  if (SiftVlfeatAvailable()) {
    EXPECT_NO_THROW(ValidateQueryOptions(options));
  } else {
    EXPECT_THAT(InputErrorOf([&] { ValidateQueryOptions(options); }),
                HasSubstr("first_octave must be >= -1"));
  }
}

TEST_F(FeatureFileTest, ReadsKeypointsAndDescriptors) {
  const std::string path =
      Write("2 128\n10.5 20.25 3.1 0.5" + Descriptor(0) + "\n1 2 1 0" + Descriptor(200) + "\n");
  Query query;
  ReadFeatureFile(path, &query);
  ASSERT_EQ(query.NumFeatures(), 2u);
  EXPECT_EQ(query.keypoints, (std::vector<float>{10.5f, 20.25f, 1, 2}));
  EXPECT_EQ(query.Descriptor(0)[5], 5);
  EXPECT_EQ(query.Descriptor(1)[100], (200 + 100) % 256);
}

TEST_F(FeatureFileTest, MalformedFilesNameTheLine) {
  Query query;
  std::string path = Write("2 64\n");
  EXPECT_EQ(InputErrorOf([&] { ReadFeatureFile(path, &query); }),
            path + ":1: descriptors have 64 dimensions, expected 128");
  path = Write("2 128\n1 2 3 4" + Descriptor(0) + "\n");
  EXPECT_EQ(InputErrorOf([&] { ReadFeatureFile(path, &query); }),
            path + ":3: file ends after 1 of 2 features");
  path = Write("1 128\n1 2 3 4 256" + Descriptor(0).substr(3) + "\n");
  EXPECT_EQ(InputErrorOf([&] { ReadFeatureFile(path, &query); }),
            path + ":2: descriptor value 1 is not an integer in 0..255");
  path = Write("1 128\n1 2 x 4" + Descriptor(0) + "\n");
  EXPECT_EQ(InputErrorOf([&] { ReadFeatureFile(path, &query); }),
            path + ":2: expected X Y SCALE ORIENTATION then 128 descriptor values");
  EXPECT_THAT(InputErrorOf([&] { ReadFeatureFile(dir_ / "none.txt", &query); }),
              HasSubstr("cannot open feature file"));
}

#ifdef CWLOC_WITH_COLMAP_DB
// A database camera with prior_focal_length = 0 (what COLMAP's extractor writes without EXIF,
// and what DatabaseWriter writes) holds the guess 1.2 * max(w, h): the query's focal length is
// unknown. (prior_focal_length = 1 gives a focal prior: sceaux_castle_test.cc.)
TEST(DatabaseQueries, CameraWithoutPriorFocalLengthIsUnknown) {
  test::TempDir dir;
  {
    colmap::DatabaseWriter writer(dir / "database.db");
    writer.WriteCamera({1, CameraModelId::kSimpleRadial, 1536, 1024, {1843.2, 768, 512, 0}});
    writer.WriteImage({1, "q.jpg", 1});
    writer.WriteKeypoints(1, {{10, 20}, {30, 40}});
    colmap::Descriptors descriptors;
    descriptors.rows = 2;
    descriptors.data.assign(2 * 128, 7);
    writer.WriteDescriptors(1, descriptors);
    writer.Commit();
  }
  const DatabaseQueries queries(dir / "database.db");
  const Query query = queries.Load("q.jpg");
  EXPECT_EQ(query.camera.calibration, Calibration::kUnknown);
  EXPECT_EQ(query.camera.source, IntrinsicsSource::kDatabase);
  EXPECT_EQ(query.camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(query.camera.params, (std::vector<double>{1843.2, 768, 512, 0}));
  EXPECT_EQ(query.NumFeatures(), 2u);
}
#endif

}  // namespace
}  // namespace cwloc
