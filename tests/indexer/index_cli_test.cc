// cwloc-index as a user runs it: build, info (--json against its schema), verify, and the
// exit code and message for each kind of damaged file.
#include <gmock/gmock.h>
#include <sys/stat.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <nlohmann/json.hpp>
#include <regex>
#include <set>
#include <sstream>

#include "format/index.h"
#include "format/index_file.h"
#include "format/index_section_table.h"
#include "indexer/build_option_table.h"
#include "indexer/index_command_flags.h"
#include "kdtree/kd_forest_builder.h"
#include "tests/indexer/indexer_fixture.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

class IndexCliTest : public test::IndexerFixture {
 protected:
  int Run(const std::string& args, std::string* output) const {
    return test::RunCommand(test::ToolPath("cwloc-index").string() + " " + args, output);
  }

  void Build(const std::string& extra = "") {
    std::string output;
    ASSERT_EQ(Run("build --model " + model_dir_.string() + " --database " +
                      database_path_.string() + " -o " + index_path_.string() + extra,
                  &output),
              0)
        << output;
  }

  std::vector<uint8_t> Bytes() const { return test::ReadBytes(index_path_); }

  // `info --json` output against schemas/index-info.schema.json.
  void ExpectValidInfoJson(const std::string& output) const {
    std::ofstream(dir_ / "info.json") << output;
    std::string validation;
    EXPECT_EQ(test::ValidateJson("index-info.schema.json", dir_ / "info.json", false, &validation),
              0)
        << validation;
  }

  void WriteCorrupt(const std::vector<uint8_t>& bytes) const {
    test::WriteBytes(dir_ / "corrupt.cwl", bytes);
  }
};

// update and apply from the command line: the same model updates to an index with the update
// recorded (info --json against its schema), apply gives its bytes, a refusal exits 2 naming why.
TEST_F(IndexCliTest, UpdateAndApplyRecordTheUpdateAndRefuseWithExitCode2) {
  ASSERT_NO_FATAL_FAILURE(Build(" --calibration-samples 0"));
  const auto updated = dir_ / "updated.cwl", delta = dir_ / "updated.cwld";
  const std::string update = "update --index " + index_path_.string() + " --model " +
                             model_dir_.string() + " --database " + database_path_.string() +
                             " -o " + updated.string();
  std::string output;
  ASSERT_EQ(Run(update + " --delta " + delta.string(), &output), 0) << output;
  EXPECT_THAT(
      output,
      HasSubstr("wrote " + updated.string() +
                ": 10 images (+0, -0, 0 changed), 400 points (+0, -0, 0 moved, 0 re-coded)"));
  ASSERT_EQ(Run("info --json " + updated.string(), &output), 0) << output;
  ExpectValidInfoJson(output);
  const auto info = nlohmann::json::parse(output);
  EXPECT_EQ(info["manifest"]["update"]["updates"], 1);
  EXPECT_EQ(info["format_version"], "1.5");
  ASSERT_EQ(Run("apply --index " + index_path_.string() + " --delta " + delta.string() + " -o " +
                    (dir_ / "applied.cwl").string(),
                &output),
            0)
      << output;
  EXPECT_EQ(test::ReadBytes(dir_ / "applied.cwl"), test::ReadBytes(updated));

  EXPECT_EQ(Run(update + " --leaf-size 4", &output), 2);
  EXPECT_THAT(output, HasSubstr(index_path_.string() +
                                ": the index was built with --leaf-size 8, and this update asks "
                                "for --leaf-size 4: a full build is needed (cwloc-index build, "
                                "or update --rebuild-if-needed)"));
  EXPECT_EQ(Run("apply --index " + updated.string() + " --delta " + delta.string() + " -o " +
                    (dir_ / "wrong.cwl").string(),
                &output),
            2);
  EXPECT_THAT(output, HasSubstr(delta.string() + ": made for the index with checksum "));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "wrong.cwl"));
}

