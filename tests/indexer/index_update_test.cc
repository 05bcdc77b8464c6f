// cwloc-index update and apply: an updated index holds what a full build of the grown model
// holds (every section but the manifest and the kd-forest, v_NN bit for bit), its kd-forest
// finds every row, apply rebuilds it bit for bit, and each refusal says why.
#include "indexer/index_update.h"

#include <gmock/gmock.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <numeric>
#include <set>

#include "colmap/reconstruction_io.h"
#include "delta/apply_delta.h"
#include "delta/covisibility.h"
#include "format/index.h"
#include "format/xxhash64.h"
#include "indexer/index_extract.h"
#include "indexer/point_codes.h"
#include "kdtree/kd_forest.h"
#include "tests/colmap/model_without_images.h"
#include "tests/indexer/indexer_fixture.h"

namespace cwloc {
namespace {

using testing::HasSubstr;

// A compact index whose codebook is its parent's, with one row per point of `model_dir`, whose
// PVNN is what the build's computation gives on the index's own clusters and decoded codes.
void ExpectCompactAndExact(const std::filesystem::path& path, const std::filesystem::path& parent,
                           const std::filesystem::path& model_dir,
                           const std::filesystem::path& database_path) {
  const Index index = Index::Open(path);
  index.Validate();
  ASSERT_TRUE(index.coded());
  const Index parent_index = Index::Open(parent);
  const std::span<const uint8_t> codebook = parent_index.codes().codebook;
  EXPECT_TRUE(std::equal(index.codes().codebook.begin(), index.codes().codebook.end(),
                         codebook.begin(), codebook.end()));
  ModelViews views = GatherModelViews(colmap::ReadReconstruction(model_dir),
                                      colmap::DatabaseReader(database_path));
  ASSERT_EQ(views.images.size(), index.images().size());
  ASSERT_EQ(views.num_views(), index.num_views());
  ASSERT_EQ(views.points.size(), index.num_points());
  // Each point's code is its parent's, or the codebook's of its views' mean descriptor as the
  // database holds them (the update reads them only for the points it may code anew).
  std::vector<uint32_t> all_points(views.points.size());
  for (uint32_t p = 0; p < all_points.size(); ++p) all_points[p] = p;
  const uint32_t code_bytes = index.codes().code_bytes;
  const std::vector<uint8_t> coded_anew =
      CodePointsWithCodebook(views, all_points, codebook, code_bytes, 2);
  std::map<uint64_t, uint32_t> parent_row;
  for (uint32_t p = 0; p < parent_index.num_points(); ++p)
    parent_row[parent_index.point_ids()[p]] = p;
  size_t anew = 0;
  for (uint32_t p = 0; p < index.num_points(); ++p) {
    const auto code = [&](std::span<const uint8_t> codes, uint32_t row) {
      return codes.subspan(size_t(row) * code_bytes, code_bytes);
    };
    const std::span<const uint8_t> stored_code = code(index.codes().codes, p);
    const auto same = [&](std::span<const uint8_t> other) {
      return std::equal(stored_code.begin(), stored_code.end(), other.begin(), other.end());
    };
    const auto from = parent_row.find(index.point_ids()[p]);
    if (from != parent_row.end() && same(code(parent_index.codes().codes, from->second))) continue;
    ASSERT_TRUE(same(code(coded_anew, p))) << "point " << p;
    ++anew;
  }
  EXPECT_GT(anew, 0u);
  Clustering clustering;
  for (const IndexImage& image : index.images()) {
    clustering.cluster_of_image.push_back(image.cluster);
    clustering.num_clusters = std::max(clustering.num_clusters, image.cluster + 1);
  }
  std::vector<uint8_t> decoded(index.num_points() * 128);
  for (uint32_t p = 0; p < index.num_points(); ++p)
    index.codes().Decode(p, &decoded[size_t(p) * 128]);
  const std::vector<float> expected = ComputePointNeighborDistances(&views, decoded, clustering, 2);
  const std::span<const float> stored = index.point_neighbor_distances();
  ASSERT_EQ(stored.size(), expected.size());
  for (size_t p = 0; p < expected.size(); ++p) ASSERT_EQ(stored[p], expected[p]) << "point " << p;
}

class IndexUpdateTest : public test::IndexerFixture {
 protected:
  colmap::Reconstruction Without(const std::set<image_t>& ids) const {
    return test::ModelWithoutImages(model_, ids);
  }

  std::filesystem::path WriteModel(const colmap::Reconstruction& model,
                                   const std::string& name) const {
    const std::filesystem::path dir = dir_ / name;
    std::filesystem::create_directories(dir);
    colmap::WriteReconstruction(model, dir, colmap::ModelFormat::kBinary);
    return dir;
  }

  std::filesystem::path Build(const std::filesystem::path& model_dir, const std::string& name,
                              uint32_t code_bytes = 0) const {
    IndexBuildOptions options;
    options.model_dir = model_dir;
    options.database_path = database_path_;
    options.output_path = dir_ / name;
    options.calibration_samples = 0;
    options.code_bytes = code_bytes;
    if (code_bytes != 0) options.forest.num_trees = 2;
    BuildIndex(options);
    return options.output_path;
  }

  IndexUpdateOptions Update(const std::filesystem::path& parent,
                            const std::filesystem::path& model_dir, const std::string& name) const {
    IndexUpdateOptions options;
    options.index_path = parent;
    options.model_dir = model_dir;
    options.database_path = database_path_;
    options.output_path = dir_ / (name + ".cwl");
    options.delta_path = dir_ / (name + ".cwld");
    return options;
  }

