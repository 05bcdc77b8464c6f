#include "indexer/index_builder.h"

#include <gmock/gmock.h>

#include <cmath>
#include <fstream>
#include <set>

#include "format/index/index.h"
#include "tests/indexer/indexer_fixture.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

class IndexBuilderTest : public test::IndexerFixture {
 protected:
  IndexBuildOptions Options() const {
    IndexBuildOptions options;
    options.model_dir = model_dir_;
    options.database_path = database_path_;
    options.output_path = index_path_;
    return options;
  }
};

TEST_F(IndexBuilderTest, StoresEveryObservedViewWithItsDescriptorPointAndImage) {
  IndexBuildOptions options = Options();
  options.keypoints = true;
  const IndexBuildReport report = BuildIndex(options);
  const Index index = Index::Open(index_path_);
  EXPECT_NO_THROW(index.Validate());
  EXPECT_NO_THROW(index.file().VerifyChecksums());
  EXPECT_EQ(index.num_views(), model_.NumObservations());
  EXPECT_EQ(report.num_views, model_.NumObservations());
  ASSERT_EQ(index.images().size(), model_.images.size());
  EXPECT_EQ(index.points().size(), model_.points3D.size());
  EXPECT_EQ(index.cameras().size(), model_.cameras.size());

  size_t camera_row = 0;
  for (const auto& [camera_id, camera] : model_.cameras) {
    const IndexCamera& stored = index.cameras()[camera_row++];
    EXPECT_EQ(stored.camera_id, camera_id);
    EXPECT_EQ(stored.model_id, static_cast<int32_t>(camera.model_id));
    EXPECT_EQ(stored.width, camera.width);
    EXPECT_EQ(stored.height, camera.height);
    ASSERT_EQ(stored.num_params, camera.params.size());
    for (size_t p = 0; p < camera.params.size(); ++p) EXPECT_EQ(stored.params[p], camera.params[p]);
  }
  size_t row = 0;
  for (const auto& [image_id, image] : model_.images) {
    const IndexImage& stored = index.images()[row++];
    EXPECT_EQ(stored.image_id, image_id);
    EXPECT_EQ(index.cameras()[stored.camera_index].camera_id, image.camera_id);
    for (int i = 0; i < 4; ++i)
      EXPECT_EQ(stored.cam_from_world_rotation[i], image.cam_from_world.rotation[i]);
    for (int i = 0; i < 3; ++i)
      EXPECT_EQ(stored.cam_from_world_translation[i], image.cam_from_world.translation[i]);
    EXPECT_EQ(index.ImageName(stored), image.name);
    EXPECT_EQ(stored.cluster, row - 1);  // one cluster per image by default
    uint32_t view = stored.first_view;
    for (size_t i = 0; i < image.points2D.size(); ++i) {
      const colmap::Point2D& point2D = image.points2D[i];
      if (point2D.point3D_id == kInvalidPoint3DId) continue;
      ASSERT_LT(view, stored.first_view + stored.num_views);
      EXPECT_EQ(0, std::memcmp(index.descriptor(view),
                               descriptors_[image_id].Row(static_cast<uint32_t>(i)), 128));
      const IndexPoint& point = index.points()[index.view_points()[view]];
      const auto& xyz = model_.points3D.at(point2D.point3D_id).xyz;
      EXPECT_EQ(point.xyz[0], xyz[0]);
      EXPECT_EQ(point.xyz[2], xyz[2]);
      EXPECT_FLOAT_EQ(index.view_keypoints()[view].x, static_cast<float>(point2D.x));
      EXPECT_EQ(index.ImageOfView(view), row - 1);
      ++view;
    }
    EXPECT_EQ(view, stored.first_view + stored.num_views);
  }
}

TEST_F(IndexBuilderTest, KeypointsAreAnOptionalSection) {
  BuildIndex(Options());
  const Index without = Index::Open(index_path_);
  EXPECT_TRUE(without.view_keypoints().empty());
  EXPECT_EQ(without.file().FindSection(section::kViewKeypoints), nullptr);
  IndexBuildOptions options = Options();
  options.keypoints = true;
  options.output_path = dir_ / "with.cwl";
  BuildIndex(options);
  const Index with = Index::Open(options.output_path);
  EXPECT_EQ(with.view_keypoints().size(), with.num_views());
  EXPECT_EQ(with.file().FindSection(section::kViewKeypoints)->flags & kSectionRequired, 0u);
  EXPECT_NO_THROW(with.Validate());
}

TEST_F(IndexBuilderTest, ViewNeighborDistanceIsTheExactNearestOtherPointInTheImage) {
  BuildIndex(Options());
  const Index index = Index::Open(index_path_);
  for (const IndexImage& image : index.images()) {
    for (uint32_t v = image.first_view; v < image.first_view + image.num_views; ++v) {
      uint32_t best = UINT32_MAX;
      for (uint32_t u = image.first_view; u < image.first_view + image.num_views; ++u) {
        if (index.view_points()[u] == index.view_points()[v]) continue;
        best = std::min(best, SquaredL2(index.descriptor(v), index.descriptor(u)));
      }
      const float expected = best == UINT32_MAX ? INFINITY : std::sqrt(static_cast<float>(best));
      EXPECT_EQ(index.view_neighbor_distances()[v], expected) << "view " << v;
    }
  }
}

