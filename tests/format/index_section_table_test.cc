// The section table (format/index_section_table.inc) drives the writer and the reader: every
// line of it round-trips through a file, in the table's order and batches, with its flag and
// format minor; a section a reader does not know is skipped when optional, and a section the
// table requires is refused, by name, when missing.
#include "format/index_section_table.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <string>
#include <vector>

#include "format/index.h"
#include "format/index_rows.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

// The smallest consistent index of either kind with every section of the table filled: two
// images of one camera, two views each, of two points.
class SectionTableTest : public testing::TestWithParam<bool> {
 protected:
  bool compact() const { return GetParam(); }

  IndexRows Rows() {
    IndexRows rows;
    camera_.model_id = 0;  // SIMPLE_PINHOLE
    camera_.num_params = 3;
    rows.cameras = {&camera_, 1};
    for (uint32_t i = 0; i < 2; ++i) {
      IndexImage& image = images_[i];
      image.image_id = i + 1;
      image.name_offset = i;
      image.name_size = 1;
      image.cam_from_world_rotation[0] = 1;
      image.first_view = 2 * i;
      image.num_views = 2;
      image.cluster = i;
    }
    rows.images = images_;
    rows.strings = std::string_view("ab");
    rows.view_points = view_points_;
    rows.tracks = tracks_;
    rows.view_keypoints = keypoints_;
    rows.point_colors = colors_;
    rows.point_ids = ids_;
    rows.manifest = std::string_view("{}");
    descriptors_.resize(4 * kDescriptorBytes);
    std::iota(descriptors_.begin(), descriptors_.end(), uint8_t{0});
    codebook_.resize(DescriptorCodes::kCodebookBytes, 7);
    if (compact()) {
      rows.code_bytes = 8;
      rows.point_origin = {&origin_, 1};
      rows.point_offsets = offsets_;
      rows.codebook = codebook_;
      rows.codes = std::span<const uint8_t>(descriptors_).first(2 * 8);
      rows.point_neighbor_distances = std::span<const float>(distances_).first(2);
    } else {
      rows.points = points_;
      rows.descriptors = descriptors_;
      rows.view_neighbor_distances = distances_;
    }
    // One tree, one leaf over every row of the kd-forest: views, or a compact index's points.
    const uint32_t forest_rows = compact() ? 2 : 4;
    node_ = {0, kKdLeaf, uint8_t(forest_rows), 0, 0};
    rows.kd_nodes = {&node_, 1};
    rows.kd_roots = root_;
    rows.kd_leaves = std::span<const uint32_t>(leaves_).first(forest_rows);
    rows.covisibility_offsets = covisibility_offsets_;
    rows.covisibility_edges = edges_;
    georeference_.origin_latitude_deg = 47.4;
    georeference_.origin_longitude_deg = 8.5;
    georeference_.scale = 1;
    georeference_.rotation[0] = 1;
    georeference_.source = uint32_t(GeoreferenceSource::kFile);
    rows.georeference = {&georeference_, 1};
    calibration_.rotation_scale[0] = 1.5f;
    rows.covariance_calibration = {&calibration_, 1};
    return rows;
  }

  // The error Index::Open gives for these sections.
  std::string OpenError(const std::vector<SectionData>& sections) {
    WriteIndexFile(path_, sections);
    return test::InputErrorOf([&] { Index::Open(path_); });
  }

  test::TempDir dir_;
  const std::filesystem::path path_ = dir_ / "index.cwl";
  IndexCamera camera_{};
  IndexImage images_[2] = {};
  const uint32_t view_points_[4] = {0, 1, 0, 1};
  const uint32_t tracks_[4] = {0, 2, 1, 3};
  const IndexPoint points_[2] = {{{1, 2, 3}, 0, 2}, {{4, 5, 6}, 2, 2}};
  const IndexPointOrigin origin_{{10, 20, 30}};
  const IndexPointOffset offsets_[2] = {{{1, 2, 3}, 0}, {{4, 5, 6}, 2}};
  const ViewKeypoint keypoints_[4] = {{1, 2}, {3, 4}, {5, 6}, {7, 8}};
  const PointColor colors_[2] = {{{1, 2, 3}}, {{4, 5, 6}}};
  const uint64_t ids_[2] = {11, 12};
  const float distances_[4] = {0.5f, 1.5f, 2.5f, 3.5f};
  std::vector<uint8_t> descriptors_, codebook_;
  KdNode node_{};
  const uint32_t root_[1] = {0};
  const uint32_t leaves_[4] = {0, 1, 2, 3};
  const uint32_t covisibility_offsets_[3] = {0, 1, 2};
  const CovisibilityEdge edges_[2] = {{1, 2}, {0, 2}};
  IndexGeoreference georeference_{};
  IndexCovarianceCalibration calibration_{};
};