  // The fixture's last `count` image ids: what a grown model adds to the old one.
  std::set<image_t> LastImages(size_t count) const {
    std::set<image_t> ids;
    for (auto it = model_.images.rbegin(); ids.size() < count; ++it) ids.insert(it->first);
    return ids;
  }

  static std::map<std::string, uint64_t> Checksums(const std::filesystem::path& path) {
    const IndexFile file = IndexFile::Open(path);
    std::map<std::string, uint64_t> out;
    for (const SectionEntry& entry : file.sections())
      out[SectionTagName(entry.tag)] = entry.checksum;
    return out;
  }

  // Every section a full build and an update share: all but the manifest and the kd-forest.
  static void ExpectSameAsFullBuild(const std::filesystem::path& updated,
                                    const std::filesystem::path& full) {
    std::map<std::string, uint64_t> a = Checksums(updated), b = Checksums(full);
    for (const char* tag : {"MANI", "KDND", "KDRT", "KDLF"}) a.erase(tag), b.erase(tag);
    EXPECT_EQ(a, b);
    EXPECT_EQ(a.count("VNND"), 1u);
    EXPECT_EQ(a.count("PIDS"), 1u);
  }

  // Each row's own descriptor, searched with a budget of one bucket (8 rows), finds the row at
  // distance 0 in the first leaf it descends to: new rows sit where the search looks for them.
  static void ExpectEveryRowFindsItself(const std::filesystem::path& path) {
    const Index index = Index::Open(path);
    index.Validate();
    KdForestSearcher searcher(index.kd_forest());
    KdSearchOptions options;
    options.max_checks = 8;  // one bucket: the first leaf the search reaches
    options.interleave = 1;
    std::vector<KdNeighbor> nearest(1);
    uint8_t scratch[128];  // a compact index's rows are codes, decoded here
    for (uint32_t row = 0; row < index.num_rows(); ++row) {
      const KdSearchResult found =
          searcher.Search(index.RowDescriptor(row, scratch), options, nearest);
      ASSERT_EQ(found.num_neighbors, 1u) << "row " << row;
      ASSERT_EQ(nearest[0].distance, 0u) << "row " << row;
    }
  }
};

TEST_F(IndexUpdateTest, HoldsWhatAFullBuildOfTheGrownModelHoldsAndApplyRebuildsItBitForBit) {
  const std::set<image_t> held_out = LastImages(3);
  const auto old_index = Build(WriteModel(Without(held_out), "old"), "old.cwl");
  const IndexUpdateOptions options = Update(old_index, model_dir_, "grown");
  const IndexUpdateReport report = UpdateIndex(options);
  const auto full_index = Build(model_dir_, "full.cwl");

  EXPECT_FALSE(report.rebuilt);
  EXPECT_EQ(report.images_added, 3u);
  EXPECT_EQ(report.images_removed, 0u);
  EXPECT_EQ(report.num_views, model_.NumObservations());
  EXPECT_EQ(report.num_views,
            Index::Open(old_index).num_views() + report.views_added - report.views_removed);
  EXPECT_GT(report.views_added, 0u);
  // The new images' and the changed ones' descriptors come from the database, the rest from
  // the index.
  EXPECT_EQ(report.images_read, report.images_added + report.images_changed);
  ExpectSameAsFullBuild(options.output_path, full_index);
  ExpectEveryRowFindsItself(options.output_path);
  // The report counts what the delta carries.
  const IndexDelta delta = ReadDelta(options.delta_path);
  EXPECT_EQ(report.neighbor_distances_changed, delta.view_neighbor_changes.size());
  EXPECT_EQ(report.points_moved, delta.point_moves.size());
  EXPECT_EQ(report.views_added, delta.new_view_points.size());

  const Index updated = Index::Open(options.output_path);
  const auto manifest = nlohmann::json::parse(updated.manifest_json());
  EXPECT_EQ(manifest["update"]["updates"], 1);
  EXPECT_EQ(manifest["update"]["images_added"], 3);
  EXPECT_EQ(manifest["counts"]["views"], model_.NumObservations());

  const std::filesystem::path applied = dir_ / "applied.cwl";
  ApplyDelta(old_index, options.delta_path, applied, 1);
  EXPECT_EQ(test::ReadBytes(applied), test::ReadBytes(options.output_path));
}

// The graph an update composes keeps the parent rows it is told to keep (renumbered) and counts
// the others: on an index's own arrays, keeping every row or none gives the index's graph, and
// a kept row is copied as given, not counted.
TEST_F(IndexUpdateTest, TheCovisibilityGraphKeepsTheRowsItIsGivenAndCountsTheRest) {
  const Index index = Index::Open(Build(model_dir_, "all.cwl"));
  const std::vector<IndexImage> images(index.images().begin(), index.images().end());
  const std::vector<IndexPoint> points(index.points().begin(), index.points().end());
  const std::vector<uint32_t> tracks(index.tracks().begin(), index.tracks().end());
  const std::vector<uint32_t> view_points(index.view_points().begin(), index.view_points().end());
  const auto same_as_index = [&](const CovisibilityGraph& graph) {
    return std::equal(graph.offsets.begin(), graph.offsets.end(),
                      index.covisibility_offsets().begin(), index.covisibility_offsets().end()) &&
           graph.edges.size() == index.covisibility_edges().size() &&
           std::memcmp(graph.edges.data(), index.covisibility_edges().data(),
                       graph.edges.size() * sizeof(CovisibilityEdge)) == 0;
  };
  ASSERT_GE(images.size(), 3u);
  std::vector<uint32_t> identity(images.size());
  std::iota(identity.begin(), identity.end(), 0u);
  KeptCovisibilityRows kept;
  kept.offsets = index.covisibility_offsets();
  kept.edges = index.covisibility_edges();
  kept.child_of_parent_image = identity;
  kept.kept_from.assign(images.size(), KeptCovisibilityRows::kNotKept);
  EXPECT_TRUE(same_as_index(BuildCovisibilityGraph(images, points, tracks, view_points, 2, &kept)));
  kept.kept_from = identity;
  EXPECT_TRUE(same_as_index(BuildCovisibilityGraph(images, points, tracks, view_points, 2, &kept)));

  // Image 0 keeps a made-up parent row: one edge to parent image 0, renumbered to image 2.
  const std::vector<uint32_t> offsets = {0, 1};
  const std::vector<CovisibilityEdge> edges = {{0, 77}};
  std::vector<uint32_t> renumbered = {2};
  kept.offsets = offsets;
  kept.edges = edges;
  kept.child_of_parent_image = renumbered;
  kept.kept_from.assign(images.size(), KeptCovisibilityRows::kNotKept);
  kept.kept_from[0] = 0;
  const CovisibilityGraph graph =
      BuildCovisibilityGraph(images, points, tracks, view_points, 1, &kept);
  ASSERT_EQ(graph.offsets[1], 1u);
  EXPECT_EQ(graph.edges[0].image_index, 2u);
  EXPECT_EQ(graph.edges[0].shared_points, 77u);
  EXPECT_EQ(graph.offsets.back() - 1,
            index.covisibility_offsets().back() - index.covisibility_offsets()[1]);
}

// The balance bound: rows inserted since the forest's build up to a quarter of its rows are
// inserted; past it the update builds the forest afresh, as a build with the seed would.
TEST_F(IndexUpdateTest, TheKdForestIsRebuiltOncePastItsBalanceBound) {
  const auto full = Build(model_dir_, "full.cwl");
  const size_t views = Index::Open(full).num_views();
  for (const size_t held_out : {1, 4}) {
    const auto old_index = Build(WriteModel(Without(LastImages(held_out)), "old"), "old.cwl");
    const size_t old_views = Index::Open(old_index).num_views();
    const IndexUpdateReport report =
        UpdateIndex(Update(old_index, model_dir_, "grown" + std::to_string(held_out)));
    const bool past_bound = double(report.views_added) > kForestRebuildFraction * double(old_views);
    EXPECT_EQ(past_bound, held_out == 4) << report.views_added << " of " << old_views;
    EXPECT_EQ(report.forest_rebuilt, past_bound);
    const auto updated = Checksums(dir_ / ("grown" + std::to_string(held_out) + ".cwl"));
    const auto built = Checksums(full);
    for (const char* tag : {"KDND", "KDRT", "KDLF"})
      EXPECT_EQ(updated.at(tag) == built.at(tag), past_bound) << tag;
    const auto manifest = nlohmann::json::parse(
        Index::Open(dir_ / ("grown" + std::to_string(held_out) + ".cwl")).manifest_json());
    EXPECT_EQ(manifest["update"]["forest_rows_at_build"], past_bound ? views : old_views);
    EXPECT_EQ(manifest["update"]["forest_rows_inserted"], past_bound ? 0 : report.views_added);
    std::filesystem::remove_all(dir_ / "old");
  }
}

TEST_F(IndexUpdateTest, AChainOfUpdatesAppliesInOrderAndRefusesAnyOtherOrder) {
  const std::set<image_t> last_three = LastImages(3), last_one = LastImages(1);
  const auto first = Build(WriteModel(Without(last_three), "first"), "first.cwl");
  const IndexUpdateOptions to_second = Update(first, WriteModel(Without(last_one), "m2"), "second");
  UpdateIndex(to_second);
  const IndexUpdateOptions to_third = Update(to_second.output_path, model_dir_, "third");
  UpdateIndex(to_third);
  ExpectSameAsFullBuild(to_third.output_path, Build(model_dir_, "full.cwl"));
  EXPECT_EQ(
      nlohmann::json::parse(Index::Open(to_third.output_path).manifest_json())["update"]["updates"],
      2);

  const std::filesystem::path second = dir_ / "applied_second.cwl", third = dir_ / "applied.cwl";
  ApplyDelta(first, to_second.delta_path, second, 1);
  ApplyDelta(second, to_third.delta_path, third, 1);
  EXPECT_EQ(test::ReadBytes(third), test::ReadBytes(to_third.output_path));

  const std::filesystem::path out_of_order = dir_ / "out_of_order.cwl";
  const FileHeader first_header = IndexFile::Open(first).header();
  const FileHeader second_header = IndexFile::Open(second).header();
  try {
    ApplyDelta(first, to_third.delta_path, out_of_order, 1);
    FAIL() << "applied the second delta of a chain to the first index";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              to_third.delta_path.string() + ": made for the index with checksum " +
                  HashHex(second_header.header_checksum) + " (" +
                  std::to_string(second_header.file_size) + " bytes), and " + first.string() +
                  " has " + HashHex(first_header.header_checksum) + " (" +
                  std::to_string(first_header.file_size) +
                  " bytes): apply a chain's deltas in order, each to the index the one before "
                  "made");
  }
  EXPECT_FALSE(std::filesystem::exists(out_of_order));
}

TEST_F(IndexUpdateTest, RemovedImagesLeaveWhatAFullBuildWithoutThemHolds) {
  const auto index = Build(model_dir_, "all.cwl");
  const std::set<image_t> removed = {model_.images.begin()->first,
                                     std::next(model_.images.begin(), 4)->first};
  std::ofstream list(dir_ / "remove.txt");
  for (image_t id : removed) list << model_.images.at(id).name << "\n";
  list.close();
  IndexUpdateOptions options = Update(index, model_dir_, "removed");
  options.remove_images_file = dir_ / "remove.txt";
  const IndexUpdateReport report = UpdateIndex(options);
  EXPECT_EQ(report.images_removed, 2u);
  EXPECT_EQ(report.images_added, 0u);
  ExpectSameAsFullBuild(options.output_path,
                        Build(WriteModel(Without(removed), "less"), "less.cwl"));
  ExpectEveryRowFindsItself(options.output_path);
  ApplyDelta(index, options.delta_path, dir_ / "applied.cwl", 1);
  EXPECT_EQ(test::ReadBytes(dir_ / "applied.cwl"), test::ReadBytes(options.output_path));

  // A name the model does not have is named with its line, and nothing is written.
  std::ofstream(dir_ / "unknown.txt") << "# images to take out\n\n  nowhere.jpg \n";
  IndexUpdateOptions unknown = Update(index, model_dir_, "unknown");
  unknown.remove_images_file = dir_ / "unknown.txt";
  try {
    UpdateIndex(unknown);
    FAIL() << "removed an image the model does not have";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()), unknown.remove_images_file.string() +
                                             ":3: image 'nowhere.jpg' is not in the model " +
                                             model_dir_.string());
  }
  EXPECT_FALSE(std::filesystem::exists(unknown.output_path));
}

