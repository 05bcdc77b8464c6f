#pragma once
// The index of a real data set in ../shared/data (its mapping_model/bin and database.db), built
// once per test binary with default options (or as a compact index of `code_bytes` codes) and
// kept until the binary exits, so that the suites that use one data set share one build.
#include <filesystem>
#include <map>
#include <optional>
#include <string>

#include "indexer/index_builder.h"
#include "tests/test_util.h"

namespace cwloc::test {

struct SharedDataIndex {
  std::filesystem::path data;   // the data set's folder
  std::filesystem::path index;  // its index file
};

// std::nullopt when the data set is not next to the source tree (the caller skips).
inline std::optional<SharedDataIndex> BuildSharedDataIndex(const std::string& name,
                                                           uint32_t code_bytes = 0) {
  static TempDir dir;
  static std::map<std::string, std::optional<SharedDataIndex>> built;
  const std::string file = name + (code_bytes ? "-" + std::to_string(code_bytes) : "") + ".cwl";
  if (const auto it = built.find(file); it != built.end()) return it->second;
  std::optional<SharedDataIndex>& entry = built[file];
  const auto data = SharedDataDir(name);
  if (!data) return entry;
  IndexBuildOptions options;
  options.model_dir = *data / "mapping_model" / "bin";
  options.database_path = *data / "database.db";
  options.output_path = dir / file;
  options.code_bytes = code_bytes;
  BuildIndex(options);
  entry = SharedDataIndex{*data, options.output_path};
  return entry;
}

}  // namespace cwloc::test