TEST_P(SectionTableTest, EveryLineRoundTripsThroughAFile) {
  const IndexRows rows = Rows();
  const std::vector<SectionData> sections = IndexSectionsOf(rows);
  WriteIndexFile(path_, sections);
  const Index index = Index::Open(path_);
  uint16_t newest = 1;
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    const std::string tag = SectionTagName(spec.tag);
    const SectionEntry* entry = index.file().FindSection(spec.tag);
    if (!spec.InIndexOfKind(compact())) {
      EXPECT_EQ(entry, nullptr) << tag;
      continue;
    }
    // A line the fixture does not fill is a line this test does not check: fill it.
    ASSERT_FALSE(spec.bytes(rows).empty()) << tag;
    ASSERT_NE(entry, nullptr) << tag;
    EXPECT_EQ(entry->flags, spec.optional() ? 0 : kSectionRequired) << tag;
    EXPECT_EQ(entry->element_size, spec.ElementBytes(rows)) << tag;
    const std::span<const uint8_t> written = spec.bytes(rows), read = spec.bytes(index.rows());
    EXPECT_TRUE(std::equal(written.begin(), written.end(), read.begin(), read.end())) << tag;
    newest = std::max(newest, spec.minor);
  }
  EXPECT_EQ(index.file().header().format_minor, newest);
  EXPECT_EQ(index.rows().code_bytes, rows.code_bytes);
  EXPECT_NO_THROW(index.Validate());
}

TEST_P(SectionTableTest, TheFileFollowsTheTablesOrderInItsBatches) {
  const IndexRows rows = Rows();
  std::vector<uint32_t> batches;
  for (const SectionBatch batch :
       {SectionBatch::kDescriptorBatch, SectionBatch::kRowBatch, SectionBatch::kLastBatch}) {
    for (const SectionData& section : IndexSectionsOf(rows, batch)) batches.push_back(section.tag);
  }
  std::vector<uint32_t> table_order;
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    if (spec.InIndexOfKind(compact())) table_order.push_back(spec.tag);
  }
  std::vector<uint32_t> whole;
  for (const SectionData& section : IndexSectionsOf(rows)) whole.push_back(section.tag);
  EXPECT_EQ(batches, whole);
  EXPECT_EQ(whole, table_order);
}

TEST_P(SectionTableTest, AnEmptyOptionalSectionIsNotWritten) {
  IndexRows rows = Rows();
  rows.point_colors = {};
  rows.georeference = {};
  WriteIndexFile(path_, IndexSectionsOf(rows));
  const Index index = Index::Open(path_);
  EXPECT_EQ(index.file().FindSection(section::kPointColors), nullptr);
  EXPECT_TRUE(index.point_colors().empty());
  EXPECT_EQ(index.georeference(), nullptr);
  EXPECT_EQ(index.file().header().format_minor, 5);  // PIDS
}

TEST_P(SectionTableTest, AnUnknownOptionalSectionIsSkipped) {
  const IndexRows rows = Rows();
  std::vector<SectionData> sections = IndexSectionsOf(rows);
  const uint8_t bytes[5] = {1, 2, 3, 4, 5};
  sections.insert(sections.begin() + 3,
                  MakeSection(SectionTag("ZZZZ"), std::span<const uint8_t>(bytes), /*flags=*/0));
  WriteIndexFile(path_, sections);
  const Index index = Index::Open(path_);
  EXPECT_EQ(index.file().sections().size(), sections.size());
  EXPECT_EQ(FindIndexSection(SectionTag("ZZZZ")), nullptr);
  EXPECT_EQ(index.num_views(), 4u);
  EXPECT_NO_THROW(index.Validate());
}

TEST_P(SectionTableTest, ARequiredSectionMissingIsRefusedByName) {
  const IndexRows rows = Rows();
  const std::vector<SectionData> sections = IndexSectionsOf(rows);
  size_t refused = 0;
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    if (spec.optional() || !spec.InIndexOfKind(compact())) continue;
    std::vector<SectionData> without;
    std::copy_if(sections.begin(), sections.end(), std::back_inserter(without),
                 [&](const SectionData& section) { return section.tag != spec.tag; });
    const std::string tag = SectionTagName(spec.tag);
    // Without PCOD a compact index is read as a full one, which lacks its own sections.
    const std::string missing = spec.tag == section::kPointCodes ? "DESC" : tag;
    EXPECT_EQ(OpenError(without), path_.string() + ": section '" + missing + "' is missing") << tag;
    ++refused;
  }
  EXPECT_EQ(refused, compact() ? 16u : 14u);
}

TEST_P(SectionTableTest, ACountOtherThanTheTablesIsRefused) {
  const std::vector<SectionData> sections = IndexSectionsOf(Rows());
  const auto with = [&](const SectionData& changed) {
    std::vector<SectionData> result = sections;
    for (SectionData& section : result) {
      if (section.tag == changed.tag) section = changed;
    }
    return result;
  };
  const uint64_t ids[3] = {11, 12, 13};
  EXPECT_EQ(OpenError(with(MakeSection(section::kPointIds, std::span<const uint64_t>(ids), 0))),
            path_.string() + ": section 'PIDS' has 3 elements, expected one per point (2)");
  const ViewKeypoint keypoints[1] = {{1, 2}};
  EXPECT_EQ(OpenError(with(
                MakeSection(section::kViewKeypoints, std::span<const ViewKeypoint>(keypoints), 0))),
            path_.string() + ": section 'VKXY' has 1 elements, expected one per view (4)");
  EXPECT_EQ(
      OpenError(with(MakeSection(section::kGeoreference, std::span<const IndexGeoreference>(), 0))),
      path_.string() + ": section 'GEOR' has 0 elements, expected 1");
}

INSTANTIATE_TEST_SUITE_P(BothKinds, SectionTableTest, testing::Bool(),
                         [](const testing::TestParamInfo<bool>& kind) {
                           return kind.param ? "Compact" : "Full";
                         });

}  // namespace
}  // namespace cwloc
