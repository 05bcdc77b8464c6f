// Reads the team's real COLMAP 3.8 model (../shared/data/herz_jesu_p25, see its README.txt).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "colmap/reconstruction_io.h"
#include "tests/colmap/text_records.h"
#include "tests/test_util.h"

namespace cwloc::colmap {
namespace {

namespace fs = std::filesystem;

constexpr const char* kDataset = "herz_jesu_p25";

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

std::vector<std::string> HeaderLines(const fs::path& path) {
  std::istringstream in(ReadFile(path));
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line) && !line.empty() && line[0] == '#') lines.push_back(line);
  return lines;
}

TEST(SharedDataTest, MappingModelCounts) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  const Reconstruction model = ReadReconstruction(data / "mapping_model" / "bin");
  EXPECT_EQ(model.images.size(), 20u);
  EXPECT_EQ(model.points3D.size(), 13419u);
  EXPECT_EQ(model.NumObservations(), 63727u);
  EXPECT_TRUE(model.rigs.empty());
  ASSERT_EQ(model.cameras.size(), 1u);
  const Camera& camera = model.cameras.begin()->second;
  EXPECT_EQ(camera.model_id, CameraModelId::kSimpleRadial);
  EXPECT_EQ(camera.width, 1536u);
  EXPECT_EQ(camera.height, 1024u);
  ASSERT_EQ(camera.params.size(), 4u);
  EXPECT_NEAR(camera.params[0], 1375.771, 1e-3);
  EXPECT_EQ(camera.params[1], 768.0);
  EXPECT_EQ(camera.params[2], 512.0);
  EXPECT_NEAR(camera.params[3], -0.000823, 1e-6);
}

TEST(SharedDataTest, FullModelCounts) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  const Reconstruction model = ReadReconstruction(data / "full_model" / "bin");
  EXPECT_EQ(model.images.size(), 25u);
  EXPECT_EQ(model.points3D.size(), 13620u);
  EXPECT_EQ(model.NumObservations(), 80108u);
}

TEST(SharedDataTest, BinaryAndTextMappingModelsAgree) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  const Reconstruction bin = ReadReconstruction(data / "mapping_model" / "bin");
  const Reconstruction txt = ReadReconstruction(data / "mapping_model" / "txt");
  // COLMAP writes text with 17 significant digits, so every number is exactly equal. (colmap
  // 3.8 re-normalizes quaternions on reading and again before writing text; for this model
  // that changes no bit, so the whole models are equal.)
  EXPECT_EQ(bin, txt);
}

TEST(SharedDataTest, OurWritersReproduceColmapFiles) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  const fs::path bin_dir = data / "mapping_model" / "bin";
  const fs::path txt_dir = data / "mapping_model" / "txt";
  test::TempDir out;
  // Binary: the same bytes for the single camera; the same sizes for images and points (COLMAP
  // 3.8 wrote their records in hash-map order, we write them by id).
  WriteReconstruction(ReadReconstruction(bin_dir), out.path(), ModelFormat::kBinary);
  EXPECT_TRUE(ReadFile(out / "cameras.bin") == ReadFile(bin_dir / "cameras.bin"));
  for (const char* name : {"images.bin", "points3D.bin"}) {
    EXPECT_EQ(fs::file_size(out / name), fs::file_size(bin_dir / name)) << name;
  }
  // Text: the same records, character for character, and the same header lines.
  WriteReconstruction(ReadReconstruction(txt_dir), out.path(), ModelFormat::kText);
  for (const auto& [name, lines_per_record] : std::vector<std::pair<std::string, int>>{
           {"cameras.txt", 1}, {"images.txt", 2}, {"points3D.txt", 1}}) {
    EXPECT_EQ(HeaderLines(out / name), HeaderLines(txt_dir / name)) << name;
    EXPECT_TRUE(test::SortedRecords(out / name, lines_per_record) ==
                test::SortedRecords(txt_dir / name, lines_per_record))
        << name << " records differ from colmap's";
    EXPECT_EQ(fs::file_size(out / name), fs::file_size(txt_dir / name)) << name;
  }
}

