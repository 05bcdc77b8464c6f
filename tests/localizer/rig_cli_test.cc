// cwloc-localize --frames and --rig on real photos: held-out photos of herz_jesu_p25 grouped
// into rig frames whose cam_from_rig comes from the full model's poses, localized as one
// generalized camera against the mapping model, and compared with COLMAP's poses.
#include <gtest/gtest.h>

#include <fstream>

#include "tests/localization_check.h"
#include "tests/shared_data_index.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

class RigCliTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    const auto shared = test::BuildSharedDataIndex("herz_jesu_p25");
    if (!shared) return;
    data_ = new test::SharedDataIndex(*shared);
  }
  static void TearDownTestSuite() {
    delete data_;
    data_ = nullptr;
  }
  void SetUp() override {
    if (data_ == nullptr) GTEST_SKIP() << "../shared/data/herz_jesu_p25 not found";
    truth_ = test::ReadGroundTruth(data_->data / "queries_gt.txt");
  }

  std::string CamFromRig(const std::string& image, const std::string& reference,
                         double scale = 1.0) const {
    return test::CamFromRigText(truth_.at(image).pose, truth_.at(reference).pose, scale);
  }

  // A --frames file of the groups, each image with its model camera; the first is the reference.
  std::filesystem::path FramesFile(const std::vector<std::vector<std::string>>& groups,
                                   double scale = 1.0) const {
    const std::filesystem::path path = dir_ / "frames.txt";
    std::ofstream out(path);
    for (size_t g = 0; g < groups.size(); ++g) {
      for (const std::string& image : groups[g]) {
        out << "frame" << g << " " << image << " " << CamFromRig(image, groups[g][0], scale) << " "
            << truth_.at(image).camera << "\n";
      }
    }
    return path;
  }

  int Localize(const std::string& args, std::string* output) const {
    return test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " +
                                data_->index.string() + " --database " +
                                (data_->data / "database.db").string() + " " + args,
                            output);
  }

  // The largest centre error (model units) and rotation error (degrees) of the poses of a rig
  // record's images against the ground truth.
  std::pair<double, double> ImageErrors(const nlohmann::json& record) const {
    double centre = 0, rotation = 0;
    for (const nlohmann::json& image : record.at("images")) {
      const test::CameraPose pose = test::PoseOfResult(image);
      const test::CameraPose& truth = truth_.at(image.at("name").get<std::string>()).pose;
      centre = std::max(centre, (pose.Center() - truth.Center()).norm());
      rotation = std::max(rotation, pose.rotation.angularDistance(truth.rotation) * 180 / M_PI);
    }
    return {centre, rotation};
  }

  static test::SharedDataIndex* data_;
  std::map<std::string, test::GroundTruthQuery> truth_;
  test::TempDir dir_;
};

test::SharedDataIndex* RigCliTest::data_ = nullptr;

// herz_jesu_p25's model is 2.77 m per unit: 1 mm is 3.6e-4 units.
constexpr double kRigMaxCentreError = 2e-3;
constexpr double kRigMaxRotationErrorDeg = 0.05;

TEST_F(RigCliTest, FramesOfHeldOutPhotosLocalizeAtColmapsPoses) {
  std::string output;
  const auto out = dir_ / "out.jsonl";
  const auto poses = dir_ / "poses.txt";
  ASSERT_EQ(
      Localize("--frames " +
                   FramesFile({{"0002.jpg", "0007.jpg"}, {"0012.jpg", "0017.jpg", "0022.jpg"}})
                       .string() +
                   " -o " + out.string() + " --poses " + poses.string(),
               &output),
      0)
      << output;
  EXPECT_EQ(test::ValidateJson("localization-result.schema.json", out, true, &output), 0) << output;
  const auto records = test::ReadJsonLines(out);
  ASSERT_EQ(records.size(), 2u);
  for (const nlohmann::json& record : records) {
    ASSERT_TRUE(record.at("success").get<bool>()) << record.dump();
    const auto [centre, rotation] = ImageErrors(record);
    EXPECT_LT(centre, kRigMaxCentreError) << record.at("name");
    EXPECT_LT(rotation, kRigMaxRotationErrorDeg) << record.at("name");
    // The frame's pose is its reference camera's; the rig's frame is the reference camera's.
    EXPECT_EQ(record.at("pose"), record.at("images").at(0).at("pose"));
    EXPECT_EQ(record.at("rig").at("reference_image"), record.at("images").at(0).at("name"));
    EXPECT_EQ(record.at("rig").at("scale"), 1.0);
    EXPECT_GT(record.at("rig").at("num_inliers").get<int>(), 1000);
    EXPECT_TRUE(record.contains("covariance"));
  }
  EXPECT_EQ(records[0].at("name"), "frame0");
  EXPECT_EQ(records[1].at("images").size(), 3u);
  // --poses: every image of every frame, as single photos.
  std::ifstream in(poses);
  int lines = 0;
  for (std::string line; std::getline(in, line);) ++lines;
  EXPECT_EQ(lines, 5);
}

