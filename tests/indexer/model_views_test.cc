// ModelViews: what the index stores about a model, and the model without some of its images.
#include "indexer/model_views.h"

#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "colmap/reconstruction_io.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// The shared data's mapping model is `colmap image_deleter` of its full model and the queries:
// WithoutImages of the full model's views must be the mapping model's, view for view.
TEST(ModelViewsTest, WithoutImagesIsColmapsImageDeleter) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  const colmap::DatabaseReader database(data / "database.db");
  const ModelViews full =
      GatherModelViews(colmap::ReadReconstruction(data / "full_model" / "bin"), database);
  const ModelViews mapping =
      GatherModelViews(colmap::ReadReconstruction(data / "mapping_model" / "bin"), database);
  std::set<std::string> queries;
  std::ifstream list(data / "query_list.txt");
  for (std::string name; list >> name;) queries.insert(name);
  ASSERT_EQ(queries.size(), 5u);
  std::vector<bool> left_out;
  for (const IndexImage& image : full.images)
    left_out.push_back(queries.count(std::string(full.ImageName(image))) > 0);

  ModelViews full_images = full;
  for (size_t i = 0; i < full_images.images.size(); ++i) full_images.images[i].cluster = i;
  const ModelViews rest = WithoutImages(full_images, left_out);
  ASSERT_EQ(rest.images.size(), mapping.images.size());
  ASSERT_EQ(rest.point_ids, mapping.point_ids);  // 13,419 points
  ASSERT_EQ(rest.view_points, mapping.view_points);
  EXPECT_EQ(rest.tracks, mapping.tracks);
  EXPECT_EQ(rest.descriptors, mapping.descriptors);
  EXPECT_EQ(rest.strings, mapping.strings);  // the left-out images' names go too
  for (size_t i = 0; i < rest.images.size(); ++i) {
    EXPECT_EQ(rest.ImageName(rest.images[i]), mapping.ImageName(mapping.images[i]));
    EXPECT_EQ(rest.images[i].first_view, mapping.images[i].first_view);
    EXPECT_EQ(rest.images[i].num_views, mapping.images[i].num_views);
    EXPECT_EQ(rest.images[i].cluster, i);  // renumbered densely
  }
  for (size_t p = 0; p < rest.points.size(); ++p) {
    EXPECT_EQ(rest.points[p].first_track, mapping.points[p].first_track);
    EXPECT_EQ(rest.points[p].track_length, mapping.points[p].track_length);
  }
}

}  // namespace
}  // namespace cwloc
