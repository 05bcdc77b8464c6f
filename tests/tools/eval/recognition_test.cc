#include "tools/eval/recognition.h"

#include <gmock/gmock.h>

#include <fstream>

#include "base/error.h"
#include "colmap/reconstruction_io.h"
#include "tests/test_util.h"

namespace cwloc::eval {
namespace {

QueryResult Ranked(const std::string& name, std::vector<uint32_t> ids) {
  QueryResult result;
  result.name = name;
  result.ranked_image_ids = std::move(ids);
  return result;
}

TEST(Recognition, TopKCountsARightImageAmongTheFirstK) {
  RunResults run;
  run.queries = {Ranked("a", {5, 3, 9}), Ranked("c", {1}), Ranked("d", {8, 7, 6, 5, 4, 3})};
  RecognitionTruth truth;
  truth.right_images = {{"a", {3}}, {"b", {1}}, {"c", {}}, {"d", {3}}};
  const RecognitionScores scores = ScoreRecognition(run, {"a", "b", "c", "d"}, truth);
  EXPECT_EQ(scores.queries, 4);
  EXPECT_EQ(scores.with_right_image, 3);  // c has none; b has one but no result
  // a: rank 2; d: rank 6; b: missing.
  EXPECT_EQ(scores.hits, (std::array<int, 4>{0, 1, 1, 2}));
}

TEST(Recognition, RightImagesShareAtLeastMinSharedPointsWithTheQuery) {
  colmap::Reconstruction model;
  model.cameras[1] = {1, CameraModelId::kSimplePinhole, 100, 100, {100, 50, 50}};
  for (image_t id : {1u, 2u})
    model.images[id] = {id, 1, "img" + std::to_string(id) + ".jpg", {}, {}};
  for (point3D_t p = 1; p <= 15; ++p) {
    colmap::Point3D point;
    point.point3D_id = p;
    for (image_t id : {1u, 2u}) {
      if (id == 2 && p > 5) continue;  // image 2 sees only points 1..5
      point.track.push_back({id, static_cast<point2D_t>(model.images[id].points2D.size())});
      model.images[id].points2D.push_back({1.0, 1.0, p});
    }
    model.points3D[p] = point;
  }
  cwloc::test::TempDir dir;
  colmap::WriteReconstruction(model, dir.path(), colmap::ModelFormat::kBinary);
  std::map<std::string, std::vector<uint64_t>> seen = {{"q", {}}, {"far", {1, 2, 3}}};
  for (uint64_t p = 1; p <= 15; ++p) seen["q"].push_back(p);
  seen["q"].push_back(999);  // not in the mapping model: ignored
  const RecognitionTruth truth = MakeRecognitionTruth(dir.path(), seen, 12);
  EXPECT_EQ(truth.right_images.at("q"), (std::set<uint32_t>{1}));
  EXPECT_TRUE(truth.right_images.at("far").empty());
  EXPECT_EQ(MakeRecognitionTruth(dir.path(), seen, 5).right_images.at("q"),
            (std::set<uint32_t>{1, 2}));
}

TEST(Recognition, QueryPointsFileErrorsNameTheLine) {
  cwloc::test::TempDir dir;
  const auto path = dir / "points.txt";
  std::ofstream(path) << "# comment\nq1 1 2 3\nq2 4 x\n";
  try {
    ReadQueryPoints(path);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), path.string() + ":3: expected NAME POINT3D_ID..., got 'x'");
  }
  std::ofstream(path) << "q1 1 2 3\nq2\n";
  const auto points = ReadQueryPoints(path);
  EXPECT_EQ(points.at("q1"), (std::vector<uint64_t>{1, 2, 3}));
  EXPECT_TRUE(points.at("q2").empty());
}

TEST(Recognition, HerzJesuQueriesHaveRightImagesFromTheFullModel) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  const std::vector<std::string> names = {"0002.jpg", "0007.jpg", "0012.jpg", "0017.jpg",
                                          "0022.jpg"};
  const auto seen = QueryPointsFromModel(data / "full_model" / "bin", names);
  // README.txt: 2581 / 4347 / 2074 / 4375 / 2806 observations per query.
  EXPECT_EQ(seen.at("0002.jpg").size(), 2581u);
  EXPECT_EQ(seen.at("0017.jpg").size(), 4375u);
  const RecognitionTruth truth = MakeRecognitionTruth(data / "mapping_model" / "bin", seen, 12);
  for (const std::string& name : names) EXPECT_FALSE(truth.right_images.at(name).empty()) << name;
}

}  // namespace
}  // namespace cwloc::eval

namespace cwloc::eval {
namespace {

TEST(RecognitionCli, ModelWithoutQueryPointsIsAUsageError) {
  cwloc::test::TempDir dir;
  std::ofstream(dir / "gt.txt") << "q 1 0 0 0 0 0 0\n";
  std::ofstream(dir / "poses.txt") << "q 1 0 0 0 0 0 0\n";
  std::string output;
  EXPECT_EQ(
      cwloc::test::RunCommand(cwloc::test::ToolPath("cwloc-eval").string() + " --results " +
                                  (dir / "poses.txt").string() + " --gt " +
                                  (dir / "gt.txt").string() + " --model " + dir.path().string(),
                              &output),
      2);
  EXPECT_THAT(output, testing::HasSubstr(
                          "--model needs --gt-points or --gt-model to know what each query sees"));
}

}  // namespace
}  // namespace cwloc::eval