// The translations of a VIO window are known up to scale: the rig estimates it.
TEST_F(RigCliTest, AnUnknownScaleIsEstimated) {
  std::string output;
  const auto out = dir_ / "out.jsonl";
  const std::string frames = FramesFile({{"0007.jpg", "0012.jpg", "0017.jpg"}}, 3.7).string();
  ASSERT_EQ(Localize("--frames " + frames + " --frames-scale unknown -o " + out.string(), &output),
            0)
      << output;
  const auto records = test::ReadJsonLines(out);
  ASSERT_EQ(records.size(), 1u);
  const nlohmann::json& rig = records[0].at("rig");
  EXPECT_TRUE(rig.at("unknown_scale").get<bool>());
  EXPECT_NEAR(rig.at("scale").get<double>() * 3.7, 1.0, 0.01);
  EXPECT_GT(rig.at("scale_std").get<double>(), 0.0);
  EXPECT_LT(ImageErrors(records[0]).first, kRigMaxCentreError);
}

// COLMAP's rig_config.json: camera A's images start with "000", camera B's with "001", so
// 0002.jpg and 0012.jpg are frame "2.jpg" (as rig_configurator would group them).
TEST_F(RigCliTest, ARigConfigGroupsImagesByPrefix) {
  std::ofstream(dir_ / "rig_config.json")
      << "[{\"cameras\": [{\"image_prefix\": \"000\", \"ref_sensor\": true}, "
         "{\"image_prefix\": \"001\", \"cam_from_rig_rotation\": [" +
             [&] {
               std::string pose = CamFromRig("0012.jpg", "0002.jpg");
               std::istringstream fields(pose);
               double v[7];
               for (double& x : v) fields >> x;
               char text[256];
               std::snprintf(text, sizeof(text),
                             "%.17g, %.17g, %.17g, %.17g], \"cam_from_rig_translation\": [%.17g, "
                             "%.17g, %.17g]",
                             v[0], v[1], v[2], v[3], v[4], v[5], v[6]);
               return std::string(text);
             }() +
             "}]}]\n";
  std::ofstream(dir_ / "list.txt") << "0012.jpg " << truth_.at("0012.jpg").camera << "\n0002.jpg "
                                   << truth_.at("0002.jpg").camera << "\n";
  std::string output;
  const auto out = dir_ / "out.jsonl";
  ASSERT_EQ(Localize("--rig " + (dir_ / "rig_config.json").string() + " --query-list " +
                         (dir_ / "list.txt").string() + " -o " + out.string(),
                     &output),
            0)
      << output;
  const auto records = test::ReadJsonLines(out);
  ASSERT_EQ(records.size(), 1u);
  EXPECT_EQ(records[0].at("name"), "2.jpg");
  ASSERT_TRUE(records[0].at("success").get<bool>());
  EXPECT_EQ(records[0].at("images").at(0).at("name"), "0002.jpg");  // the reference sensor first
  EXPECT_LT(ImageErrors(records[0]).first, kRigMaxCentreError);
}

TEST_F(RigCliTest, AnImageOutsideEveryRigIsRefusedBeforeAnyWork) {
  std::ofstream(dir_ / "rig_config.json")
      << R"([{"cameras": [{"image_prefix": "000", "ref_sensor": true}]}])";
  std::ofstream(dir_ / "list.txt") << "0002.jpg\n0012.jpg\n";
  std::string output;
  const auto out = dir_ / "out.jsonl";
  EXPECT_EQ(Localize("--rig " + (dir_ / "rig_config.json").string() + " --query-list " +
                         (dir_ / "list.txt").string() + " -o " + out.string(),
                     &output),
            2);
  EXPECT_NE(output.find("cwloc-localize: error: " + (dir_ / "list.txt").string() +
                        ": image '0012.jpg' matches no image_prefix of " +
                        (dir_ / "rig_config.json").string()),
            std::string::npos)
      << output;
  EXPECT_FALSE(std::filesystem::exists(out));
}

}  // namespace
}  // namespace cwloc