// A compact index: new points and old ones whose views changed are coded with the index's own
// codebook, PVNN equals what the build's computation gives on the updated index's codes and
// clusters, every point row finds itself, and apply rebuilds it bit for bit (also a removal).
TEST_F(IndexUpdateTest, ACompactIndexCodesNewPointsWithItsCodebookAndKeepsPvnnExact) {
  const auto old_index = Build(WriteModel(Without(LastImages(3)), "old"), "old.cwl", 8);
  const IndexUpdateOptions options = Update(old_index, model_dir_, "grown");
  const IndexUpdateReport report = UpdateIndex(options);
  EXPECT_FALSE(report.rebuilt);
  EXPECT_EQ(report.images_added, 3u);
  EXPECT_GT(report.points_added, 0u);
  EXPECT_GT(report.points_recoded, 0u);  // old points the new images see
  EXPECT_GE(report.images_read, 3u);     // the new ones, and the old ones that see their points
  const IndexDelta delta = ReadDelta(options.delta_path);
  EXPECT_EQ(report.neighbor_distances_changed, delta.view_neighbor_changes.size());
  EXPECT_GT(report.neighbor_distances_changed, 0u);
  EXPECT_EQ(report.points_added + report.points_recoded, delta.new_points.size());
  ExpectCompactAndExact(options.output_path, old_index, model_dir_, database_path_);
  ExpectEveryRowFindsItself(options.output_path);
  ApplyDelta(old_index, options.delta_path, dir_ / "applied.cwl", 1);
  EXPECT_EQ(test::ReadBytes(dir_ / "applied.cwl"), test::ReadBytes(options.output_path));

  // A delta without the compact parent's codes (as a full index's would be) is refused.
  IndexDelta without_codes = delta;
  without_codes.code_bytes = 0;
  without_codes.new_point_codes.clear();
  WriteDelta(dir_ / "without_codes.cwld", without_codes);
  try {
    ApplyDelta(old_index, dir_ / "without_codes.cwld", dir_ / "refused.cwl", 1);
    FAIL() << "applied a delta without codes to a compact index";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()), (dir_ / "without_codes.cwld").string() +
                                             ": the delta's point codes are of 0 bytes, " +
                                             old_index.string() +
                                             "'s of 8 (0: a full index, which stores descriptors)");
  }
  EXPECT_FALSE(std::filesystem::exists(dir_ / "refused.cwl"));

  const std::set<image_t> removed = {std::next(model_.images.begin(), 2)->first};
  std::ofstream(dir_ / "remove.txt") << model_.images.at(*removed.begin()).name << "\n";
  IndexUpdateOptions removal = Update(options.output_path, model_dir_, "removed");
  removal.remove_images_file = dir_ / "remove.txt";
  const IndexUpdateReport removed_report = UpdateIndex(removal);
  EXPECT_EQ(removed_report.images_removed, 1u);
  EXPECT_GT(removed_report.points_removed, 0u);
  ExpectCompactAndExact(removal.output_path, old_index, WriteModel(Without(removed), "less"),
                        database_path_);
  ExpectEveryRowFindsItself(removal.output_path);
  ApplyDelta(options.output_path, removal.delta_path, dir_ / "applied_removal.cwl", 2);
  EXPECT_EQ(test::ReadBytes(dir_ / "applied_removal.cwl"), test::ReadBytes(removal.output_path));
}

