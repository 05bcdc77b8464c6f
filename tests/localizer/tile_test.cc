// `cwloc-index extract` end to end (docs/cli.md, docs/algorithm.md "Tiles"): a tile of a
// georeferenced generated city, full and compact, holds exactly the parent's data for its
// clusters and localizes its queries as the whole index does with the same position prior.
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "format/index.h"
#include "tests/localization_check.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// 20 m south of the city centre, 25 m around: about a third of the demo city's cameras.
constexpr char kRegion[] = "47.37772 8.5403 25";

class TileTest : public testing::TestWithParam<bool> {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    fixture_ = new std::filesystem::path(test::SharedFixture("tile_city", [](const auto& out) {
      std::string output;
      const auto city = out / "city";
      ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-synth").string() +
                                     " --preset demo --seed 3 --threads 2"
                                     " --geo '47.3779 8.5403 455' -o " +
                                     city.string(),
                                 &output),
                0)
          << output;
      for (const bool compact : {false, true}) {
        ASSERT_EQ(Index("build --model " + (city / "mapping_model" / "bin").string() +
                            " --database " + (city / "database.db").string() + " --georef " +
                            (city / "georef.txt").string() +
                            // The full parent's PCAL must reach its tiles; the compact
                            // calibration would train codes per fold.
                            (compact ? " --compact --calibration-samples 0" : "") + " -o " +
                            (out / (compact ? "compact.cwl" : "full.cwl")).string(),
                        &output),
                  0)
            << output;
      }
    }));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
    delete fixture_;
    fixture_ = nullptr;
  }

  // The city and its indexes, shared by the suite's processes: read only.
  static std::filesystem::path City() { return *fixture_ / "city"; }
  static std::filesystem::path Whole(bool compact) {
    return *fixture_ / (compact ? "compact.cwl" : "full.cwl");
  }
  static int Index(const std::string& arguments, std::string* output) {
    return test::RunCommand(test::ToolPath("cwloc-index").string() + " " + arguments, output);
  }
  // cwloc-localize on the database queries in `list`; the JSON lines.
  static std::vector<nlohmann::json> Localize(const std::filesystem::path& index,
                                              const std::filesystem::path& list,
                                              const std::string& extra) {
    const auto results = *dir_ / "results.jsonl";
    std::string output;
    test::RunCommand(test::ToolPath("cwloc-localize").string() + " --index " + index.string() +
                         " --database " + (City() / "database.db").string() + " --query-list " +
                         list.string() + " --threads 1 -q " + extra + " -o " + results.string(),
                     &output);
    return test::ReadJsonLines(results);
  }
  static std::vector<std::string> SectionChecksums(const std::filesystem::path& index) {
    std::string output;
    EXPECT_EQ(Index("info --json " + index.string(), &output), 0) << output;
    const auto info = nlohmann::json::parse(output);
    std::vector<std::string> checksums;
    for (const auto& section : info["sections"])
      checksums.push_back(section["tag"].get<std::string>() + " " +
                          section["checksum"].get<std::string>());
    return checksums;
  }

  static inline test::TempDir* dir_ = nullptr;  // this process's scratch
  static inline std::filesystem::path* fixture_ = nullptr;
};

