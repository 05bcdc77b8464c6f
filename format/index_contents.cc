#include "format/index_contents.h"

#include "format/index.h"

namespace cwloc {

void KeepParentCoding(const Index& parent, IndexPointOrigin* origin, IndexContents* contents) {
  *origin = parent.point_origin();
  contents->point_origin = origin;
  contents->codebook = parent.codes().codebook;
  contents->code_bytes = parent.codes().code_bytes;
}

SectionData DescriptorSection(const IndexContents& contents) {
  return {section::kDescriptors,
          kSectionRequired,
          kDescriptorBytes,
          contents.view_points.size(),
          contents.descriptors,
          {contents.descriptor_pieces.begin(), contents.descriptor_pieces.end()}};
}

std::vector<SectionData> RowSections(const IndexContents& contents) {
  const bool coded = contents.code_bytes != 0;
  std::vector<SectionData> sections;
  if (coded) {
    sections.push_back(MakeSection(section::kPointOrigin,
                                   std::span<const IndexPointOrigin>(contents.point_origin, 1)));
    sections.push_back(MakeSection(section::kPointOffsets, contents.point_offsets));
  } else {
    sections.push_back(MakeSection(section::kPoints, contents.points));
  }
  sections.push_back(MakeSection(section::kTracks, contents.tracks));
  if (coded) {
    sections.push_back(MakeSection(section::kCodebook, contents.codebook));
    sections.push_back(SectionData{section::kPointCodes, kSectionRequired, contents.code_bytes,
                                   contents.codes.size() / contents.code_bytes, contents.codes});
  }
  sections.push_back(MakeSection(section::kViewPoint, contents.view_points));
  sections.push_back(MakeSection(coded ? section::kPointNeighbor : section::kViewNeighbor,
                                 contents.neighbor_distances));
  if (!contents.view_keypoints.empty()) {
    // Optional: the localizer does not read model keypoints; tools that draw matches do.
    sections.push_back(MakeSection(section::kViewKeypoints, contents.view_keypoints, /*flags=*/0));
  }
  if (!contents.point_colors.empty()) {
    // Optional: for viewers (cwloc-serve's map); the localizer does not read them.
    sections.push_back(MakeSection(section::kPointColors, contents.point_colors, /*flags=*/0));
  }
  if (!contents.point_ids.empty()) {
    // Optional: what `cwloc-index update` recognizes the model's points by.
    sections.push_back(MakeSection(section::kPointIds, contents.point_ids, /*flags=*/0));
  }
  return sections;
}

std::vector<SectionData> IndexSectionsOf(const IndexContents& contents, std::string_view manifest) {
  std::vector<SectionData> sections;
  if (contents.code_bytes == 0) sections.push_back(DescriptorSection(contents));
  const std::vector<SectionData> rows = RowSections(contents);
  sections.insert(sections.end(), rows.begin(), rows.end());
  const KdForest& forest = *contents.forest;
  sections.insert(
      sections.end(),
      {MakeSection<char>(section::kManifest, {manifest.data(), manifest.size()}),
       MakeSection(section::kCameras, contents.cameras),
       MakeSection(section::kImages, contents.images),
       MakeSection<char>(section::kStrings, {contents.strings.data(), contents.strings.size()}),
       MakeSection(section::kKdNodes, std::span<const KdNode>(forest.nodes)),
       MakeSection(section::kKdRoots, std::span<const uint32_t>(forest.roots)),
       MakeSection(section::kKdLeaves, std::span<const uint32_t>(forest.leaves)),
       MakeSection(section::kCovisOffsets, contents.covisibility_offsets),
       MakeSection(section::kCovisEdges, contents.covisibility_edges)});
  if (contents.georeference != nullptr) {
    sections.push_back(MakeSection(section::kGeoreference,
                                   std::span<const IndexGeoreference>(contents.georeference, 1),
                                   /*flags=*/0));
  }
  if (contents.covariance_calibration != nullptr) {
    sections.push_back(
        MakeSection(section::kCovarianceCalibration,
                    std::span<const IndexCovarianceCalibration>(contents.covariance_calibration, 1),
                    /*flags=*/0));
  }
  return sections;
}

}  // namespace cwloc