TEST_F(IndexCliTest, BuildInfoAndVerifySucceed) {
  ASSERT_NO_FATAL_FAILURE(Build());
  std::string output;
  EXPECT_EQ(Run("info " + index_path_.string(), &output), 0) << output;
  EXPECT_THAT(output, HasSubstr("10 images, 400 points"));
  EXPECT_EQ(Run("verify " + index_path_.string(), &output), 0) << output;
  EXPECT_THAT(output, HasSubstr(": OK: 16 section checksums and every stored index verified"));
}

// A section this cwloc does not know, flagged optional, is skipped: verify and info name it
// (what it knows is the section table, format/index_section_table.inc).
TEST_F(IndexCliTest, VerifyAndInfoNameAnOptionalSectionThisCwlocDoesNotKnow) {
  ASSERT_NO_FATAL_FAILURE(Build(" --calibration-samples 0"));
  std::vector<SectionData> sections;
  const IndexFile file = IndexFile::Open(index_path_);
  for (const SectionEntry& entry : file.sections()) {
    sections.push_back({entry.tag, entry.flags, entry.element_size, entry.count,
                        file.bytes().subspan(entry.offset, entry.size)});
  }
  const uint8_t newer[3] = {1, 2, 3};
  sections.push_back(MakeSection(SectionTag("ZZZZ"), std::span<const uint8_t>(newer), 0));
  const std::string path = (dir_ / "newer.cwl").string();
  WriteIndexFile(path, sections);
  std::string output;
  EXPECT_EQ(Run("verify " + path, &output), 0) << output;
  EXPECT_THAT(output, HasSubstr(": OK: 16 section checksums and every stored index verified"));
  EXPECT_THAT(output, HasSubstr("\n  section 'ZZZZ' is unknown to this cwloc: its checksum "
                                "verified, not its contents\n"));
  EXPECT_EQ(Run("info " + path, &output), 0) << output;
  EXPECT_THAT(output, HasSubstr("  PIDS "));
  EXPECT_THAT(output, HasSubstr("each point's COLMAP id (optional, format 1.5)\n"));
  EXPECT_THAT(output, HasSubstr("unknown to this cwloc (optional: skipped)\n"));
  ASSERT_EQ(Run("info --json " + path, &output), 0) << output;
  ExpectValidInfoJson(output);
  EXPECT_EQ(nlohmann::json::parse(output)["sections"].back()["contents"],
            "unknown to this cwloc (optional: skipped)");
}

// Every optional section of the table reaches tiles and updates: the elements of a section
// kept with its rows are the parent's for each kept view or point, and a section the parent
// gives whole is the parent's.
TEST_F(IndexCliTest, EverySectionOfTheTableReachesATileAndAnUpdate) {
  ASSERT_NO_FATAL_FAILURE(
      Build(" --keypoints --point-colors --model-frame enu:47.3779,8.5403,400"));
  const Index parent = Index::Open(index_path_);
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    if (spec.InIndexOfKind(false)) {
      EXPECT_NE(parent.file().FindSection(spec.tag), nullptr) << SectionTagName(spec.tag);
    }
  }
  const auto list = dir_ / "images.txt", tile_path = dir_ / "tile.cwl";
  std::ofstream(list) << parent.ImageName(parent.images()[3]) << "\n"
                      << parent.ImageName(parent.images()[7]) << "\n";
  std::string output;
  ASSERT_EQ(Run("extract --index " + index_path_.string() + " --images " + list.string() + " -o " +
                    tile_path.string(),
                &output),
            0)
      << output;
  const auto updated = dir_ / "updated.cwl";
  ASSERT_EQ(Run("update --index " + index_path_.string() + " --model " + model_dir_.string() +
                    " --database " + database_path_.string() + " -o " + updated.string(),
                &output),
            0)
      << output;
  const Index tile = Index::Open(tile_path);
  const Index update = Index::Open(updated);
  // The tile's views and points as the parent's rows: images by id, points by COLMAP id.
  std::vector<uint32_t> parent_views, parent_points;
  for (const IndexImage& image : tile.images()) {
    for (const IndexImage& old_image : parent.images()) {
      for (uint32_t v = 0; old_image.image_id == image.image_id && v < image.num_views; ++v)
        parent_views.push_back(old_image.first_view + v);
    }
  }
  for (const uint64_t id : tile.point_ids()) {
    const auto ids = parent.point_ids();
    parent_points.push_back(uint32_t(std::lower_bound(ids.begin(), ids.end(), id) - ids.begin()));
  }
  ASSERT_EQ(parent_views.size(), tile.num_views());
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    const std::string tag = SectionTagName(spec.tag);
    const std::span<const uint8_t> from = spec.bytes(parent.rows());
    if (spec.child == SectionInChild::kMade || from.empty()) continue;
    EXPECT_TRUE(std::ranges::equal(spec.bytes(update.rows()), from)) << tag;
    const std::span<const uint8_t> kept = spec.bytes(tile.rows());
    if (spec.child == SectionInChild::kParents) {
      EXPECT_TRUE(std::ranges::equal(kept, from)) << tag;
      continue;
    }
    const std::vector<uint32_t>& rows =
        spec.count == SectionCount::kPerView ? parent_views : parent_points;
    const size_t size = spec.ElementBytes(parent.rows());
    ASSERT_EQ(kept.size(), rows.size() * size) << tag;
    for (size_t i = 0; i < rows.size(); ++i) {
      ASSERT_TRUE(
          std::ranges::equal(kept.subspan(i * size, size), from.subspan(rows[i] * size, size)))
          << tag << " row " << i;
    }
  }
}