TEST_P(TileTest, ATileOfEveryClusterHoldsTheParentsSectionsBitForBit) {
  const bool compact = GetParam();
  const auto tile = *dir_ / "everything.cwl";
  std::string output;
  ASSERT_EQ(Index("extract --index " + Whole(compact).string() +
                      " --near '47.3779 8.5403 10000' -o " + tile.string(),
                  &output),
            0)
      << output;
  std::vector<std::string> parent = SectionChecksums(Whole(compact));
  std::vector<std::string> copy = SectionChecksums(tile);
  ASSERT_EQ(parent.size(), copy.size());
  ASSERT_GE(parent.size(), 15u);
  // The manifest says where the tile came from.
  const auto manifest = std::find_if(parent.begin(), parent.end(), [](const std::string& section) {
    return section.starts_with("MANI ");
  });
  ASSERT_NE(manifest, parent.end());
  const size_t manifest_at = size_t(manifest - parent.begin());
  EXPECT_NE(parent[manifest_at], copy[manifest_at]);
  parent.erase(parent.begin() + manifest_at);
  copy.erase(copy.begin() + manifest_at);
  EXPECT_EQ(parent, copy);
  // The full parent is calibrated: its PCAL is among the copied sections.
  EXPECT_EQ(std::count_if(copy.begin(), copy.end(),
                          [](const std::string& section) { return section.starts_with("PCAL "); }),
            compact ? 0 : 1);
}

TEST_P(TileTest, ATileLocalizesItsQueriesAsTheWholeIndexWithTheSamePrior) {
  const bool compact = GetParam();
  const auto tile = *dir_ / "tile.cwl";
  std::string output;
  ASSERT_EQ(Index("extract --index " + Whole(compact).string() + " --near '" + kRegion + "' -o " +
                      tile.string(),
                  &output),
            0)
      << output;
  ASSERT_EQ(Index("verify " + tile.string(), &output), 0) << output;
  const auto parent = cwloc::Index::Open(Whole(compact));
  const auto part = cwloc::Index::Open(tile);
  EXPECT_GT(part.images().size(), parent.images().size() / 5);
  EXPECT_LT(part.images().size(), parent.images().size() / 2);
  EXPECT_LT(part.file().header().file_size, parent.file().header().file_size / 2);

  // Every query; the ones whose cameras lie far outside the region fail in both.
  const auto list = City() / "queries_with_intrinsics.txt";
  const auto whole =
      Localize(Whole(compact), list, std::string("--prior-position '") + kRegion + "'");
  const auto alone = Localize(tile, list, "");
  ASSERT_EQ(whole.size(), alone.size());
  const double metres = test::ReadMetresPerUnit(City() / "scale_to_metres.txt");
  const auto truth = test::ReadGroundTruth(City() / "queries_gt.txt");
  int localized = 0, identical = 0;
  for (size_t i = 0; i < whole.size(); ++i) {
    SCOPED_TRACE(whole[i].dump() + "\n" + alone[i].dump());
    ASSERT_EQ(whole[i]["name"], alone[i]["name"]);
    ASSERT_EQ(whole[i]["success"], alone[i]["success"]);
    if (!whole[i]["success"].get<bool>()) continue;
    ++localized;
    identical += whole[i]["pose"] == alone[i]["pose"];
    // Only the kd-forest differs (docs/algorithm.md, "Tiles"): a few neighbours, and so a few
    // inliers, change; the poses stay within a fraction of their error.
    const test::PoseError between =
        test::ErrorOf(test::PoseOfResult(alone[i]), test::PoseOfResult(whole[i]), metres);
    EXPECT_LT(between.position_m, 0.03);
    EXPECT_LT(between.rotation_deg, 0.1);
    const test::PoseError error =
        test::ErrorOf(test::PoseOfResult(alone[i]), truth.at(alone[i]["name"]).pose, metres);
    EXPECT_LT(error.position_m, 0.1);
    EXPECT_LT(error.rotation_deg, 0.5);
  }
  std::cout << localized << " of " << whole.size() << " queries localized in both, " << identical
            << " with bit-identical poses\n";
  EXPECT_GE(localized, 6);
}

