#pragma once

// The build option table (build_option_table.inc) as data: `cwloc-index build` makes its flags
// from it, cwloc.build_index (python/) its keywords, and both, like BuildIndex itself, check
// values through ValidateBuildOptions, so every surface accepts the same values and refuses
// the others with the same message ("--FLAG VALUE: expected ..."), before anything is read.

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "base/option_value.h"
#include "indexer/index_build_flags.h"
#include "indexer/index_builder.h"

namespace cwloc {

// `--code-bytes`: 0 (each view's full descriptor) or a code size IsValidCodeBytes accepts.
inline constexpr std::array<uint32_t, 6> kCodeBytesChoices = {0, 4, 8, 16, 32, 64};

struct BuildOptionSpec {
  std::string_view flag;  // without dashes; Python's keyword with '-' written '_'
  std::string help;
  ValueRange range;
  size_t type;  // index of the option's type in OptionValue
  // The value, nullopt for an optional member that is unset.
  std::optional<OptionValue> (*get)(const IndexBuildOptions& options, const IndexBuildFlags& flags);
  // Stores a value of the spec's type (unchecked) and marks the flag given where the table says.
  void (*set)(const OptionValue& value, IndexBuildOptions* options, IndexBuildFlags* flags);
};

// Every build option, in the table's order.
std::span<const BuildOptionSpec> BuildOptionTable();

// The option with this flag name (without dashes); throws InputError "unknown option 'NAME'".
const BuildOptionSpec& FindBuildOption(std::string_view flag);

// "--FLAG VALUE: expected ..." (InputError) unless the value is in the option's range.
void CheckBuildOption(const BuildOptionSpec& spec, const OptionValue& value);

// Text as `cwloc-index build` takes it ("12", "5.5", "true", a path) as the option's type;
// throws InputError naming the flag when it is not a value of that type or is out of range.
OptionValue ParseBuildOption(const BuildOptionSpec& spec, std::string_view text);

// Checks every option of the table in options and flags against its range; throws InputError
// naming the flag. Reads no file: `cwloc-index build`, cwloc.build_index and BuildIndex call it
// before anything is read.
void ValidateBuildOptions(const IndexBuildOptions& options, const IndexBuildFlags& flags = {});

}  // namespace cwloc