TEST_F(IndexCliTest, InfoJsonValidatesAgainstItsSchema) {
  ASSERT_NO_FATAL_FAILURE(Build());
  std::string output;
  ASSERT_EQ(Run("info --json " + index_path_.string(), &output), 0) << output;
  const auto info = nlohmann::json::parse(output);
  EXPECT_EQ(info["manifest"]["counts"]["images"], 10);
  EXPECT_EQ(info["manifest"]["build_parameters"]["kd_trees"], 4);
  EXPECT_EQ(info["manifest"]["build_parameters"]["clustering"]["method"], "image");
  ExpectValidInfoJson(output);
}

TEST_F(IndexCliTest, CompactBuildSaysHowItStoresDescriptorsInInfoAndItsSchema) {
  ASSERT_NO_FATAL_FAILURE(Build(" --compact"));
  std::string output;
  EXPECT_EQ(Run("info " + index_path_.string(), &output), 0) << output;
  EXPECT_THAT(output, HasSubstr(": cwloc index format 1.5, "));
  EXPECT_THAT(output, testing::ContainsRegex(
                          "descriptors: one 32-byte product-quantization code per 3D point "
                          "\\([0-9.]+ views per point\\)"));
  EXPECT_EQ(Run("verify " + index_path_.string(), &output), 0) << output;
  EXPECT_THAT(output, HasSubstr(": OK: 18 section checksums and every stored index verified"));
  ASSERT_EQ(Run("info --json " + index_path_.string(), &output), 0) << output;
  const auto info = nlohmann::json::parse(output);
  EXPECT_EQ(info["format_version"], "1.5");  // PCAL, PIDS
  EXPECT_EQ(info["manifest"]["build_parameters"]["descriptors"]["code_bytes"], 32);
  EXPECT_DOUBLE_EQ(info["bytes_per_view"].get<double>(),
                   double(info["file_bytes"].get<uint64_t>()) /
                       info["manifest"]["counts"]["views"].get<double>());
  ExpectValidInfoJson(output);
  // A code size that does not split 128 is refused before any work, naming the value.
  EXPECT_EQ(Run("build --model " + model_dir_.string() + " --database " + database_path_.string() +
                    " -o " + (dir_ / "bad.cwl").string() + " --code-bytes 48",
                &output),
            2);
  EXPECT_THAT(output, HasSubstr("--code-bytes 48: expected 0 (full descriptors) or 4, 8, 16, 32 "
                                "or 64"));
}

