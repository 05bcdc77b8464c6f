#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <span>

#include "format/index_contents.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {

// Writes the sections atomically, `manifest` first with its format_version set from them.
void WriteIndex(const std::filesystem::path& path, const IndexContents& contents,
                nlohmann::ordered_json manifest);

// The global kd-forest over an index's rows (N x 128: views, or a compact index's decoded
// points), with a progress bar on a terminal.
KdForest BuildIndexForest(std::span<const uint8_t> rows, KdForestBuildOptions options,
                          uint64_t seed, int threads);

}  // namespace cwloc