TEST_P(TileTest, ATileOfListedImagesHoldsTheirClusters) {
  const bool compact = GetParam();
  const auto list = *dir_ / "images.txt";
  std::ofstream(list) << "# two images\nmap_000010.jpg\n\n  map_000042.jpg \n";
  const auto tile = *dir_ / "listed.cwl";
  std::string output;
  ASSERT_EQ(Index("extract --index " + Whole(compact).string() + " --images " + list.string() +
                      " -o " + tile.string() + " --json",
                  &output),
            0)
      << output;
  const auto report = nlohmann::json::parse(output);
  EXPECT_EQ(report["counts"]["images"], 2);
  EXPECT_EQ(report["counts"]["clusters"], 2);  // one cluster per image, the default
  const auto part = cwloc::Index::Open(tile);
  part.Validate();
  ASSERT_EQ(part.images().size(), 2u);
  EXPECT_EQ(part.ImageName(part.images()[0]), "map_000010.jpg");
  EXPECT_EQ(part.ImageName(part.images()[1]), "map_000042.jpg");
  EXPECT_EQ(report["counts"]["views"], part.images()[0].num_views + part.images()[1].num_views);
  const auto manifest = nlohmann::json::parse(part.manifest_json());
  EXPECT_EQ(manifest["extracted"]["region"]["images"], list.string());
  EXPECT_EQ(manifest["counts"]["images"], 2);
  ASSERT_EQ(Index("info " + tile.string(), &output), 0) << output;
  const size_t parent_images = cwloc::Index::Open(Whole(compact)).images().size();
  EXPECT_NE(output.find("\n  a tile of " + Whole(compact).string() + " (" +
                        std::to_string(parent_images) + " images): the clusters of the images in " +
                        list.string() + "\n"),
            std::string::npos)
      << output;
  ASSERT_EQ(Index("info --json " + tile.string(), &output), 0) << output;
  std::ofstream(*dir_ / "info.json") << output;
  EXPECT_EQ(test::ValidateJson("index-info.schema.json", *dir_ / "info.json", false, &output), 0)
      << output;
}

// A city without a georeference, indexed with 12 spectral clusters.
class ClusteredTileTest : public testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    fixture_ = new std::filesystem::path(test::SharedFixture("clustered_city", [](const auto& out) {
      std::string output;
      ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-synth").string() +
                                     " --preset demo --seed 4 -o " + (out / "city").string(),
                                 &output),
                0)
          << output;
      ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " build --model " +
                                     (out / "city" / "mapping_model" / "bin").string() +
                                     " --database " + (out / "city" / "database.db").string() +
                                     " --clusters 12 --calibration-samples 0 -o " +
                                     (out / "clustered.cwl").string(),
                                 &output),
                0)
          << output;
    }));
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
    delete fixture_;
    fixture_ = nullptr;
  }
  static std::filesystem::path City() { return *fixture_ / "city"; }  // read only
  static std::filesystem::path Whole() { return *fixture_ / "clustered.cwl"; }

  static inline test::TempDir* dir_ = nullptr;  // this process's scratch
  static inline std::filesystem::path* fixture_ = nullptr;
};

TEST_F(ClusteredTileTest, AListedImageBringsItsWholeCluster) {
  const test::TempDir& dir = *dir_;  // the suite's
  const auto whole = Whole();
  std::string output;
  std::ofstream(dir / "one.txt") << "map_000010.jpg\n";
  const auto tile = dir / "tile.cwl";
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " extract --index " +
                                 whole.string() + " --images " + (dir / "one.txt").string() +
                                 " -o " + tile.string(),
                             &output),
            0)
      << output;
  const auto parent = cwloc::Index::Open(whole);
  uint32_t cluster = UINT32_MAX;
  for (const IndexImage& image : parent.images()) {
    if (parent.ImageName(image) == "map_000010.jpg") cluster = image.cluster;
  }
  std::vector<std::string> expected, kept;
  for (const IndexImage& image : parent.images()) {
    if (image.cluster == cluster) expected.emplace_back(parent.ImageName(image));
  }
  const auto part = cwloc::Index::Open(tile);
  for (const IndexImage& image : part.images()) {
    kept.emplace_back(part.ImageName(image));
    EXPECT_EQ(image.cluster, 0u);
  }
  EXPECT_GT(expected.size(), 1u);
  EXPECT_EQ(kept, expected);
}