// A new image that sees two old points: the clusters of the images that see those points are
// recomputed, and so are the other clusters of every point in them, whose v_NN the points'
// PVNN takes when smaller; PVNN stays exact (it would not without the second step).
TEST_F(IndexUpdateTest, ACompactUpdateTouchingTwoPointsComputesTheirNeighboursClustersToo) {
  const image_t added = *LastImages(1).begin();
  const colmap::Reconstruction old_model = Without({added});
  colmap::Reconstruction grown = model_;
  uint32_t kept = 0;
  for (colmap::Point2D& point : grown.images.at(added).points2D) {
    if (point.point3D_id == kInvalidPoint3DId) continue;
    if (kept < 2 && old_model.points3D.count(point.point3D_id) > 0) {
      ++kept;
      continue;
    }
    std::erase_if(grown.points3D.at(point.point3D_id).track,
                  [&](const colmap::TrackElement& e) { return e.image_id == added; });
    point.point3D_id = kInvalidPoint3DId;
  }
  grown = test::ModelWithoutImages(grown, {});  // points left with one view go
  ASSERT_EQ(kept, 2u);
  const auto old_index = Build(WriteModel(old_model, "old"), "old.cwl", 8);
  const std::filesystem::path grown_dir = WriteModel(grown, "grown_model");
  const IndexUpdateOptions options = Update(old_index, grown_dir, "grown");
  const IndexUpdateReport report = UpdateIndex(options);
  EXPECT_EQ(report.points_recoded, 2u);
  EXPECT_EQ(report.points_added, 0u);
  // Only the images that see those two points are read from the database (a compact index
  // holds no descriptors; the others' points keep their codes).
  std::set<image_t> seeing;
  for (const colmap::Point2D& point : grown.images.at(added).points2D) {
    if (point.point3D_id == kInvalidPoint3DId) continue;
    for (const colmap::TrackElement& element : grown.points3D.at(point.point3D_id).track)
      seeing.insert(element.image_id);
  }
  EXPECT_EQ(report.images_read, seeing.size());
  EXPECT_LT(report.images_read, report.num_images);
  ExpectCompactAndExact(options.output_path, old_index, grown_dir, database_path_);
}