TEST_F(IndexCliTest, CompactBuildOfAModelWithTooFewPointsSaysSoAndWritesNothing) {
  std::string output;
  const auto scene = dir_ / "tiny";
  ASSERT_EQ(test::RunCommand(test::ToolPath("cwloc-synth").string() +
                                 " --blocks 1 --queries 2 --camera-spacing 15 "
                                 "--features-per-image 100 -o " +
                                 scene.string(),
                             &output),
            0)
      << output;
  const auto model = scene / "mapping_model" / "bin";
  EXPECT_EQ(
      Run("build --model " + model.string() + " --database " + (scene / "database.db").string() +
              " --compact -o " + (dir_ / "tiny.cwl").string(),
          &output),
      2);
  EXPECT_THAT(output, testing::MatchesRegex(
                          "cwloc-index: error: " + model.string() +
                          ": a compact index learns 256 codes per part from the 3D points, and "
                          "the model has [0-9]+; build a full index \\(no --compact\\)\n"));
  EXPECT_FALSE(std::filesystem::exists(dir_ / "tiny.cwl"));
}

TEST_F(IndexCliTest, VerifyReportsAFlippedByteInEverySection) {
  ASSERT_NO_FATAL_FAILURE(Build());
  const std::vector<uint8_t> original = Bytes();
  std::vector<SectionEntry> entries;
  {
    const IndexFile file = IndexFile::Open(index_path_);
    entries.assign(file.sections().begin(), file.sections().end());
  }
  ASSERT_EQ(entries.size(), 16u);
  // Named strings: "literal" + a temporary std::string trips GCC 12's -Wrestrict.
  const std::string corrupt = (dir_ / "corrupt.cwl").string();
  for (const SectionEntry& entry : entries) {
    std::vector<uint8_t> bytes = original;
    bytes[entry.offset + entry.size / 2] ^= 0x20;
    WriteCorrupt(bytes);
    const std::string tag = SectionTagName(entry.tag);
    std::string output;
    EXPECT_EQ(Run("verify " + corrupt, &output), 2) << tag;
    EXPECT_THAT(output, HasSubstr("'" + tag + "': checksum mismatch")) << output;
  }
}

TEST_F(IndexCliTest, DamagedFilesGiveTheirOwnErrors) {
  ASSERT_NO_FATAL_FAILURE(Build());
  const std::vector<uint8_t> original = Bytes();
  const std::string corrupt = (dir_ / "corrupt.cwl").string();
  std::string output;

  std::vector<uint8_t> truncated(original.begin(), original.begin() + original.size() / 2);
  WriteCorrupt(truncated);
  EXPECT_EQ(Run("info " + corrupt, &output), 2);
  EXPECT_THAT(output, HasSubstr("cwloc-index: error: " + corrupt +
                                ": truncated or extended: the header says " +
                                std::to_string(original.size()) + " bytes, the file has " +
                                std::to_string(truncated.size())));

  std::vector<uint8_t> magic = original;
  magic[3] = 'X';
  WriteCorrupt(magic);
  EXPECT_EQ(Run("verify " + corrupt, &output), 2);
  EXPECT_THAT(output, HasSubstr(corrupt + ": not a cwloc index (wrong magic"));

  std::vector<uint8_t> newer = original;
  newer[12] = 3;
  WriteCorrupt(newer);
  EXPECT_EQ(Run("info " + corrupt, &output), 2);
  EXPECT_THAT(output,
              HasSubstr("index format 3.5 is not readable by this cwloc, which reads format 1.x"));

  EXPECT_EQ(Run("info " + (dir_ / "missing.cwl").string(), &output), 2);
  EXPECT_THAT(output, HasSubstr("missing.cwl: cannot open: No such file or directory"));
}

