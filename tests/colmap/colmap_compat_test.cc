// Proves that the real `colmap` program (Debian's 3.8, classic layout) reads what we write and
// that we read what it writes, value for value.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "colmap/reconstruction_io.h"
#include "tests/colmap/synthetic_model.h"
#include "tests/colmap/text_records.h"
#include "tests/test_util.h"

namespace cwloc::colmap {
namespace {

namespace fs = std::filesystem;

bool HaveColmap() {
  std::string output;
  return test::RunCommand("command -v colmap", &output) == 0;
}

#define REQUIRE_COLMAP()                                                                       \
  if (!HaveColmap())                                                                           \
  GTEST_SKIP() << "the `colmap` program is not on PATH (Debian package colmap); skipping the " \
                  "COLMAP compatibility test"

// Runs `colmap <args>` headless; fails the test with colmap's output when it does not exit 0.
std::string Colmap(const std::string& args) {
  std::string output;
  const int code = test::RunCommand("QT_QPA_PLATFORM=offscreen colmap " + args, &output);
  EXPECT_EQ(code, 0) << "colmap " << args << "\n" << output;
  return output;
}

using cwloc::test::Quote;

std::string Convert(const fs::path& in, const fs::path& out, const char* type) {
  fs::create_directories(out);
  return Colmap("model_converter --input_path " + Quote(in) + " --output_path " + Quote(out) +
                " --output_type " + type);
}

// "Cameras: 4" -> {"Cameras", 4} for every such line of model_analyzer's output.
std::map<std::string, uint64_t> AnalyzerCounts(const std::string& output) {
  std::map<std::string, uint64_t> counts;
  const std::regex line(R"(([A-Za-z ]+): (\d+)\s*$)");
  std::istringstream in(output);
  for (std::string text; std::getline(in, text);) {
    std::smatch match;
    if (std::regex_search(text, match, line)) counts[match[1]] = std::stoull(match[2]);
  }
  return counts;
}

Reconstruction CompatModel() {
  test::SyntheticModelOptions options;
  options.num_cameras = 11;  // one camera per model colmap 3.8 knows
  options.num_images = 15;
  options.num_points3D = 600;
  options.camera_models = test::Colmap38CameraModels();
  return test::SyntheticModel(options);
}

TEST(ColmapCompatTest, AnalyzerCountsOurBinaryModel) {
  REQUIRE_COLMAP();
  const Reconstruction model = CompatModel();
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), ModelFormat::kBinary);
  const auto counts = AnalyzerCounts(Colmap("model_analyzer --path " + Quote(dir.path())));
  EXPECT_EQ(counts.count("Cameras") ? counts.at("Cameras") : 0, model.cameras.size());
  EXPECT_EQ(counts.count("Images") ? counts.at("Images") : 0, model.images.size());
  EXPECT_EQ(counts.count("Registered images") ? counts.at("Registered images") : 0,
            model.images.size());
  EXPECT_EQ(counts.count("Points") ? counts.at("Points") : 0, model.points3D.size());
  EXPECT_EQ(counts.count("Observations") ? counts.at("Observations") : 0, model.NumObservations());
}

TEST(ColmapCompatTest, ColmapConvertsOurBinaryToTextAndBack) {
  REQUIRE_COLMAP();
  const Reconstruction model = CompatModel();
  test::TempDir dir;
  const fs::path ours_bin = dir / "ours_bin", colmap_txt = dir / "colmap_txt",
                 colmap_bin = dir / "colmap_bin", ours_txt = dir / "ours_txt";
  fs::create_directories(ours_bin);
  WriteReconstruction(model, ours_bin, ModelFormat::kBinary);

  Convert(ours_bin, colmap_txt, "TXT");
  EXPECT_EQ(ReadReconstruction(colmap_txt), model) << "colmap's text of our binary model";

  // Our text writer and colmap's agree record for record (colmap 3.8 orders by hash).
  fs::create_directories(ours_txt);
  WriteReconstruction(model, ours_txt, ModelFormat::kText);
  for (const auto& [name, lines] : std::vector<std::pair<std::string, int>>{
           {"cameras.txt", 1}, {"images.txt", 2}, {"points3D.txt", 1}}) {
    EXPECT_TRUE(test::SortedRecords(ours_txt / name, lines) ==
                test::SortedRecords(colmap_txt / name, lines))
        << name << " differs between our writer and colmap's";
    EXPECT_EQ(fs::file_size(ours_txt / name), fs::file_size(colmap_txt / name)) << name;
  }

  Convert(colmap_txt, colmap_bin, "BIN");
  EXPECT_EQ(ReadReconstruction(colmap_bin), model) << "colmap's binary of its text";
  for (const char* name : {"cameras.bin", "images.bin", "points3D.bin"}) {
    EXPECT_EQ(fs::file_size(colmap_bin / name), fs::file_size(ours_bin / name)) << name;
  }
}

TEST(ColmapCompatTest, ColmapConvertsOurTextToBinary) {
  REQUIRE_COLMAP();
  const Reconstruction model = CompatModel();
  test::TempDir dir;
  const fs::path ours_txt = dir / "ours_txt", colmap_bin = dir / "colmap_bin";
  fs::create_directories(ours_txt);
  WriteReconstruction(model, ours_txt, ModelFormat::kText);
  Convert(ours_txt, colmap_bin, "BIN");
  EXPECT_EQ(ReadReconstruction(colmap_bin), model) << "colmap's binary of our text model";
}

}  // namespace
}  // namespace cwloc::colmap
