#pragma once

// A delta: what turns one index (the parent) into the next (the child) that `cwloc-index
// update` made from a grown model, small enough to ship to devices. It holds the child's rows
// that the parent cannot give (new views and points, changed values, the small sections
// whole) and which parent rows the child keeps; `apply` (delta/apply_delta.h) recomputes the
// rest (tracks, co-visibility, kd-forest) and must give the child bit for bit. The file is the
// index's container with another magic (docs/format.md, "Deltas").

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "format/index_file.h"
#include "format/index_sections.h"

namespace cwloc {

inline constexpr uint16_t kDeltaFormatMajor = 1;
// 1.1: NCOD, the deltas of compact indexes.
inline constexpr uint16_t kDeltaFormatMinor = 1;
// Section DHDR (one element): which parent the delta applies to, which child it makes.
struct DeltaHeader {
  uint64_t parent_checksum;  // the parent file's header checksum (it covers every section's)
  uint64_t parent_file_size;
  uint64_t child_checksum;  // the child's, checked before the child is written
  uint64_t child_file_size;
  uint64_t forest_seed;  // the kd-forest's seed (splits of overfull leaves, a rebuild)
  uint32_t forest_leaf_size;
  uint32_t flags;  // kDeltaForestRebuilt
  uint32_t reserved[4];
};
static_assert(sizeof(DeltaHeader) == 64);
// The child's kd-forest is built afresh (the balance bound was passed), not updated.
inline constexpr uint32_t kDeltaForestRebuilt = 1u << 0;

// Child rows [child_first, child_first + count) are the parent's rows from parent_first on.
struct RowRun {
  uint32_t child_first;
  uint32_t parent_first;
  uint32_t count;
};
static_assert(sizeof(RowRun) == 12);

// A value that changed on a kept row (the child's row number).
template <typename T>
struct RowChange {
  uint32_t row;
  T value;
};
struct PointMove {
  uint32_t row;
  uint32_t reserved;
  double xyz[3];
};
static_assert(sizeof(PointMove) == 32);
struct PointColorChange {
  uint32_t row;
  PointColor color;
  uint8_t reserved;
};
static_assert(sizeof(PointColorChange) == 8);

namespace delta_section {
inline constexpr uint32_t kHeader = SectionTag("DHDR");
inline constexpr uint32_t kViewRuns = SectionTag("VRUN");
inline constexpr uint32_t kPointRuns = SectionTag("PRUN");
inline constexpr uint32_t kNewDescriptors = SectionTag("NDSC");
inline constexpr uint32_t kNewViewPoints = SectionTag("NV2P");
inline constexpr uint32_t kNewViewKeypoints = SectionTag("NVKP");
inline constexpr uint32_t kNewViewNeighbors = SectionTag("NVNN");
inline constexpr uint32_t kViewPointChanges = SectionTag("CV2P");
inline constexpr uint32_t kViewNeighborChanges = SectionTag("CVNN");
inline constexpr uint32_t kNewPoints = SectionTag("NPNT");
inline constexpr uint32_t kNewPointIds = SectionTag("NPID");
inline constexpr uint32_t kNewPointColors = SectionTag("NRGB");
inline constexpr uint32_t kPointMoves = SectionTag("CPNT");
inline constexpr uint32_t kPointColorChanges = SectionTag("CRGB");
inline constexpr uint32_t kNewPointCodes = SectionTag("NCOD");
inline constexpr uint32_t kAll[] = {kHeader,
                                    section::kManifest,
                                    section::kCameras,
                                    section::kImages,
                                    section::kStrings,
                                    kViewRuns,
                                    kPointRuns,
                                    kNewDescriptors,
                                    kNewViewPoints,
                                    kNewViewKeypoints,
                                    kNewViewNeighbors,
                                    kViewPointChanges,
                                    kViewNeighborChanges,
                                    kNewPoints,
                                    kNewPointIds,
                                    kNewPointColors,
                                    kPointMoves,
                                    kPointColorChanges,
                                    kNewPointCodes};
}  // namespace delta_section

inline constexpr ContainerKind kDeltaContainer{
    "CWLOCDLT",
    "cwloc index delta",
    "delta",
    kDeltaFormatMajor,
    kDeltaFormatMinor,
    "make the delta again with this cwloc-index update, or rebuild the index",
    delta_section::kAll};

// A delta in memory: the sections of the file, owned. For a compact parent (codes per point)
// new views carry no descriptors, NVNN and CVNN are per point (PVNN), and a point whose track
// changed is a new point (its code is the mean of its views' descriptors coded anew).
struct IndexDelta {
  DeltaHeader header{};
  std::string manifest;  // the child's MANI, whole
  std::vector<IndexCamera> cameras;
  std::vector<IndexImage> images;
  std::string strings;
  std::vector<RowRun> view_runs, point_runs;  // ascending, not overlapping
  // The child's views no run covers, in row order.
  std::vector<uint8_t> new_descriptors;  // x 128; none for a compact parent
  std::vector<uint32_t> new_view_points;
  std::vector<ViewKeypoint> new_view_keypoints;         // when the index stores keypoints
  std::vector<float> new_view_neighbors;                // per new point for a compact parent
  std::vector<RowChange<uint32_t>> view_point_changes;  // ascending rows
  std::vector<RowChange<float>> view_neighbor_changes;  // point rows for a compact parent
  // The child's points no run covers, in row order (first_track and track_length zero).
  std::vector<IndexPoint> new_points;
  std::vector<uint64_t> new_point_ids;       // COLMAP ids (PIDS)
  std::vector<PointColor> new_point_colors;  // when the index stores colours
  std::vector<uint8_t> new_point_codes;      // x code_bytes, for a compact parent
  uint32_t code_bytes = 0;                   // NCOD's element size; 0: no NCOD
  std::vector<PointMove> point_moves;
  std::vector<PointColorChange> point_color_changes;
};

// Writes the delta atomically.
void WriteDelta(const std::filesystem::path& path, const IndexDelta& delta);

// Reads a delta: the container (magic, version, every checksum: a truncated or corrupt file
// is named as such) and every section's presence and element size. Whether it fits a parent
// is ApplyDelta's to check. Throws InputError naming the file.
IndexDelta ReadDelta(const std::filesystem::path& path);

}  // namespace cwloc
