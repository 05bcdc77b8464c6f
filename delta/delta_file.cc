#include "delta/delta_file.h"

#include <algorithm>
#include <cstring>

#include "base/error.h"

namespace cwloc {
namespace {

template <typename T>
SectionData SectionOf(uint32_t tag, const std::vector<T>& rows) {
  return MakeSection(tag, std::span<const T>(rows), /*flags=*/kSectionRequired);
}

// The section's rows copied out of the mapping; an absent section is empty.
template <typename T>
std::vector<T> Rows(const IndexFile& file, uint32_t tag) {
  if (file.FindSection(tag) == nullptr) return {};
  const std::span<const T> rows = file.Section<T>(tag);
  return {rows.begin(), rows.end()};
}

}  // namespace

void WriteDelta(const std::filesystem::path& path, const IndexDelta& delta) {
  using namespace delta_section;
  std::vector<SectionData> sections = {
      MakeSection(kHeader, std::span<const DeltaHeader>(&delta.header, 1)),
      MakeSection<char>(section::kManifest, {delta.manifest.data(), delta.manifest.size()}),
      SectionOf(section::kCameras, delta.cameras),
      SectionOf(section::kImages, delta.images),
      MakeSection<char>(section::kStrings, {delta.strings.data(), delta.strings.size()}),
      SectionOf(kViewRuns, delta.view_runs),
      SectionOf(kPointRuns, delta.point_runs),
      SectionData{kNewDescriptors, kSectionRequired, kDescriptorBytes,
                  delta.new_descriptors.size() / kDescriptorBytes, delta.new_descriptors},
      SectionOf(kNewViewPoints, delta.new_view_points),
      SectionOf(kNewViewKeypoints, delta.new_view_keypoints),
      SectionOf(kNewViewNeighbors, delta.new_view_neighbors),
      SectionOf(kViewPointChanges, delta.view_point_changes),
      SectionOf(kViewNeighborChanges, delta.view_neighbor_changes),
      SectionOf(kNewPoints, delta.new_points),
      SectionOf(kNewPointIds, delta.new_point_ids),
      SectionOf(kNewPointColors, delta.new_point_colors),
      SectionOf(kPointMoves, delta.point_moves),
      SectionOf(kPointColorChanges, delta.point_color_changes),
  };
  // A compact parent's delta is 1.1; a full one's stays 1.0, readable by 1.0's apply.
  if (delta.code_bytes != 0) {
    sections.push_back({kNewPointCodes, kSectionRequired, delta.code_bytes,
                        delta.new_point_codes.size() / delta.code_bytes, delta.new_point_codes});
  }
  WriteIndexFile(path, sections, kDeltaContainer, delta.code_bytes != 0 ? 1 : 0);
}

IndexDelta ReadDelta(const std::filesystem::path& path) {
  using namespace delta_section;
  const IndexFile file = IndexFile::Open(path, kDeltaContainer);
  file.VerifyChecksums();
  IndexDelta delta;
  const std::span<const DeltaHeader> header = file.Section<DeltaHeader>(kHeader);
  if (header.size() != 1)
    throw InputError(path.string() + ": section 'DHDR' has " + std::to_string(header.size()) +
                     " elements, expected 1");
  delta.header = header[0];
  const std::span<const char> manifest = file.Section<char>(section::kManifest);
  delta.manifest.assign(manifest.begin(), manifest.end());
  delta.cameras = Rows<IndexCamera>(file, section::kCameras);
  delta.images = Rows<IndexImage>(file, section::kImages);
  const std::vector<char> strings = Rows<char>(file, section::kStrings);
  delta.strings.assign(strings.begin(), strings.end());
  delta.view_runs = Rows<RowRun>(file, kViewRuns);
  delta.point_runs = Rows<RowRun>(file, kPointRuns);
  if (file.FindSection(kNewDescriptors) != nullptr) {
    const SectionEntry& entry = *file.FindSection(kNewDescriptors);
    if (entry.element_size != kDescriptorBytes)
      throw InputError(path.string() + ": section 'NDSC' has elements of " +
                       std::to_string(entry.element_size) + " bytes, expected 128");
    const uint8_t* bytes = file.bytes().data() + entry.offset;
    delta.new_descriptors.assign(bytes, bytes + entry.size);
  }
  if (file.FindSection(kNewPointCodes) != nullptr) {  // whether it fits the parent: apply's
    const SectionEntry& entry = *file.FindSection(kNewPointCodes);
    const uint8_t* bytes = file.bytes().data() + entry.offset;
    delta.new_point_codes.assign(bytes, bytes + entry.size);
    delta.code_bytes = entry.element_size;
  }
  delta.new_view_points = Rows<uint32_t>(file, kNewViewPoints);
  delta.new_view_keypoints = Rows<ViewKeypoint>(file, kNewViewKeypoints);
  delta.new_view_neighbors = Rows<float>(file, kNewViewNeighbors);
  delta.view_point_changes = Rows<RowChange<uint32_t>>(file, kViewPointChanges);
  delta.view_neighbor_changes = Rows<RowChange<float>>(file, kViewNeighborChanges);
  delta.new_points = Rows<IndexPoint>(file, kNewPoints);
  delta.new_point_ids = Rows<uint64_t>(file, kNewPointIds);
  delta.new_point_colors = Rows<PointColor>(file, kNewPointColors);
  delta.point_moves = Rows<PointMove>(file, kPointMoves);
  delta.point_color_changes = Rows<PointColorChange>(file, kPointColorChanges);
  return delta;
}

}  // namespace cwloc