// A tile of an updated index written as the old index's tile changed by a delta (`extract
// --parent-tile`): apply rebuilds it bit for bit, it holds what a fresh extract of the updated
// index holds (every section but the manifest and the kd-forest), and every row finds itself.
TEST_F(IndexUpdateTest, ATileOfAnUpdatedIndexIsItsParentTileChangedByADelta) {
  for (const uint32_t code_bytes : {0u, 8u}) {
    SCOPED_TRACE("code bytes " + std::to_string(code_bytes));
    const std::string kind = code_bytes == 0 ? "full" : "compact";
    const image_t added = *LastImages(1).begin();
    const auto old_index =
        Build(WriteModel(Without({added}), "old_" + kind), "old_" + kind + ".cwl", code_bytes);
    const IndexUpdateOptions update = Update(old_index, model_dir_, "grown_" + kind);
    UpdateIndex(update);
    std::ofstream old_list(dir_ / "old_tile.txt"), new_list(dir_ / "new_tile.txt");
    for (auto it = model_.images.begin(); it != std::next(model_.images.begin(), 4); ++it)
      old_list << it->second.name << "\n", new_list << it->second.name << "\n";
    new_list << model_.images.at(added).name << "\n";
    old_list.close(), new_list.close();

    IndexExtractOptions old_tile;
    old_tile.index_path = old_index;
    old_tile.images_file = dir_ / "old_tile.txt";
    old_tile.output_path = dir_ / ("old_tile_" + kind + ".cwl");
    ExtractIndex(old_tile);
    IndexExtractOptions by_delta = old_tile;
    by_delta.index_path = update.output_path;
    by_delta.images_file = dir_ / "new_tile.txt";
    by_delta.output_path = dir_ / ("new_tile_" + kind + ".cwl");
    by_delta.parent_tile_path = old_tile.output_path;
    by_delta.delta_path = dir_ / ("tile_" + kind + ".cwld");
    const IndexExtractReport report = ExtractIndex(by_delta);
    EXPECT_EQ(report.num_images, 5u);
    EXPECT_GT(report.delta_bytes, 0u);
    EXPECT_LT(report.delta_bytes, report.file_bytes);
    IndexExtractOptions fresh = by_delta;
    fresh.parent_tile_path.clear(), fresh.delta_path.clear();
    fresh.output_path = dir_ / ("fresh_tile_" + kind + ".cwl");
    ExtractIndex(fresh);
    std::map<std::string, uint64_t> a = Checksums(by_delta.output_path);
    std::map<std::string, uint64_t> b = Checksums(fresh.output_path);
    for (const char* tag : {"MANI", "KDND", "KDRT", "KDLF"}) a.erase(tag), b.erase(tag);
    EXPECT_EQ(a, b);
    ExpectEveryRowFindsItself(by_delta.output_path);
    const auto manifest = nlohmann::json::parse(Index::Open(by_delta.output_path).manifest_json());
    EXPECT_EQ(manifest["update"]["updates"], 1);
    EXPECT_EQ(manifest["update"]["images_added"], 1);
    EXPECT_TRUE(manifest.contains("extracted"));

    const std::filesystem::path applied = dir_ / ("applied_tile_" + kind + ".cwl");
    ApplyDelta(old_tile.output_path, by_delta.delta_path, applied, 1);
    EXPECT_EQ(test::ReadBytes(applied), test::ReadBytes(by_delta.output_path));
    // The tile's own delta does not apply to the index it was cut from.
    EXPECT_THROW(ApplyDelta(old_index, by_delta.delta_path, dir_ / "wrong.cwl", 1), InputError);
    EXPECT_FALSE(std::filesystem::exists(dir_ / "wrong.cwl"));
  }

  // Refusals, each writing nothing.
  IndexExtractOptions options;
  options.index_path = dir_ / "grown_full.cwl";
  options.output_path = dir_ / "refused.cwl";
  options.delta_path = dir_ / "refused.cwld";
  const auto message = [&] {
    try {
      ExtractIndex(options);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("(no error)");
  };
  EXPECT_EQ(message(), "extract: --delta needs --parent-tile (the tile the delta changes)");
  options.parent_tile_path = dir_ / "old_full.cwl";
  EXPECT_EQ(message(), options.parent_tile_path.string() +
                           ": not a tile (cwloc-index extract); --parent-tile takes one");
  options.parent_tile_path = dir_ / "old_tile_compact.cwl";
  EXPECT_EQ(message(), options.parent_tile_path.string() +
                           ": cut from an index that stores descriptors otherwise (full or "
                           "compact, code size); send the tile whole");
  EXPECT_FALSE(std::filesystem::exists(options.output_path));
  EXPECT_FALSE(std::filesystem::exists(options.delta_path));
}

TEST_F(IndexUpdateTest, RefusesAModelWhoseOldPosesMovedUnlessAskedToRebuild) {
  const auto index = Build(WriteModel(Without(LastImages(2)), "old"), "old.cwl");
  colmap::Reconstruction moved = model_;
  colmap::Image& image = moved.images.begin()->second;
  image.cam_from_world.translation[0] += 0.5;
  const IndexUpdateOptions options = Update(index, WriteModel(moved, "moved"), "out");
  try {
    UpdateIndex(options);
    FAIL() << "updated from a model adjusted again";
  } catch (const UpdateRefused& refused) {
    EXPECT_THAT(refused.what(), HasSubstr(options.model_dir.string() + ": the pose of image '" +
                                          image.name + "' moved by 0.5 ("));
    EXPECT_THAT(refused.what(), HasSubstr("the model was adjusted again, not grown" +
                                          std::string(kFullBuildNeeded)));
  }
  EXPECT_FALSE(std::filesystem::exists(options.output_path));
  EXPECT_FALSE(std::filesystem::exists(options.delta_path));

  IndexUpdateOptions rebuild = options;
  rebuild.rebuild_if_needed = true;
  const IndexUpdateReport report = UpdateIndex(rebuild);
  EXPECT_TRUE(report.rebuilt);
  EXPECT_THAT(report.rebuild_reason, HasSubstr("moved by 0.5"));
  EXPECT_FALSE(std::filesystem::exists(options.delta_path));
  std::map<std::string, uint64_t> rebuilt = Checksums(options.output_path),
                                  built = Checksums(Build(options.model_dir, "moved.cwl"));
  rebuilt.erase("MANI"), built.erase("MANI");
  EXPECT_EQ(rebuilt, built);
}

TEST_F(IndexUpdateTest, RefusesOtherBuildOptionsAndAnOtherDatabase) {
  const auto index = Build(WriteModel(Without(LastImages(2)), "old"), "old.cwl");
  IndexUpdateOptions options = Update(index, model_dir_, "out");
  options.build_flags = {{"trees", OptionValue(uint32_t{8})}};
  try {
    UpdateIndex(options);
    FAIL();
  } catch (const UpdateRefused& refused) {
    EXPECT_EQ(std::string(refused.what()),
              index.string() +
                  ": the index was built with --trees 4, and this update asks for "
                  "--trees 8" +
                  kFullBuildNeeded);
  }
  options.build_flags = {{"trees", OptionValue(uint32_t{4})}, {"threads", OptionValue(int32_t{1})}};
  EXPECT_NO_THROW(UpdateIndex(options));

  // The database extracted again: the first image's descriptors differ.
  {
    colmap::DatabaseWriter writer(dir_ / "other.db");
    for (const auto& [id, camera] : model_.cameras) writer.WriteCamera(camera);
    for (const auto& [id, image] : model_.images) {
      writer.WriteImage({id, image.name, image.camera_id});
      std::vector<colmap::Keypoint> keypoints;
      for (const colmap::Point2D& point : image.points2D)
        keypoints.push_back({static_cast<float>(point.x), static_cast<float>(point.y)});
      writer.WriteKeypoints(id, keypoints);
      colmap::Descriptors descriptors = descriptors_.at(id);
      if (id == model_.images.begin()->first) {
        for (uint8_t& byte : descriptors.data) byte ^= 1;
      }
      writer.WriteDescriptors(id, descriptors);
    }
    writer.Commit();
  }
  IndexUpdateOptions other_database = Update(index, model_dir_, "other_database");
  other_database.database_path = dir_ / "other.db";
  try {
    UpdateIndex(other_database);
    FAIL();
  } catch (const UpdateRefused& refused) {
    EXPECT_EQ(std::string(refused.what()),
              other_database.database_path.string() + ": the descriptors of image '" +
                  model_.images.begin()->second.name +
                  "' differ from those the index was built from" + kFullBuildNeeded);
  }
}

TEST_F(IndexUpdateTest, ATruncatedOrCorruptDeltaIsNamedAndWritesNothing) {
  const auto index = Build(WriteModel(Without(LastImages(2)), "old"), "old.cwl");
  const IndexUpdateOptions options = Update(index, model_dir_, "grown");
  UpdateIndex(options);
  const std::vector<uint8_t> bytes = test::ReadBytes(options.delta_path);
  const std::filesystem::path damaged = dir_ / "damaged.cwld", output = dir_ / "out.cwl";

  test::WriteBytes(damaged, std::span(bytes).first(bytes.size() - 100));
  try {
    ApplyDelta(index, damaged, output, 1);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              damaged.string() + ": truncated or extended: the header says " +
                  std::to_string(bytes.size()) + " bytes, the file has " +
                  std::to_string(bytes.size() - 100));
  }
  std::vector<uint8_t> flipped = bytes;
  const IndexFile file = IndexFile::Open(options.delta_path, kDeltaContainer);
  const SectionEntry* descriptors = file.FindSection(delta_section::kNewDescriptors);
  ASSERT_NE(descriptors, nullptr);
  ASSERT_GT(descriptors->size, 0u);
  flipped[descriptors->offset + 7] ^= 0x10;
  test::WriteBytes(damaged, flipped);
  try {
    ApplyDelta(index, damaged, output, 1);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_THAT(error.what(), HasSubstr(damaged.string() + ": section "));
    EXPECT_THAT(error.what(), HasSubstr(" 'NDSC': checksum mismatch"));
  }
  try {
    ApplyDelta(index, index, output, 1);
    FAIL();
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              index.string() + ": not a cwloc index delta (wrong magic; expected \"CWLOCDLT\")");
  }
  EXPECT_FALSE(std::filesystem::exists(output));
}