TEST_F(IndexCliTest, BuildFromAMissingModelIsABadInputError) {
  std::string output;
  EXPECT_EQ(Run("build --model " + (dir_ / "nope").string() + " --database " +
                    database_path_.string() + " -o " + index_path_.string(),
                &output),
            2);
  EXPECT_THAT(output, HasSubstr("cwloc-index: error: "));
  EXPECT_THAT(output, HasSubstr("nope"));
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

// A value out of its range in the build option table is refused by name, with exit code 2,
// before anything is read: the model and database here do not exist (issue #39). --leaf-size 255
// used to pass the builder's own check and fail in the kd-forest, after the whole model was read.
TEST_F(IndexCliTest, OutOfRangeBuildOptionsAreRefusedBeforeAnythingIsRead) {
  const std::string inputs =
      " --model /nonexistent --database /nonexistent -o " + (dir_ / "x.cwl").string();
  for (const auto& [flag, message] : std::vector<std::pair<std::string, std::string>>{
           {"--leaf-size 255", "--leaf-size 255: expected 1 to 254"},
           {"--trees 0", "--trees 0: expected 1 to 64"},
           {"--code-bytes 3",
            "--code-bytes 3: expected 0 (full descriptors) or 4, 8, 16, 32 or 64"},
           {"--clusters 0", "--clusters 0: expected at least 1"},
           {"--georef-sigma 0", "--georef-sigma 0: expected a number of metres > 0"},
           {"--trees 2x", "--trees 2x: expected a whole number"}}) {
    std::string output;
    EXPECT_EQ(Run("build " + flag + inputs, &output), 2) << flag;
    EXPECT_EQ(output, "cwloc-index: error: " + message + "\n");
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ / "x.cwl"));
}

TEST_F(IndexCliTest, TheLargestLeafSizeOfTheKdForestIsAccepted) {
  ASSERT_NO_FATAL_FAILURE(Build(" --leaf-size " + std::to_string(kMaxKdLeafSize)));
  std::string output;
  ASSERT_EQ(Run("info --json " + index_path_.string(), &output), 0) << output;
  EXPECT_EQ(nlohmann::json::parse(output)["manifest"]["build_parameters"]["kd_leaf_size"], 254);
  EXPECT_EQ(Run("verify " + index_path_.string(), &output), 0) << output;
}

// `build --help` lists exactly the table's flags (each with its help) and the few that are not
// options: the CLI cannot grow a flag that cwloc.build_index lacks (tests/python checks that side).
TEST_F(IndexCliTest, BuildHelpListsEveryLineOfTheBuildOptionTable) {
  std::string help;
  ASSERT_EQ(Run("build --help", &help), 0) << help;
  std::set<std::string> expected = {"help", "model", "database", "output", "json"};
  for (const BuildOptionSpec& spec : BuildOptionTable()) {
    expected.insert(std::string(spec.flag));
    EXPECT_THAT(help, HasSubstr("  --" + std::string(spec.flag) + " ")) << spec.flag;
    EXPECT_THAT(help, HasSubstr(spec.help)) << spec.flag;
  }
  std::set<std::string> listed;
  std::istringstream lines(help);
  const std::regex flag_line(R"(^  (?:-[a-z],)?--([a-z-]+)\b.*)");
  for (std::string line; std::getline(lines, line);) {
    std::smatch match;
    if (std::regex_match(line, match, flag_line)) listed.insert(match[1]);
  }
  EXPECT_EQ(listed, expected);
  EXPECT_THAT(help, HasSubstr("--trees UINT=4 "));
  EXPECT_THAT(help, HasSubstr("--georef-sigma FLOAT=5 "));
}

// build, update, extract and apply list their lines of the command table, each with its help
// and a number's default; --threads is the build option table's line on each of them, with one
// type, range and message.
TEST_F(IndexCliTest, EachCommandTakesItsLinesOfTheCommandTable) {
  const auto expect_listed = [&](const std::string& command, const auto& table) {
    std::string help;
    ASSERT_EQ(Run(command + " --help", &help), 0) << help;
    for (const auto& spec : table) {
      EXPECT_THAT(help, HasSubstr("  " + spec.names + " ")) << command << " " << spec.names;
      EXPECT_THAT(help, HasSubstr(spec.help)) << command << " " << spec.names;
    }
    EXPECT_THAT(help, HasSubstr("  --threads INT=0 ")) << command;
  };
  expect_listed("build", CommandFlagTable<IndexBuildOptions>());
  expect_listed("update", CommandFlagTable<IndexUpdateOptions>());
  expect_listed("extract", CommandFlagTable<IndexExtractOptions>());
  expect_listed("apply", CommandFlagTable<IndexApplyOptions>());
  for (const std::string command :
       {"build --model m --database d -o o", "update --index i --model m --database d -o o",
        "extract --index i --near '47 8 100' -o o", "apply --index i --delta d -o o"}) {
    std::string output;
    EXPECT_EQ(Run(command + " --threads 2x", &output), 2) << command;
    EXPECT_EQ(output, "cwloc-index: error: --threads 2x: expected a whole number\n") << command;
  }
}

