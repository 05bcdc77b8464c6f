#include "indexer/index_command_flags.h"

#include <stdexcept>
#include <type_traits>
#include <variant>
#include <vector>

#include "geo/geo_region.h"
#include "indexer/build_option_table.h"

namespace cwloc {
namespace {

// The table's command column.
constexpr unsigned kBuild = 1, kUpdate = 2, kExtract = 4, kApply = 8;
enum class FlagNeed { kRequired, kOptional };
using enum FlagNeed;

// "output" of "-o,--output".
std::string_view FlagName(std::string_view names) { return names.substr(names.rfind('-') + 1); }

template <typename Type, typename T>
std::optional<OptionValue> ShownDefault(const T& member) {
  if constexpr (std::is_arithmetic_v<Type> && !std::is_same_v<Type, bool>) {
    return OptionValue(std::in_place_type<Type>, Type(member));
  } else {
    return std::nullopt;
  }
}

template <typename Type, typename T>
void AssignFlag(const Type& value, T* member) {
  *member = T(value);
}
void AssignFlag(const std::string& text, std::optional<GeoRegion>* near) {
  *near = ParseGeoRegion(text, "--near");
}

// A build option's value into a command's member of another (numeric) type.
template <typename T>
void AssignNumber(const OptionValue& value, T* member) {
  std::visit(
      [member](const auto& number) {
        if constexpr (std::is_arithmetic_v<std::decay_t<decltype(number)>>) {
          *member = T(number);
        } else {
          throw std::logic_error("a build option taken by another command is not a number");
        }
      },
      value);
}

// The command whose options these are.
template <typename Options>
constexpr unsigned CommandOf() {
  if constexpr (std::is_same_v<Options, IndexBuildOptions>) return kBuild;
  if constexpr (std::is_same_v<Options, IndexUpdateOptions>) return kUpdate;
  if constexpr (std::is_same_v<Options, IndexExtractOptions>) return kExtract;
  if constexpr (std::is_same_v<Options, IndexApplyOptions>) return kApply;
}

template <typename Options, unsigned kCommand>
std::vector<CommandFlagSpec<Options>> CommandTable() {
  std::vector<CommandFlagSpec<Options>> specs;
#define CWLOC_INDEX_FLAG(commands, names, type, member, range, need, help)                      \
  if constexpr (((commands)&kCommand) != 0) {                                                   \
    specs.push_back({names, FlagName(names), help, range, OptionTypeIndex<type>(),              \
                     need == kRequired,                                                         \
                     [](const Options& options) { return ShownDefault<type>(options.member); }, \
                     [](const OptionValue& value, Options* options) {                           \
                       AssignFlag(std::get<type>(value), &options->member);                     \
                     }});                                                                       \
  }
#define CWLOC_INDEX_BUILD_FLAG(commands, build_flag, member)                                       \
  if constexpr (((commands)&kCommand) != 0) {                                                      \
    const BuildOptionSpec& build = FindBuildOption(build_flag);                                    \
    specs.push_back(                                                                               \
        {"--" + std::string(build.flag), build.flag, build.help, build.range, build.type, false,   \
         [](const Options& options) -> std::optional<OptionValue> {                                \
           const BuildOptionSpec& spec = FindBuildOption(build_flag);                              \
           return OptionValueFromNumber(spec.flag, spec.range, spec.type, double(options.member)); \
         },                                                                                        \
         [](const OptionValue& value, Options* options) {                                          \
           AssignNumber(value, &options->member);                                                  \
         }});                                                                                      \
  }
#include "indexer/index_command_flags.inc"
#undef CWLOC_INDEX_BUILD_FLAG
#undef CWLOC_INDEX_FLAG
  return specs;
}

}  // namespace

template <typename Options>
std::span<const CommandFlagSpec<Options>> CommandFlagTable() {
  static const std::vector<CommandFlagSpec<Options>> specs =
      CommandTable<Options, CommandOf<Options>()>();
  return specs;
}
template std::span<const CommandFlagSpec<IndexBuildOptions>> CommandFlagTable();
template std::span<const CommandFlagSpec<IndexUpdateOptions>> CommandFlagTable();
template std::span<const CommandFlagSpec<IndexExtractOptions>> CommandFlagTable();
template std::span<const CommandFlagSpec<IndexApplyOptions>> CommandFlagTable();

void TakeThreadsOfBuildFlags(IndexUpdateOptions* options) {
  for (const auto& [flag, value] : options->build_flags) {
    if (flag == "threads") AssignNumber(value, &options->threads);
  }
}

}  // namespace cwloc
