#include "indexer/index_builder.h"

#include <gmock/gmock.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>

#include "format/index.h"
#include "indexer/index_extract.h"
#include "tests/indexer/indexer_fixture.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

class IndexBuilderTest : public test::IndexerFixture {
 protected:
  static std::string ImageNameAt(const Index& index, size_t image) {
    return std::string(index.ImageName(index.images()[image]));
  }
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
      EXPECT_EQ(0, std::memcmp(index.ViewDescriptor(view, nullptr),
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

// --point-colors: each point's colour in the model, kept by a tile for its points.
TEST_F(IndexBuilderTest, PointColorsAreTheModelsAndAnOptionalSectionATileKeeps) {
  BuildIndex(Options());
  const Index without = Index::Open(index_path_);
  EXPECT_TRUE(without.point_colors().empty());
  EXPECT_EQ(without.file().FindSection(section::kPointColors), nullptr);
  EXPECT_FALSE(
      nlohmann::json::parse(without.manifest_json())["build_parameters"].contains("point_colors"));

  IndexBuildOptions options = Options();
  options.point_colors = true;
  options.output_path = dir_ / "colored.cwl";
  BuildIndex(options);
  const Index with = Index::Open(options.output_path);
  EXPECT_EQ(with.file().FindSection(section::kPointColors)->flags & kSectionRequired, 0u);
  EXPECT_EQ(with.file().header().format_minor, 5);  // PIDS, which every full build writes
  EXPECT_TRUE(
      nlohmann::json::parse(with.manifest_json())["build_parameters"]["point_colors"].get<bool>());
  // The model's colour of the point at each stored position.
  std::map<std::array<double, 3>, std::array<uint8_t, 3>> color_at;
  std::set<std::array<uint8_t, 3>> colors;
  for (const auto& [id, point] : model_.points3D) {
    color_at[point.xyz] = point.color;
    colors.insert(point.color);
  }
  ASSERT_GT(colors.size(), 1u);  // the fixture's points are not all one colour
  const auto expect_model_colors = [&](const Index& index) {
    ASSERT_EQ(index.point_colors().size(), index.num_points());
    for (uint32_t p = 0; p < index.num_points(); ++p) {
      const PointColor& stored = index.point_colors()[p];
      EXPECT_EQ((std::array<uint8_t, 3>{stored.rgb[0], stored.rgb[1], stored.rgb[2]}),
                color_at.at(index.PointXyz(p)))
          << p;
    }
  };
  expect_model_colors(with);

  std::ofstream(dir_ / "images.txt") << ImageNameAt(with, 0) << "\n";
  IndexExtractOptions extract;
  extract.index_path = options.output_path;
  extract.images_file = dir_ / "images.txt";
  extract.output_path = dir_ / "tile.cwl";
  ExtractIndex(extract);
  const Index tile = Index::Open(extract.output_path);
  EXPECT_LT(tile.num_points(), with.num_points());
  expect_model_colors(tile);
}

TEST_F(IndexBuilderTest, ViewNeighborDistanceIsTheExactNearestOtherPointInTheImage) {
  BuildIndex(Options());
  const Index index = Index::Open(index_path_);
  for (const IndexImage& image : index.images()) {
    for (uint32_t v = image.first_view; v < image.first_view + image.num_views; ++v) {
      uint32_t best = UINT32_MAX;
      for (uint32_t u = image.first_view; u < image.first_view + image.num_views; ++u) {
        if (index.view_points()[u] == index.view_points()[v]) continue;
        best = std::min(
            best, SquaredL2(index.ViewDescriptor(v, nullptr), index.ViewDescriptor(u, nullptr)));
      }
      const float expected = best == UINT32_MAX ? INFINITY : std::sqrt(static_cast<float>(best));
      EXPECT_EQ(index.view_neighbor_distances()[v], expected) << "view " << v;
    }
  }
}

// Format 1.2's sections, and 1.5's point ids (what `update` follows the model's points by).
TEST_F(IndexBuilderTest, CompactIndexCodesEachPointsMeanDescriptorAndKeepsPointIds) {
  IndexBuildOptions options = Options();
  options.code_bytes = 16;
  options.calibration_samples = 0;
  BuildIndex(options);
  const Index index = Index::Open(index_path_);
  EXPECT_NO_THROW(index.Validate());
  EXPECT_NO_THROW(index.file().VerifyChecksums());
  EXPECT_EQ(index.file().header().format_minor, 5);
  EXPECT_EQ(nlohmann::json::parse(index.manifest_json()).at("format_version"), "1.5");
  std::vector<uint64_t> ids;
  for (const auto& [id, point] : model_.points3D) ids.push_back(id);
  EXPECT_THAT(std::vector<uint64_t>(index.point_ids().begin(), index.point_ids().end()),
              testing::ElementsAreArray(ids));
  EXPECT_EQ(nlohmann::json::parse(index.manifest_json())
                .at("build_parameters")
                .at("descriptors")
                .at("code_bytes"),
            16);
  ASSERT_TRUE(index.coded());
  EXPECT_EQ(index.file().FindSection(section::kDescriptors), nullptr);
  EXPECT_EQ(index.file().FindSection(section::kViewNeighbor), nullptr);
  EXPECT_EQ(index.file().FindSection(section::kPoints), nullptr);
  EXPECT_TRUE(index.points().empty());
  EXPECT_EQ(index.num_views(), model_.NumObservations());
  ASSERT_EQ(index.num_points(), model_.points3D.size());
  EXPECT_EQ(index.codes().NumRows(), index.num_points());
  EXPECT_EQ(index.kd_forest().NumDescriptors(), index.num_points());

  // Each subspace's code is the stored centroid nearest the point's rounded mean descriptor
  // (up to the centroids' rounding to bytes: at most sqrt(dims) / 2 each way).
  const DescriptorCodes& codes = index.codes();
  constexpr uint32_t kDims = 128 / 16;
  size_t row = 0;
  for (const auto& [point_id, point] : model_.points3D) {  // the index keeps id order
    // PORG + PNTF: a float offset from the mean position keeps the point to float precision.
    const std::array<double, 3> xyz = index.PointXyz(uint32_t(row));
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(xyz[i], point.xyz[i], 1e-6 * (1 + std::abs(point.xyz[i]))) << point_id;
    double mean[128] = {};
    for (const colmap::TrackElement& element : point.track) {
      const uint8_t* descriptor = descriptors_.at(element.image_id).Row(element.point2D_idx);
      for (int d = 0; d < 128; ++d) mean[d] += descriptor[d];
    }
    for (double& value : mean) value = std::round(value / point.track.size());
    auto distance = [&](uint32_t s, uint32_t c) {
      double squared = 0;
      for (uint32_t d = 0; d < kDims; ++d) {
        const double diff = mean[s * kDims + d] - codes.codebook[(s * 256 + c) * kDims + d];
        squared += diff * diff;
      }
      return std::sqrt(squared);
    };
    for (uint32_t s = 0; s < 16; ++s) {
      double nearest = INFINITY;
      for (uint32_t c = 0; c < 256; ++c) nearest = std::min(nearest, distance(s, c));
      EXPECT_LE(distance(s, codes.Code(row)[s]), nearest + std::sqrt(kDims))
          << "point " << point_id << " subspace " << s;
    }
    ++row;
  }

  // PVNN: per point, the nearest other point's decoded descriptor in any image (the default
  // clusters) that sees it.
  uint8_t a[128], b[128];
  for (uint32_t p = 0; p < index.num_points(); ++p) {
    uint32_t best = UINT32_MAX;
    for (const uint32_t view : index.TrackOf(p)) {
      const IndexImage& image = index.images()[index.ImageOfView(view)];
      for (uint32_t u = image.first_view; u < image.first_view + image.num_views; ++u) {
        if (index.view_points()[u] == p) continue;
        best = std::min(best, SquaredL2(index.RowDescriptor(p, a),
                                        index.RowDescriptor(index.view_points()[u], b)));
      }
    }
    const float expected = best == UINT32_MAX ? INFINITY : std::sqrt(static_cast<float>(best));
    EXPECT_EQ(index.point_neighbor_distances()[p], expected) << "point " << p;
  }
}

TEST_F(IndexBuilderTest, CodeBytesThatDoNotSplitADescriptorAreRefused) {
  IndexBuildOptions options = Options();
  options.code_bytes = 12;
  EXPECT_EQ(test::InputErrorOf([&] { BuildIndex(options); }),
            "--code-bytes 12: expected 0 (full descriptors) or 4, 8, 16, 32 or 64");
  EXPECT_FALSE(std::filesystem::exists(index_path_));
}

// BuildIndex, the C++ entry point, checks the build option table's ranges before it reads
// anything (ValidateBuildOptions): the model and database here do not exist.
TEST_F(IndexBuilderTest, OutOfRangeOptionsAreRefusedBeforeTheModelIsRead) {
  IndexBuildOptions options = Options();
  options.model_dir = dir_ / "nonexistent";
  options.database_path = dir_ / "nonexistent.db";
  options.forest.max_leaf_size = 255;
  EXPECT_EQ(test::InputErrorOf([&] { BuildIndex(options); }), "--leaf-size 255: expected 1 to 254");
  options.forest.max_leaf_size = 8;
  options.forest.num_trees = 0;
  EXPECT_EQ(test::InputErrorOf([&] { BuildIndex(options); }), "--trees 0: expected 1 to 64");
  EXPECT_FALSE(std::filesystem::exists(index_path_));
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

// PCAL's values are checked at open (the localizer scales every covariance by them), with a
// message naming the file and the section; checksums are verify's.
TEST_F(IndexBuilderTest, ACorruptCovarianceCalibrationIsRefusedAtOpen) {
  BuildIndex(Options());
  uint64_t offset = 0;
  {
    const Index index = Index::Open(index_path_);
    ASSERT_NE(index.covariance_calibration(), nullptr);
    EXPECT_EQ(index.covariance_calibration()->sampled, 10u);  // every fixture image
    offset = index.file().FindSection(section::kCovarianceCalibration)->offset;
  }
  const auto open_error = [&](size_t field, const auto& value) {
    std::vector<uint8_t> bytes = test::ReadBytes(index_path_);
    std::memcpy(bytes.data() + offset + field, &value, sizeof(value));
    const auto corrupt = dir_ / "corrupt.cwl";
    test::WriteBytes(corrupt, bytes);
    try {
      Index::Open(corrupt);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("opened");
  };
  const std::string name = (dir_ / "corrupt.cwl").string();
  EXPECT_EQ(open_error(offsetof(IndexCovarianceCalibration, position_scale), -1.0f),
            name + ": section 'PCAL': scale -1.000000 is not a finite number >= 0");
  EXPECT_EQ(open_error(offsetof(IndexCovarianceCalibration, rotation_scale) + 8, NAN),
            name + ": section 'PCAL': scale nan is not a finite number >= 0");
  EXPECT_EQ(open_error(offsetof(IndexCovarianceCalibration, localized), uint32_t{11}),
            name + ": section 'PCAL': 11 samples localized of 10");
}

TEST_F(IndexBuilderTest, OutputIsByteIdenticalForTheSameInputAndAnyThreadCount) {
  for (const uint32_t code_bytes : {0u, 16u}) {  // a compact index trains its codes on threads
    IndexBuildOptions options = Options();
    options.code_bytes = code_bytes;
    options.threads = 1;
    BuildIndex(options);
    const auto first = test::ReadBytes(index_path_);
    options.threads = 2;
    options.output_path = dir_ / "second.cwl";
    BuildIndex(options);
    EXPECT_EQ(first, test::ReadBytes(options.output_path)) << code_bytes << "-byte codes";
  }
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
  options.calibration_samples = 0;  // the calibration on real data: CovarianceCalibrationTest
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