// Every input file of a build given as a device, a pipe or an oversized file is refused by name
// before it is read (issue #23), with exit code 2, under a 1 GB address-space limit that reading
// /dev/zero would exhaust within a second.
class IndexInputLimitsTest : public IndexCliTest {
 protected:
  int RunBuild(const std::string& args, std::string* output) const {
    return test::RunCommand(
        test::UnderMemoryLimit(1'048'576, test::ToolPath("cwloc-index").string() + " build " +
                                              args + " -o " + test::Quote(index_path_)),
        output);
  }
  std::string Inputs(const std::filesystem::path& model) const {
    return "--model " + test::Quote(model) + " --database " + test::Quote(database_path_);
  }
  // A copy of the fixture's model, in `format`, with `file` replaced by a link to /dev/zero.
  std::filesystem::path ModelWithDevZero(const std::string& file,
                                         colmap::ModelFormat format) const {
    const auto model = dir_ / ("zero_" + file);
    std::filesystem::create_directories(model);
    colmap::WriteReconstruction(model_, model, format);
    std::filesystem::remove(model / file);
    std::filesystem::create_symlink("/dev/zero", model / file);
    return model;
  }
  static std::string NotRegular(const std::string& path, const std::string& kind,
                                const std::string& what) {
    return "cwloc-index: error: " + path + ": not a regular file (" + kind + "); " + what +
           " must be a regular file, not a device, a pipe, a socket or /dev/stdin\n";
  }
};

