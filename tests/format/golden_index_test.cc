// Files of format 1.x keep opening (docs/format.md). Each golden file was written by its format
// version's writer and is never regenerated (tests/data/README.md): today's reader must open it,
// pass every checksum and index check, read its exact header version and counts, and
// cwloc-localize must still localize the queries stored with it near their ground truth. Poses
// are compared with a tolerance, not bit for bit: the localizer may change, the file may not.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <ostream>
#include <set>
#include <string>

#include "format/index.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

struct GoldenIndex {
  std::string name;     // test name suffix
  std::string file;     // under tests/data/golden
  std::string queries;  // folder there: NAME.txt feature files, queries_gt.txt, scale_to_metres.txt
  uint16_t format_major = 0;
  uint16_t format_minor = 0;
  size_t cameras = 0, images = 0, points = 0, views = 0, clusters = 0;
  size_t covisibility_edges = 0, kd_trees = 0;
  size_t keypoints = 0;         // rows of the optional VKXY section
  uint32_t georef_inliers = 0;  // of the optional GEOR section (format 1.1); 0: none
  uint32_t code_bytes = 0;      // a compact index's point codes (format 1.2); 0: DESC
  size_t num_queries = 0;
  double max_position_m = 0, max_rotation_deg = 0;
};

// A new format version appends a row and its files; rows are never removed.
const GoldenIndex kGoldenIndexes[] = {
    // Measured at 42010ac with the 4 stored queries: worst position error 0.043 m, worst
    // rotation error 0.135 deg (the same as from the generating database); bounds about 5x.
    {.name = "Format1_0",
     .file = "index-1.0.cwl",
     .queries = "index-1.0-queries",
     .format_major = 1,
     .format_minor = 0,
     .cameras = 1,
     .images = 26,
     .points = 718,
     .views = 1707,
     .clusters = 8,
     .covisibility_edges = 76,
     .kd_trees = 4,
     .keypoints = 1707,
     .num_queries = 4,
     .max_position_m = 0.25,
     .max_rotation_deg = 0.7},
    // Format 1.1 adds the optional GEOR section: the same city placed at 47.3779 N, 8.5403 E
    // (its model in a random similarity frame), fit to GPS with 3 m noise and 3 of 26 wild.
    {.name = "Format1_1",
     .file = "index-1.1.cwl",
     .queries = "index-1.1-queries",
     .format_major = 1,
     .format_minor = 1,
     .cameras = 1,
     .images = 26,
     .points = 718,
     .views = 1707,
     .clusters = 8,
     .covisibility_edges = 76,
     .kd_trees = 4,
     .keypoints = 1707,
     .georef_inliers = 23,
     .num_queries = 4,
     .max_position_m = 0.25,
     .max_rotation_deg = 0.7},
    // Format 1.2 adds the compact index (PQCB, PCOD, PVNN, PORG, PNTF in place of DESC, VNND
    // and PNTS): the 1.0 city built with --compact, localizing the 1.0 queries.
    {.name = "Format1_2",
     .file = "index-1.2.cwl",
     .queries = "index-1.0-queries",
     .format_major = 1,
     .format_minor = 2,
     .cameras = 1,
     .images = 26,
     .points = 718,
     .views = 1707,
     .clusters = 8,
     .covisibility_edges = 76,
     .kd_trees = 2,
     .keypoints = 1707,
     .code_bytes = 32,
     .num_queries = 4,
     .max_position_m = 0.25,
     .max_rotation_deg = 0.7},
};

// Failure messages name the file instead of dumping the struct's bytes.
void PrintTo(const GoldenIndex& golden, std::ostream* os) { *os << golden.file; }

class GoldenIndexTest : public testing::TestWithParam<GoldenIndex> {};