TEST(SharedDataTest, MappingModelIsTheFullModelWithoutQueries) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  const Reconstruction full = ReadReconstruction(data / "full_model" / "bin");
  const Reconstruction mapping = ReadReconstruction(data / "mapping_model" / "bin");
  std::ifstream list(data / "query_list.txt");
  std::vector<std::string> queries{std::istream_iterator<std::string>(list), {}};
  ASSERT_EQ(queries.size(), 5u);
  for (const auto& [id, image] : mapping.images) {
    EXPECT_EQ(std::count(queries.begin(), queries.end(), image.name), 0) << image.name;
    const Image& same = full.images.at(id);
    EXPECT_EQ(same.name, image.name);
    EXPECT_EQ(same.cam_from_world, image.cam_from_world);  // no re-adjustment
  }
}

// queries_gt.txt: NAME QW QX QY QZ TX TY TZ CAMERA_MODEL W H PARAMS...
struct QueryGt {
  std::string name;
  Rigid3d cam_from_world;
  Camera camera;
};

std::vector<QueryGt> ReadQueriesGt(const fs::path& path) {
  std::ifstream in(path);
  std::vector<QueryGt> queries;
  std::string line;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    QueryGt q;
    std::string model;
    fields >> q.name;
    for (double& v : q.cam_from_world.rotation) fields >> v;
    for (double& v : q.cam_from_world.translation) fields >> v;
    fields >> model >> q.camera.width >> q.camera.height;
    const auto info = FindCameraModel(model);
    EXPECT_TRUE(info.has_value()) << model;
    if (info) q.camera.model_id = info->id;
    for (double v; fields >> v;) q.camera.params.push_back(v);
    queries.push_back(q);
  }
  return queries;
}

TEST(SharedDataTest, QueryGroundTruthReprojectsFullModelPoints) {
  CWLOC_REQUIRE_SHARED_DATA(data, kDataset);
  const Reconstruction full = ReadReconstruction(data / "full_model" / "bin");
  const std::vector<QueryGt> queries = ReadQueriesGt(data / "queries_gt.txt");
  ASSERT_EQ(queries.size(), 5u);
  for (const QueryGt& query : queries) {
    SCOPED_TRACE(query.name);
    const auto it = std::find_if(full.images.begin(), full.images.end(), [&](const auto& entry) {
      return entry.second.name == query.name;
    });
    ASSERT_NE(it, full.images.end());
    const Image& image = it->second;
    const Camera& camera = full.cameras.at(image.camera_id);
    EXPECT_EQ(query.camera.model_id, camera.model_id);
    for (size_t i = 0; i < camera.params.size(); ++i) {
      EXPECT_NEAR(query.camera.params[i], camera.params[i], 1e-9 * std::abs(camera.params[i]));
    }
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(query.cam_from_world.rotation[i], image.cam_from_world.rotation[i], 1e-12);
    }
    for (int i = 0; i < 3; ++i) {
      EXPECT_NEAR(query.cam_from_world.translation[i], image.cam_from_world.translation[i], 1e-12);
    }

    std::vector<double> errors;
    for (const Point2D& point2D : image.points2D) {
      if (point2D.point3D_id == kInvalidPoint3DId) continue;
      const auto& xyz = full.points3D.at(point2D.point3D_id).xyz;
      std::array<double, 2> pixel{};
      ASSERT_TRUE(ProjectToPixel(query.camera.model_id, query.camera.params,
                                 query.cam_from_world * xyz, &pixel));
      errors.push_back(std::hypot(pixel[0] - point2D.x, pixel[1] - point2D.y));
    }
    ASSERT_GT(errors.size(), 1000u);
    std::sort(errors.begin(), errors.end());
    const double median = errors[errors.size() / 2];
    const double p95 = errors[errors.size() * 95 / 100];
    EXPECT_LT(median, 1.0);
    EXPECT_LT(p95, 2.0);
    RecordProperty(query.name + "_median_px", std::to_string(median));

    // And back: the unprojected observation and the 3D point's direction agree.
    std::array<double, 2> normalized{};
    const Point2D& first =
        *std::find_if(image.points2D.begin(), image.points2D.end(),
                      [](const Point2D& p) { return p.point3D_id != kInvalidPoint3DId; });
    ASSERT_TRUE(PixelToNormalized(camera.model_id, camera.params, {first.x, first.y}, &normalized));
    const auto in_camera = image.cam_from_world * full.points3D.at(first.point3D_id).xyz;
    EXPECT_NEAR(normalized[0], in_camera[0] / in_camera[2], 5.0 / camera.params[0]);
    EXPECT_NEAR(normalized[1], in_camera[1] / in_camera[2], 5.0 / camera.params[0]);
  }
}

}  // namespace
}  // namespace cwloc::colmap
