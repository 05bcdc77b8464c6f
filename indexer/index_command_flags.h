#pragma once

// The command table (index_command_flags.inc) as data: each of `cwloc-index build`, `update`,
// `extract` and `apply` makes its flags from its lines, as build makes the rest of its flags
// from the build option table, so that a flag several commands take (--output, --threads) is
// declared, range-checked and explained once.

#include <cstdint>
#include <filesystem>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "base/option_value.h"
#include "indexer/index_builder.h"
#include "indexer/index_extract.h"
#include "indexer/index_update.h"

namespace cwloc {

// `cwloc-index apply`'s arguments (ApplyDelta's).
struct IndexApplyOptions {
  std::filesystem::path index_path;
  std::filesystem::path delta_path;
  std::filesystem::path output_path;
  int threads = 0;  // 0 = all cores
};

template <typename Options>
struct CommandFlagSpec {
  std::string names;      // the command line's: "-o,--output"
  std::string_view flag;  // without dashes, as messages name it: "output"
  std::string help;
  ValueRange range;
  size_t type;  // index of the flag's type in OptionValue
  bool required;
  // The default --help shows: a number's, nullopt for a switch, a path or a text.
  std::optional<OptionValue> (*shown_default)(const Options& options);
  // Stores a value of the spec's type (range-checked before).
  void (*set)(const OptionValue& value, Options* options);
};

// A command's flags, in the table's order: of build (IndexBuildOptions), update, extract or
// apply (IndexApplyOptions).
template <typename Options>
std::span<const CommandFlagSpec<Options>> CommandFlagTable();

// `update` takes --threads among the build option table's flags (it compares the others with the
// index's build): the value given, if any, as options->threads.
void TakeThreadsOfBuildFlags(IndexUpdateOptions* options);

}  // namespace cwloc