TEST_P(GoldenIndexTest, OpensValidatesAndHasTheExactVersionAndCounts) {
  const GoldenIndex& golden = GetParam();
  const Index index = Index::Open(test::GoldenDir() / golden.file);
  const FileHeader& header = index.file().header();
  EXPECT_EQ(header.format_major, golden.format_major);
  EXPECT_EQ(header.format_minor, golden.format_minor);
  EXPECT_NO_THROW(index.file().VerifyChecksums());
  EXPECT_NO_THROW(index.Validate());

  EXPECT_EQ(index.cameras().size(), golden.cameras);
  EXPECT_EQ(index.images().size(), golden.images);
  EXPECT_EQ(index.num_points(), golden.points);
  EXPECT_EQ(index.num_views(), golden.views);
  EXPECT_EQ(index.coded(), golden.code_bytes != 0);
  if (golden.code_bytes == 0) {
    EXPECT_EQ(index.descriptors().size(), golden.views * kDescriptorBytes);
    EXPECT_EQ(index.view_neighbor_distances().size(), golden.views);
  } else {
    EXPECT_EQ(index.codes().code_bytes, golden.code_bytes);
    EXPECT_EQ(index.codes().NumRows(), golden.points);
    EXPECT_EQ(index.point_neighbor_distances().size(), golden.points);
    EXPECT_EQ(index.kd_forest().NumDescriptors(), golden.points);
  }
  EXPECT_EQ(index.view_keypoints().size(), golden.keypoints);
  EXPECT_EQ(index.covisibility_edges().size(), golden.covisibility_edges);
  EXPECT_EQ(index.kd_forest().NumTrees(), golden.kd_trees);
  if (golden.georef_inliers == 0) {
    EXPECT_EQ(index.georeference(), nullptr);
  } else {
    ASSERT_NE(index.georeference(), nullptr);
    EXPECT_EQ(index.georeference()->num_inliers, golden.georef_inliers);
  }
  std::set<uint32_t> clusters;
  for (const IndexImage& image : index.images()) clusters.insert(image.cluster);
  EXPECT_EQ(clusters.size(), golden.clusters);

  // The manifest agrees with the header and the sections.
  const auto manifest = nlohmann::json::parse(index.manifest_json());
  EXPECT_EQ(manifest.at("format_version"),
            std::to_string(golden.format_major) + "." + std::to_string(golden.format_minor));
  EXPECT_EQ(manifest.at("counts").at("views"), golden.views);
  EXPECT_EQ(manifest.at("counts").at("clusters"), golden.clusters);
}

TEST_P(GoldenIndexTest, LocalizesItsStoredQueriesNearTheirGroundTruth) {
  const GoldenIndex& golden = GetParam();
  const auto queries = test::GoldenDir() / golden.queries;
  const auto truth = test::ReadGroundTruth(queries / "queries_gt.txt");
  const double metres_per_unit = test::ReadMetresPerUnit(queries / "scale_to_metres.txt");
  ASSERT_EQ(truth.size(), golden.num_queries);
  test::TempDir dir;
  for (const auto& [name, query] : truth) {
    SCOPED_TRACE(name);
    const auto results = dir / (name + ".jsonl");
    std::string output;
    // Exit 0: localized. One run per query, each with its own camera.
    EXPECT_EQ(test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " +
                                   (test::GoldenDir() / golden.file).string() + " --features " +
                                   (queries / (name + ".txt")).string() + " --camera \"" +
                                   query.camera + "\" -o " + results.string(),
                               &output),
              0)
        << output;
    const auto lines = test::ReadJsonLines(results);
    ASSERT_EQ(lines.size(), 1u) << output;
    const auto& result = lines[0];
    EXPECT_EQ(result.at("name"), name + ".txt");
    ASSERT_TRUE(result.value("success", false)) << result.dump();
    const test::PoseError error =
        test::ErrorOf(test::PoseOfResult(result), query.pose, metres_per_unit);
    EXPECT_LT(error.position_m, golden.max_position_m);
    EXPECT_LT(error.rotation_deg, golden.max_rotation_deg);
  }
}

std::string TestName(const testing::TestParamInfo<GoldenIndex>& golden) {
  return golden.param.name;
}

INSTANTIATE_TEST_SUITE_P(EveryFormatVersion, GoldenIndexTest, testing::ValuesIn(kGoldenIndexes),
                         TestName);

}  // namespace
}  // namespace cwloc