TEST_P(TileTest, BadRegionsListsAndOutputsAreRefusedAndWriteNothing) {
  const bool compact = GetParam();
  const std::string whole = Whole(compact).string();
  const auto tile = *dir_ / "refused.cwl";
  const auto list = *dir_ / "unknown.txt";
  std::ofstream(list) << "map_000010.jpg\nnot_in_the_model.jpg\n";
  const auto empty_list = *dir_ / "empty.txt";
  std::ofstream(empty_list) << "# nothing\n";
  const std::pair<std::string, std::string> cases[] = {
      {"--near '47.5 8.5403 100'",
       whole + ": no camera lies within 100 m of 47.5, 8.5403; nothing to extract"},
      {"--near '47.5 8.5403'", "--near '47.5 8.5403': expected 'LAT LON [HEIGHT] RADIUS_M'"},
      {"--near '91 8.5403 100'", "--near: latitude 91.000000 is outside [-90, 90]"},
      {"--images " + list.string(),
       list.string() + ":2: image 'not_in_the_model.jpg' is not in " + whole},
      {"--images " + empty_list.string(), empty_list.string() + ": no image names"},
  };
  for (const auto& [arguments, message] : cases) {
    SCOPED_TRACE(arguments);
    std::string output;
    EXPECT_EQ(Index("extract --index " + whole + " " + arguments + " -o " + tile.string(), &output),
              2);
    EXPECT_EQ(output, "cwloc-index: error: " + message + "\n");
    EXPECT_FALSE(std::filesystem::exists(tile));
  }
  std::string output;
  EXPECT_EQ(Index("extract --index " + whole + " --near '" + kRegion + "' -o " + whole, &output),
            2);
  EXPECT_EQ(output,
            "cwloc-index: error: " + whole +
                ": the output is the index being extracted from; write the tile elsewhere\n");
  EXPECT_NE(Index("extract --index " + whole + " -o " + tile.string(), &output), 0);
  EXPECT_FALSE(std::filesystem::exists(tile));

  // A parent with a flipped byte is refused before anything is cut from it.
  std::vector<uint8_t> bytes = test::ReadBytes(Whole(compact));
  const auto parent = cwloc::Index::Open(Whole(compact));
  const SectionEntry& tracks = *parent.file().FindSection(section::kTracks);
  bytes[tracks.offset + tracks.size / 2] ^= 0x10;
  const auto corrupt = *dir_ / "corrupt.cwl";
  test::WriteBytes(corrupt, bytes);
  EXPECT_EQ(
      Index("extract --index " + corrupt.string() + " --near '" + kRegion + "' -o " + tile.string(),
            &output),
      2);
  // The rows first: DESC and PNTS, or a compact index's PORG and PNTF.
  const std::string number = "2";
  EXPECT_EQ(output.substr(0, output.find(" (stored")), "cwloc-index: error: " + corrupt.string() +
                                                           ": section " + number +
                                                           " 'TRKS': checksum mismatch");
  EXPECT_FALSE(std::filesystem::exists(tile));
}

TEST_F(ClusteredTileTest, NearNeedsAGeoreferencedIndex) {
  const auto plain = Whole();
  std::string output;
  EXPECT_EQ(test::RunCommand(test::ToolPath("cwloc-index").string() + " extract --index " +
                                 plain.string() + " --near '47.3779 8.5403 25' -o " +
                                 (*dir_ / "tile.cwl").string(),
                             &output),
            2);
  EXPECT_EQ(output, "cwloc-index: error: " + plain.string() +
                        ": --near needs a georeferenced index (cwloc-index build --georef, "
                        "--georef-images or --model-frame)\n");
}

INSTANTIATE_TEST_SUITE_P(FullAndCompact, TileTest, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& param_info) {
                           return param_info.param ? "Compact" : "Full";
                         });

}  // namespace
}  // namespace cwloc