TEST_F(IndexBuilderTest, CovisibilityCountsSharedPointsSymmetrically) {
  BuildIndex(Options());
  const Index index = Index::Open(index_path_);
  std::map<image_t, uint32_t> row_of;
  for (uint32_t i = 0; i < index.images().size(); ++i) row_of[index.images()[i].image_id] = i;
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> expected;
  for (const auto& [id, point] : model_.points3D) {
    std::set<uint32_t> seen;
    for (const auto& element : point.track) seen.insert(row_of[element.image_id]);
    for (uint32_t a : seen) {
      for (uint32_t b : seen) {
        if (a != b) ++expected[{a, b}];
      }
    }
  }
  std::map<std::pair<uint32_t, uint32_t>, uint32_t> stored;
  for (uint32_t i = 0; i < index.images().size(); ++i) {
    for (const CovisibilityEdge& edge : index.CovisibleImages(i))
      stored[{i, edge.image_index}] = edge.shared_points;
  }
  EXPECT_EQ(stored, expected);
}

TEST_F(IndexBuilderTest, OutputIsByteIdenticalForTheSameInputAndAnyThreadCount) {
  IndexBuildOptions options = Options();
  options.threads = 1;
  BuildIndex(options);
  const auto first = test::ReadBytes(index_path_);
  options.threads = 2;
  options.output_path = dir_ / "second.cwl";
  BuildIndex(options);
  EXPECT_EQ(first, test::ReadBytes(options.output_path));
}

TEST_F(IndexBuilderTest, ClusteringFromAFileGroupsImages) {
  const auto cluster_file = dir_ / "clusters.txt";
  {
    std::ofstream out(cluster_file);
    out << "# name cluster\n";
    int i = 0;
    for (const auto& [id, image] : model_.images)
      out << image.name << " " << (i++ < 5 ? 70 : 3) << "\n";
    out << "not_in_model.jpg 5\n";
  }
  IndexBuildOptions options = Options();
  options.clustering.method = ClusteringMethod::kFile;
  options.clustering.file = cluster_file;
  const IndexBuildReport report = BuildIndex(options);
  EXPECT_EQ(report.num_clusters, 2u);
  const Index index = Index::Open(index_path_);
  EXPECT_EQ(index.images()[0].cluster, 1u);  // file id 70 -> dense 1
  EXPECT_EQ(index.images()[9].cluster, 0u);  // file id 3 -> dense 0
  EXPECT_NO_THROW(index.Validate());
}

TEST_F(IndexBuilderTest, CovisibilityClusteringReachesTheTargetCount) {
  IndexBuildOptions options = Options();
  options.clustering.method = ClusteringMethod::kCovisibility;
  options.clustering.target_clusters = 3;
  const IndexBuildReport report = BuildIndex(options);
  EXPECT_GE(report.num_clusters, 1u);
  EXPECT_LE(report.num_clusters, 3u);
  const Index index = Index::Open(index_path_);
  EXPECT_NO_THROW(index.Validate());
}

TEST_F(IndexBuilderTest, BadClusteringInputIsAClearError) {
  IndexBuildOptions options = Options();
  options.clustering.method = ClusteringMethod::kFile;
  options.clustering.file = dir_ / "clusters.txt";
  std::ofstream(options.clustering.file) << model_.images.begin()->second.name << " x\n";
  try {
    BuildIndex(options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              options.clustering.file.string() +
                  ":1: expected 'IMAGE_NAME CLUSTER_ID' with a non-negative integer id");
  }
  std::ofstream(options.clustering.file) << model_.images.begin()->second.name << " 1\n";
  EXPECT_THROW(BuildIndex(options), InputError);  // the other images have no cluster
  options.clustering.method = ClusteringMethod::kCovisibility;
  options.clustering.target_clusters = 11;
  try {
    BuildIndex(options);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()),
              "--clusters 11: expected a count in [1, 10] (the number of model images)");
  }
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

TEST_F(IndexBuilderTest, ModelAndDatabaseThatDoNotBelongTogetherAreRejected) {
  // Another image's descriptor count.
  const auto& [image_id, image] = *model_.images.begin();
  {
    colmap::DatabaseWriter writer(database_path_);
    for (const auto& [id, camera] : model_.cameras) writer.WriteCamera(camera);
    for (const auto& [id, other] : model_.images) {
      writer.WriteImage({id, other.name, other.camera_id});
      colmap::Descriptors descriptors = descriptors_[id];
      if (id == image_id) {
        descriptors.rows -= 1;
        descriptors.data.resize(size_t{descriptors.rows} * 128);
      }
      writer.WriteDescriptors(id, descriptors);
    }
    writer.Commit();
  }
  try {
    BuildIndex(Options());
    FAIL();
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("image " + std::to_string(image_id) + " '" + image.name + "' has " +
                          std::to_string(image.points2D.size() - 1) + " descriptors but " +
                          std::to_string(image.points2D.size()) + " 2D points in the model"));
  }
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

TEST(IndexBuilderSharedData, HerzJesuIndexHasTheModelsCounts) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  test::TempDir dir;
  IndexBuildOptions options;
  options.model_dir = data / "mapping_model" / "bin";
  options.database_path = data / "database.db";
  options.output_path = dir / "herz_jesu.cwl";
  const IndexBuildReport report = BuildIndex(options);
  EXPECT_EQ(report.num_images, 20u);
  EXPECT_EQ(report.num_points, 13419u);
  EXPECT_EQ(report.num_views, 63727u);
  const Index index = Index::Open(options.output_path);
  EXPECT_NO_THROW(index.Validate());
  EXPECT_NO_THROW(index.file().VerifyChecksums());
}

}  // namespace
}  // namespace cwloc
