#pragma once

// The build option table (build_option_table.inc) as data: `cwloc-index build` makes its flags
// from it, cwloc.build_index (python/) its keywords, and both, like BuildIndex itself, check
// values through ValidateBuildOptions, so every surface accepts the same values and refuses
// the others with the same message ("--FLAG VALUE: expected ..."), before anything is read.

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

#include "indexer/index_build_flags.h"
#include "indexer/index_builder.h"

namespace cwloc {

// `--code-bytes`: 0 (each view's full descriptor) or a code size IsValidCodeBytes accepts.
inline constexpr std::array<uint32_t, 6> kCodeBytesChoices = {0, 4, 8, 16, 32, 64};

// A value of a build option in its table type.
using BuildOptionValue =
    std::variant<bool, int32_t, uint32_t, uint64_t, double, std::string, std::filesystem::path>;

// The index of T in BuildOptionValue, as BuildOptionSpec::type holds it.
template <typename T, size_t I = 0>
constexpr size_t BuildOptionType() {
  if constexpr (std::is_same_v<std::variant_alternative_t<I, BuildOptionValue>, T>) {
    return I;
  } else {
    return BuildOptionType<T, I + 1>();
  }
}

// The values a build option accepts: numbers between min and max (a closed range unless
// min_open; whole-number types are further limited to what they hold), or, when `choices` is
// not empty, one of those whole numbers.
struct BuildValueRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  std::string_view unit;               // said in messages: "a positive number of metres"
  std::span<const uint32_t> choices;   // whole numbers accepted; empty for a range
  std::string_view first_choice_note;  // "0 (full descriptors) or 4, ..."
};

struct BuildOptionSpec {
  std::string_view flag;  // without dashes; Python's keyword with '-' written '_'
  std::string help;
  BuildValueRange range;
  size_t type;  // index of the option's type in BuildOptionValue
  // The value, nullopt for an optional member that is unset.
  std::optional<BuildOptionValue> (*get)(const IndexBuildOptions& options,
                                         const IndexBuildFlags& flags);
  // Stores a value of the spec's type (unchecked) and marks the flag given where the table says.
  void (*set)(const BuildOptionValue& value, IndexBuildOptions* options, IndexBuildFlags* flags);
};

// Every build option, in the table's order.
std::span<const BuildOptionSpec> BuildOptionTable();

// The option with this flag name (without dashes); throws InputError "unknown option 'NAME'".
const BuildOptionSpec& FindBuildOption(std::string_view flag);

// "--FLAG VALUE: expected ..." (InputError) unless the value is in the option's range.
void CheckBuildOption(const BuildOptionSpec& spec, const BuildOptionValue& value);

// Text as `cwloc-index build` takes it ("12", "5.5", "true", a path) as the option's type;
// throws InputError naming the flag when it is not a value of that type. The range is
// ValidateBuildOptions' to check.
BuildOptionValue ParseBuildOption(const BuildOptionSpec& spec, std::string_view text);

// A value as --help shows it and messages quote it: "4", "5", "0.5", "true", a path.
std::string FormatBuildOption(const BuildOptionValue& value);

// Checks every option of the table in options and flags against its range; throws InputError
// naming the flag. Reads no file: `cwloc-index build`, cwloc.build_index and BuildIndex call it
// before anything is read.
void ValidateBuildOptions(const IndexBuildOptions& options, const IndexBuildFlags& flags = {});

}  // namespace cwloc
