#pragma once
// What `cwloc-index build`'s flags mean beyond one field each, shared by the CLI and the
// Python module (python/) so that each default and rule lives in one place.
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>

#include "indexer/index_builder.h"

namespace cwloc {

struct IndexBuildFlags {
  std::filesystem::path cluster_file;  // --cluster-file
  std::optional<uint32_t> clusters;    // --clusters
  bool compact = false;                // --compact
  bool code_bytes_given = false;       // --code-bytes was given: --compact keeps it
  bool trees_given = false;            // --trees was given: --compact keeps it
};

// Sets the clustering, and --compact's code size and kd-trees unless given. Throws InputError
// for --cluster-file with --clusters.
void ApplyBuildFlags(const IndexBuildFlags& flags, IndexBuildOptions* options);

// The report `cwloc-index build --json` prints: output, file_bytes, bytes_per_view, counts,
// seconds per stage and georeference.
nlohmann::ordered_json BuildReportJson(const IndexBuildOptions& options,
                                       const IndexBuildReport& report);

}  // namespace cwloc
