#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>

#include "format/index_rows.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {

// Writes the rows' sections atomically, `manifest` (its format_version set from them) as MANI.
void WriteIndex(const std::filesystem::path& path, IndexRows rows, nlohmann::ordered_json manifest);

// The global kd-forest over an index's rows (N x 128: views, or a compact index's decoded
// points), with a progress bar on a terminal.
KdForest BuildIndexForest(std::span<const uint8_t> rows, KdForestBuildOptions options,
                          uint64_t seed, int threads);

}  // namespace cwloc