// The parent's bulk sections are checked on a second thread while the model is read. A corrupt
// parent is the error reported, also when the model cannot be read (here: a folder without one)
// and the check is not done yet, and so is a flip in a section checked before the read. One
// thread or two, nothing is written.
TEST_F(IndexUpdateTest, ACorruptParentIsNamedWhicheverThreadFindsIt) {
  const auto index = Build(WriteModel(Without(LastImages(2)), "old"), "old.cwl");
  const std::vector<uint8_t> bytes = test::ReadBytes(index);
  for (const uint32_t tag : {section::kDescriptors, section::kViewPoint}) {
    for (int threads : {1, 2}) {
      SCOPED_TRACE(SectionTagName(tag) + ", threads " + std::to_string(threads));
      std::vector<uint8_t> flipped = bytes;
      {
        const IndexFile file = IndexFile::Open(index);
        const SectionEntry* entry = file.FindSection(tag);
        ASSERT_NE(entry, nullptr);
        flipped[entry->offset + 1] ^= 0x40;
      }
      const std::filesystem::path damaged = dir_ / "damaged.cwl";
      test::WriteBytes(damaged, flipped);
      IndexUpdateOptions options = Update(damaged, dir_ / "no_model", "grown");
      std::filesystem::create_directories(options.model_dir);
      options.threads = threads;
      try {
        UpdateIndex(options);
        FAIL();
      } catch (const InputError& error) {
        EXPECT_THAT(error.what(), HasSubstr(damaged.string() + ": section "));
        EXPECT_THAT(error.what(),
                    HasSubstr(" '" + SectionTagName(tag) + "': checksum mismatch (stored "));
      }
      EXPECT_FALSE(std::filesystem::exists(options.output_path));
      EXPECT_FALSE(std::filesystem::exists(options.delta_path));
    }
  }
}