TEST_F(IndexInputLimitsTest, DevZeroAsAModelOrDatabaseIsRefused) {
  std::string output;
  EXPECT_EQ(RunBuild(Inputs("/dev/zero"), &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-index: error: /dev/zero: not a directory (expected a "
                                "COLMAP sparse model)\n"));
  for (const auto& [file, format] : {std::pair{"images.bin", colmap::ModelFormat::kBinary},
                                     std::pair{"points3D.txt", colmap::ModelFormat::kText}}) {
    const auto model = ModelWithDevZero(file, format);
    EXPECT_EQ(RunBuild(Inputs(model), &output), 2) << output;
    EXPECT_THAT(output, HasSubstr(NotRegular((model / file).string(), "a character device",
                                             "a COLMAP model file")));
  }
  EXPECT_EQ(RunBuild("--model " + test::Quote(model_dir_) + " --database /dev/zero", &output), 2)
      << output;
  EXPECT_THAT(output,
              HasSubstr(NotRegular("/dev/zero", "a character device", "a COLMAP database")));
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

TEST_F(IndexInputLimitsTest, DevZeroOrAPipeAsAGeorefClusteringOrPhotoFileIsRefused) {
  std::string output;
  EXPECT_EQ(RunBuild(Inputs(model_dir_) + " --georef /dev/zero", &output), 2) << output;
  EXPECT_THAT(output, HasSubstr(NotRegular("/dev/zero", "a character device", "a georef file")));
  EXPECT_EQ(RunBuild(Inputs(model_dir_) + " --cluster-file /dev/zero", &output), 2) << output;
  EXPECT_THAT(output,
              HasSubstr(NotRegular("/dev/zero", "a character device", "a clustering file")));

  // A named pipe nobody writes would block an open() forever.
  const auto fifo = dir_ / "georef.fifo";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0) << std::strerror(errno);
  EXPECT_EQ(RunBuild(Inputs(model_dir_) + " --georef " + test::Quote(fifo), &output), 2) << output;
  EXPECT_THAT(output, HasSubstr(NotRegular(fifo.string(), "a pipe", "a georef file")));

  // --georef-images: the first model image's photo is /dev/zero.
  const auto photos = dir_ / "photos";
  const std::string first = model_.images.begin()->second.name;
  std::filesystem::create_directories((photos / first).parent_path());
  std::filesystem::create_symlink("/dev/zero", photos / first);
  EXPECT_EQ(RunBuild(Inputs(model_dir_) + " --georef-images " + test::Quote(photos), &output), 2)
      << output;
  EXPECT_THAT(output,
              HasSubstr(NotRegular((photos / first).string(), "a character device", "an image")));
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

TEST_F(IndexInputLimitsTest, FilesOverTheirLimitAreRefusedBeforeTheyAreRead) {
  std::string output;
  const auto georef = test::WriteSparseFile(dir_ / "georef.txt", 300'000'000);
  EXPECT_EQ(RunBuild(Inputs(model_dir_) + " --georef " + test::Quote(georef), &output), 2)
      << output;
  EXPECT_THAT(output, HasSubstr("cwloc-index: error: " + georef.string() +
                                ": 300 MB, more than the 256 MB limit for a georef file\n"));

  const auto model = dir_ / "huge_model";
  std::filesystem::create_directories(model);
  colmap::WriteReconstruction(model_, model, colmap::ModelFormat::kBinary);
  test::WriteSparseFile(model / "points3D.bin", 300'000'000'000);
  EXPECT_EQ(RunBuild(Inputs(model), &output), 2) << output;
  EXPECT_THAT(output, HasSubstr("cwloc-index: error: " + (model / "points3D.bin").string() +
                                ": 300 GB, more than the 256 GB limit for a COLMAP model file\n"));
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

}  // namespace
}  // namespace cwloc

namespace cwloc {
namespace {

// A writer killed at any moment leaves the previous index or the new one at the destination,
// and nothing else in its folder (docs/format.md: the temporary file has no name until it is
// in place). The kill moments are spread over a whole build's duration.
TEST_F(IndexCliTest, KilledBuildsLeaveTheOldOrTheNewIndexAndNothingElse) {
  const auto out_dir = dir_ / "out";
  std::filesystem::create_directories(out_dir);
  const auto output = out_dir / "model.cwl";
  const std::vector<std::string> args = {test::ToolPath("cwloc-index").string(),
                                         "build",
                                         "--model",
                                         model_dir_.string(),
                                         "--database",
                                         database_path_.string(),
                                         "--threads",
                                         "1",
                                         "-o",
                                         output.string()};
  // One whole build: its duration and its bytes (builds are deterministic).
  const auto start = std::chrono::steady_clock::now();
  ASSERT_EQ(test::Wait(test::Spawn(args)), 0);
  const auto duration = std::chrono::steady_clock::now() - start;
  const std::vector<uint8_t> complete = test::ReadBytes(output);
  ASSERT_FALSE(complete.empty());

  auto& rng = test::Rng();
  std::vector<pid_t> killed;
  for (int kill_number = 0; kill_number < 24; ++kill_number) {
    // Half the kills with no previous index, half replacing one.
    const bool replacing = kill_number % 2 == 1;
    std::filesystem::remove(output);
    if (replacing) test::WriteBytes(output, complete);
    const pid_t pid = test::Spawn(args);
    killed.push_back(pid);
    test::KillAfter(pid, duration * (rng() % 1000) / 1000);
    // A kill between the link and the rename of a replacement leaves the killed writer's
    // named file, which the next writer removes (the window is microseconds wide).
    bool has_output = false;
    for (const auto& entry : std::filesystem::directory_iterator(out_dir)) {
      const std::string name = entry.path().filename().string();
      if (entry.path() == output) {
        has_output = true;
      } else {
        EXPECT_TRUE(test::IsKilledWritersTemporary(name, output.filename().string(), killed))
            << name << " after kill " << kill_number;
      }
    }
    if (!has_output) {
      EXPECT_FALSE(replacing) << "the previous index vanished";
      continue;
    }
    EXPECT_TRUE(test::ReadBytes(output) == complete)
        << "a partial index after kill " << kill_number;
  }
  // A last complete build cleans up after every killed writer.
  ASSERT_EQ(test::Wait(test::Spawn(args)), 0);
  EXPECT_EQ(test::ListDir(out_dir), std::vector<std::filesystem::path>{output});
}

}  // namespace
}  // namespace cwloc
