#include "tests/localizer/matching_scene.h"

#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "colmap/database.h"
#include "colmap/reconstruction_io.h"
#include "format/index_file.h"
#include "format/index_layout.h"
#include "indexer/index_builder.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// The scene as a COLMAP model: ids are rows + 1, every 2D point is a view.
colmap::Reconstruction ModelOf(const test::MatchingScene& scene) {
  colmap::Reconstruction model;
  for (const IndexCamera& c : scene.cameras) {
    colmap::Camera camera;
    camera.camera_id = c.camera_id;
    camera.model_id = static_cast<CameraModelId>(c.model_id);
    camera.width = c.width;
    camera.height = c.height;
    camera.params.assign(c.params, c.params + c.num_params);
    model.cameras.emplace(camera.camera_id, camera);
  }
  for (size_t p = 0; p < scene.points.size(); ++p) {
    colmap::Point3D point;
    point.point3D_id = p + 1;
    std::copy_n(scene.points[p].xyz, 3, point.xyz.begin());
    model.points3D.emplace(point.point3D_id, point);
  }
  for (const IndexImage& row : scene.images) {
    colmap::Image image;
    image.image_id = row.image_id;
    image.camera_id = scene.cameras[row.camera_index].camera_id;
    image.name = scene.strings.substr(row.name_offset, row.name_size);
    std::copy_n(row.cam_from_world_rotation, 4, image.cam_from_world.rotation.begin());
    std::copy_n(row.cam_from_world_translation, 3, image.cam_from_world.translation.begin());
    for (uint32_t v = row.first_view; v < row.first_view + row.num_views; ++v) {
      const point3D_t point = scene.view_points[v] + 1;
      model.points3D.at(point).track.push_back(
          {image.image_id, static_cast<point2D_t>(image.points2D.size())});
      image.points2D.push_back({10.0 + v % 600, 20.0 + v / 600, point});
    }
    model.images.emplace(image.image_id, image);
  }
  return model;
}

// The matching tests' index, made in memory (tests/localizer/matching_scene.h), is the index
// `cwloc-index build` makes of the same model: every section but the manifest byte for byte,
// the kd-forest, the v_NN distances and the co-visibility graph included.
TEST(MatchingSceneTest, ItsIndexIsTheIndexOfItsModel) {
  SplitMix64 rng(test::Rng()());
  const test::MatchingScene scene = test::RandomMatchingScene(rng);
  const test::TempDir dir;
  const colmap::Reconstruction model = ModelOf(scene);
  std::filesystem::create_directories(dir / "model");
  colmap::WriteReconstruction(model, dir / "model", colmap::ModelFormat::kBinary);
  colmap::DatabaseWriter database(dir / "database.db");
  for (const auto& [id, camera] : model.cameras) database.WriteCamera(camera);
  for (const auto& [id, image] : model.images) {
    database.WriteImage({id, image.name, image.camera_id});
    std::vector<colmap::Keypoint> keypoints;
    for (const colmap::Point2D& point : image.points2D) {
      keypoints.push_back({static_cast<float>(point.x), static_cast<float>(point.y)});
    }
    database.WriteKeypoints(id, keypoints);
    const IndexImage& row = scene.images[id - 1];
    colmap::Descriptors descriptors;
    descriptors.rows = row.num_views;
    descriptors.data.assign(
        scene.descriptors.begin() + size_t{row.first_view} * kDescriptorBytes,
        scene.descriptors.begin() + size_t{row.first_view + row.num_views} * kDescriptorBytes);
    database.WriteDescriptors(id, descriptors);
  }
  database.Commit();

  test::WriteMatchingIndex(scene, dir / "scene.cwl");
  IndexBuildOptions options;
  options.model_dir = dir / "model";
  options.database_path = dir / "database.db";
  options.output_path = dir / "built.cwl";
  options.threads = 2;
  options.calibration_samples = 0;  // the scene's index has no PCAL
  BuildIndex(options);

  const IndexFile built = IndexFile::Open(dir / "built.cwl");
  const IndexFile made = IndexFile::Open(dir / "scene.cwl");
  ASSERT_EQ(made.sections().size(), built.sections().size());
  for (const SectionEntry& entry : built.sections()) {
    const std::string tag = SectionTagName(entry.tag);
    if (entry.tag == section::kManifest) continue;
    const SectionEntry* other = made.FindSection(entry.tag);
    ASSERT_NE(other, nullptr) << tag;
    EXPECT_EQ(other->flags, entry.flags) << tag;
    EXPECT_EQ(other->count, entry.count) << tag;
    EXPECT_EQ(other->element_size, entry.element_size) << tag;
    ASSERT_EQ(other->size, entry.size) << tag;
    EXPECT_EQ(std::memcmp(made.bytes().data() + other->offset, built.bytes().data() + entry.offset,
                          entry.size),
              0)
        << tag << " differs";
  }
}

}  // namespace
}  // namespace cwloc
