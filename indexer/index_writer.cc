#include "indexer/index_writer.h"

#include <string>
#include <vector>

#include "base/progress.h"

namespace cwloc {

void WriteIndex(const std::filesystem::path& path, IndexRows rows,
                nlohmann::ordered_json manifest) {
  manifest["format_version"] =
      std::to_string(kFormatMajor) + "." + std::to_string(FormatMinorOf(IndexSectionsOf(rows)));
  const std::string manifest_text = manifest.dump(2) + "\n";
  rows.manifest = manifest_text;
  WriteIndexFile(path, IndexSectionsOf(rows));
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