// The delta's corruption sweep: a flipped byte in its header, its section table and the first
// bytes of every section (all of DHDR and the runs) is refused naming the delta with the stored
// checksums; with the checksums recomputed over the flip, apply refuses it (InputError) or
// writes the update's very bytes (a byte no one reads), and never writes another index.
TEST_F(IndexUpdateTest, EveryFlippedDeltaByteIsRefusedOrChangesNothing) {
  const auto parent = Build(WriteModel(Without(LastImages(2)), "old"), "old.cwl");
  const IndexUpdateOptions options = Update(parent, model_dir_, "grown");
  UpdateIndex(options);
  const std::vector<uint8_t> original = test::ReadBytes(options.delta_path);
  const std::vector<uint8_t> child = test::ReadBytes(options.output_path);
  std::vector<uint64_t> offsets;
  for (uint64_t b = 0; b < sizeof(FileHeader); ++b) offsets.push_back(b);
  {
    const IndexFile file = IndexFile::Open(options.delta_path, kDeltaContainer);
    const FileHeader& header = file.header();
    for (uint64_t b = 0; b < header.section_count * sizeof(SectionEntry); ++b)
      offsets.push_back(header.section_table_offset + b);
    for (const SectionEntry& entry : file.sections()) {
      const bool whole = entry.tag == delta_section::kHeader ||
                         entry.tag == delta_section::kViewRuns ||
                         entry.tag == delta_section::kPointRuns;
      for (uint64_t b = 0; b < std::min<uint64_t>(entry.size, whole ? entry.size : 48); ++b)
        offsets.push_back(entry.offset + b);
    }
  }
  const std::filesystem::path damaged = dir_ / "damaged.cwld", output = dir_ / "out.cwl";
  int refused = 0, unchanged = 0;
  for (const uint64_t offset : offsets) {
    for (const bool repaired : {false, true}) {
      std::vector<uint8_t> bytes = original;
      bytes[offset] ^= offset % 2 ? 0x80 : 0x01;
      if (repaired) RecomputeChecksums(bytes);
      test::WriteBytes(damaged, bytes);
      std::filesystem::remove(output);
      try {
        ApplyDelta(parent, damaged, output, 1);
        ASSERT_TRUE(repaired) << "byte " << offset << " flipped under its stored checksums";
        ASSERT_TRUE(test::ReadBytes(output) == child) << "byte " << offset;
        ++unchanged;
      } catch (const InputError& error) {
        EXPECT_FALSE(std::filesystem::exists(output)) << "byte " << offset;
        if (!repaired) {
          EXPECT_THAT(error.what(), testing::StartsWith(damaged.string() + ": "));
        }
        ++refused;
      }
    }
  }
  EXPECT_GT(refused, int(offsets.size()));  // every unrepaired flip, and most repaired ones
  std::cout << offsets.size() << " bytes flipped twice: " << refused << " refused, " << unchanged
            << " changed nothing\n";
}

