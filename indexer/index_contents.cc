#include "indexer/index_contents.h"

#include <string>
#include <vector>

#include "base/progress.h"
#include "format/index_file.h"

namespace cwloc {

void WriteIndex(const std::filesystem::path& path, const IndexContents& contents,
                nlohmann::ordered_json manifest) {
  const bool coded = contents.code_bytes != 0;
  std::vector<SectionData> sections = {
      SectionData{section::kManifest},  // filled below, once the format version is known
      MakeSection(section::kCameras, contents.cameras),
      MakeSection(section::kImages, contents.images),
      MakeSection<char>(section::kStrings, {contents.strings.data(), contents.strings.size()}),
  };
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
  } else {
    sections.push_back(SectionData{section::kDescriptors, kSectionRequired, kDescriptorBytes,
                                   contents.view_points.size(), contents.descriptors});
  }
  sections.push_back(MakeSection(section::kViewPoint, contents.view_points));
  sections.push_back(MakeSection(coded ? section::kPointNeighbor : section::kViewNeighbor,
                                 contents.neighbor_distances));
  const KdForest& forest = *contents.forest;
  sections.insert(sections.end(),
                  {MakeSection(section::kKdNodes, std::span<const KdNode>(forest.nodes)),
                   MakeSection(section::kKdRoots, std::span<const uint32_t>(forest.roots)),
                   MakeSection(section::kKdLeaves, std::span<const uint32_t>(forest.leaves)),
                   MakeSection(section::kCovisOffsets, contents.covisibility_offsets),
                   MakeSection(section::kCovisEdges, contents.covisibility_edges)});
  if (!contents.view_keypoints.empty()) {
    // Optional: the localizer does not read model keypoints; tools that draw matches do.
    sections.push_back(MakeSection(section::kViewKeypoints, contents.view_keypoints, /*flags=*/0));
  }
  if (!contents.point_colors.empty()) {
    // Optional: for viewers (cwloc-serve's map); the localizer does not read them.
    sections.push_back(MakeSection(section::kPointColors, contents.point_colors, /*flags=*/0));
  }
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
  manifest["format_version"] =
      std::to_string(kFormatMajor) + "." + std::to_string(FormatMinorOf(sections));
  const std::string manifest_text = manifest.dump(2) + "\n";
  sections[0] = MakeSection<char>(section::kManifest, {manifest_text.data(), manifest_text.size()});
  WriteIndexFile(path, sections);
}

KdForest BuildIndexForest(std::span<const uint8_t> rows, KdForestBuildOptions options,
                          uint64_t seed, int threads) {
  options.seed = seed;
  options.num_threads = static_cast<uint32_t>(threads);
  Progress progress("kd-forest", 1000);
  uint64_t permille_shown = 0;
  options.progress = [&](double fraction) {
    const auto permille = static_cast<uint64_t>(fraction * 1000);
    if (permille > permille_shown) {
      progress.Advance(permille - permille_shown);
      permille_shown = permille;
    }
  };
  KdForest forest = BuildKdForest(rows, options);
  progress.Finish();
  return forest;
}

}  // namespace cwloc
