#pragma once
// The index of a real data set in ../shared/data (its mapping_model/bin and database.db), built
// with default options but no covariance calibration unless `calibrated` (its ten folds are
// slow under the sanitizers; covariance_calibration_test.cc asks for it), or as a compact
// index of `code_bytes` codes, once per build tree and
// shared by every test process (test::SharedFixture).
#include <filesystem>
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
                                                           uint32_t code_bytes = 0,
                                                           bool calibrated = false) {
  const auto data = SharedDataDir(name);
  if (!data) return std::nullopt;
  const std::string file = name + (code_bytes ? "_" + std::to_string(code_bytes) : "") +
                           (calibrated ? "_calibrated" : "");
  const auto folder = SharedFixture("data_" + file, [&](const std::filesystem::path& out) {
    IndexBuildOptions options;
    options.model_dir = *data / "mapping_model" / "bin";
    options.database_path = *data / "database.db";
    options.output_path = out / "index.cwl";
    options.code_bytes = code_bytes;
    if (!calibrated) options.calibration_samples = 0;
    BuildIndex(options);
  });
  return SharedDataIndex{*data, folder / "index.cwl"};
}

}  // namespace cwloc::test