// SIGKILL at any moment of `update` or `apply` leaves the parent as it was, and each output
// either absent (or as before) or complete, with nothing else but a killed writer's temporary.
TEST_F(IndexUpdateTest, KilledUpdatesAndAppliesLeaveTheParentAndNoPartialOutput) {
  const auto parent = Build(WriteModel(Without(LastImages(2)), "old"), "old.cwl");
  const std::vector<uint8_t> parent_bytes = test::ReadBytes(parent);
  const auto out_dir = dir_ / "out";
  std::filesystem::create_directories(out_dir);
  std::filesystem::create_directories(dir_ / "applied");
  const auto updated = out_dir / "new.cwl", delta = out_dir / "new.cwld",
             applied = dir_ / "applied" / "applied.cwl";
  const std::string tool = test::ToolPath("cwloc-index").string();
  const std::vector<std::string> update = {tool,         "update",
                                           "--index",    parent.string(),
                                           "--model",    model_dir_.string(),
                                           "--database", database_path_.string(),
                                           "--threads",  "1",
                                           "-o",         updated.string(),
                                           "--delta",    delta.string()};
  const std::vector<std::string> apply = {tool,      "apply",         "--index",   parent.string(),
                                          "--delta", delta.string(),  "--threads", "1",
                                          "-o",      applied.string()};
  for (const auto& [args, outputs] :
       {std::pair{update, std::vector{updated, delta}}, std::pair{apply, std::vector{applied}}}) {
    const auto start = std::chrono::steady_clock::now();
    ASSERT_EQ(test::Wait(test::Spawn(args)), 0);
    const auto duration = std::chrono::steady_clock::now() - start;
    std::vector<std::vector<uint8_t>> complete;
    for (const auto& output : outputs) complete.push_back(test::ReadBytes(output));
    std::vector<pid_t> killed;
    for (int kill_number = 0; kill_number < 12; ++kill_number) {
      const bool replacing = kill_number % 2 == 1;
      for (size_t i = 0; i < outputs.size(); ++i) {
        std::filesystem::remove(outputs[i]);
        if (replacing) test::WriteBytes(outputs[i], complete[i]);
      }
      const pid_t pid = test::Spawn(args);
      killed.push_back(pid);
      test::KillAfter(pid, duration * (test::Rng()() % 1000) / 1000);
      EXPECT_TRUE(test::ReadBytes(parent) == parent_bytes) << "the parent changed";
      for (const auto& entry : std::filesystem::directory_iterator(outputs[0].parent_path())) {
        const auto it = std::find(outputs.begin(), outputs.end(), entry.path());
        if (it != outputs.end()) {
          EXPECT_TRUE(test::ReadBytes(entry.path()) == complete[it - outputs.begin()])
              << "a partial " << entry.path() << " after kill " << kill_number;
        } else {
          bool temporary = false;
          for (const auto& output : outputs)
            temporary |= test::IsKilledWritersTemporary(entry.path().filename().string(),
                                                        output.filename().string(), killed);
          EXPECT_TRUE(temporary) << entry.path() << " after kill " << kill_number;
        }
      }
    }
    ASSERT_EQ(test::Wait(test::Spawn(args)), 0);
  }
}

// On a real model: PVNN exact where the clusters the new images change share points with the
// others (whose v_NN their points' PVNN takes when smaller).
TEST(IndexUpdateSharedData, ACompactHerzJesuGrownByThreeImagesKeepsPvnnExact) {
  CWLOC_REQUIRE_SHARED_DATA(data, "herz_jesu_p25");
  test::TempDir dir;
  const colmap::Reconstruction model = colmap::ReadReconstruction(data / "mapping_model" / "bin");
  std::set<image_t> held_out;
  for (auto it = model.images.rbegin(); held_out.size() < 3; ++it) held_out.insert(it->first);
  const std::filesystem::path old_model = dir / "old_model";
  std::filesystem::create_directories(old_model);
  colmap::WriteReconstruction(test::ModelWithoutImages(model, held_out), old_model,
                              colmap::ModelFormat::kBinary);
  IndexBuildOptions build;
  build.model_dir = old_model;
  build.database_path = data / "database.db";
  build.output_path = dir / "old.cwl";
  build.calibration_samples = 0;
  build.code_bytes = 16;
  BuildIndex(build);
  IndexUpdateOptions options;
  options.index_path = build.output_path;
  options.model_dir = data / "mapping_model" / "bin";
  options.database_path = build.database_path;
  options.output_path = dir / "grown.cwl";
  options.delta_path = dir / "grown.cwld";
  const IndexUpdateReport report = UpdateIndex(options);
  EXPECT_EQ(report.images_added, 3u);
  ExpectCompactAndExact(options.output_path, build.output_path, options.model_dir,
                        options.database_path);
  ApplyDelta(build.output_path, options.delta_path, dir / "applied.cwl", 2);
  EXPECT_EQ(test::ReadBytes(dir / "applied.cwl"), test::ReadBytes(options.output_path));
}

}  // namespace
}  // namespace cwloc
