#pragma once

#include <gtest/gtest.h>

#include "colmap/database.h"
#include "colmap/reconstruction_io.h"
#include "indexer/index_builder.h"
#include "kdtree/descriptor_distance.h"
#include "tests/colmap/synthetic_model.h"
#include "tests/test_util.h"

namespace cwloc::test {

// A small synthetic COLMAP model and a database with one random descriptor per 2D point,
// written to a temp dir, ready for `cwloc-index build`.
class IndexerFixture : public testing::Test {
 protected:
  void SetUp() override {
    SyntheticModelOptions options;
    options.num_images = 10;
    options.num_points3D = 400;
    options.camera_models = Colmap38CameraModels();
    model_ = SyntheticModel(options);
    model_dir_ = dir_ / "model";
    std::filesystem::create_directories(model_dir_);
    colmap::WriteReconstruction(model_, model_dir_, colmap::ModelFormat::kBinary);
    database_path_ = dir_ / "database.db";
    colmap::DatabaseWriter writer(database_path_);
    for (const auto& [id, camera] : model_.cameras) writer.WriteCamera(camera);
    for (const auto& [id, image] : model_.images) {
      writer.WriteImage({id, image.name, image.camera_id});
      colmap::Descriptors descriptors;
      descriptors.rows = static_cast<uint32_t>(image.points2D.size());
      descriptors.data.resize(size_t{descriptors.rows} * 128);
      for (auto& byte : descriptors.data) byte = static_cast<uint8_t>(Rng()() % 64);
      descriptors_[id] = descriptors;
      std::vector<colmap::Keypoint> keypoints;
      for (const colmap::Point2D& point : image.points2D) {
        keypoints.push_back({static_cast<float>(point.x), static_cast<float>(point.y)});
      }
      writer.WriteKeypoints(id, keypoints);
      writer.WriteDescriptors(id, descriptors);
    }
    // A query image that is in the database but not in the model must be ignored.
    writer.WriteImage({9999, "query.jpg", model_.cameras.begin()->first});
    writer.Commit();
    index_path_ = dir_ / "model.cwl";
  }

  // Builds index_path_ from the fixture's model and database with default options.
  void BuildFixtureIndex() const {
    IndexBuildOptions options;
    options.model_dir = model_dir_;
    options.database_path = database_path_;
    options.output_path = index_path_;
    BuildIndex(options);
  }

  TempDir dir_;
  colmap::Reconstruction model_;
  std::map<image_t, colmap::Descriptors> descriptors_;
  std::filesystem::path model_dir_, database_path_, index_path_;
};

}  // namespace cwloc::test
