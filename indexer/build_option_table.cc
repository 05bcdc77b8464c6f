#include "indexer/build_option_table.h"

#include <stdexcept>

#include "kdtree/kd_forest_builder.h"

namespace cwloc {
namespace {

// Between an option's table type and the member it lands in.
template <typename Type, typename T>
std::optional<OptionValue> Get(const T& member) {
  return OptionValue(std::in_place_type<Type>, Type(member));
}
template <typename Type, typename T>
std::optional<OptionValue> Get(const std::optional<T>& member) {
  if (!member) return std::nullopt;
  return OptionValue(std::in_place_type<Type>, Type(*member));
}
template <typename Type, typename T>
void Assign(const Type& value, T* member) {
  *member = T(value);
}
void Mark(bool IndexBuildFlags::*given, IndexBuildFlags* flags) {
  if (given != nullptr) flags->*given = true;
}

#define CWLOC_BUILD_OPTION(flag, type, target, range, given, help)                                 \
  BuildOptionSpec{flag,                                                                            \
                  help,                                                                            \
                  range,                                                                           \
                  OptionTypeIndex<type>(),                                                         \
                  []([[maybe_unused]] const IndexBuildOptions& options,                            \
                     [[maybe_unused]] const IndexBuildFlags& flags) { return Get<type>(target); }, \
                  [](const OptionValue& value, IndexBuildOptions* o, IndexBuildFlags* f) {         \
                    [[maybe_unused]] IndexBuildOptions& options = *o;                              \
                    [[maybe_unused]] IndexBuildFlags& flags = *f;                                  \
                    Assign(std::get<type>(value), &(target));                                      \
                    Mark(given, f);                                                                \
                  }},
// Function-local, so that it is made before a caller's static initialisation uses it.
std::span<const BuildOptionSpec> Specs() {
  static const BuildOptionSpec specs[] = {
#include "indexer/build_option_table.inc"
  };
  return specs;
}
#undef CWLOC_BUILD_OPTION

}  // namespace

std::span<const BuildOptionSpec> BuildOptionTable() { return Specs(); }

const BuildOptionSpec& FindBuildOption(std::string_view flag) {
  return FindOptionSpec(Specs(), flag);
}

void CheckBuildOption(const BuildOptionSpec& spec, const OptionValue& value) {
  if (value.index() != spec.type)
    throw std::logic_error("option --" + std::string(spec.flag) + ": value of the wrong type");
  CheckOptionValue(spec.flag, spec.range, value);
}

OptionValue ParseBuildOption(const BuildOptionSpec& spec, std::string_view text) {
  return ParseOptionValue(spec.flag, spec.range, spec.type, text);
}

void ValidateBuildOptions(const IndexBuildOptions& options, const IndexBuildFlags& flags) {
  for (const BuildOptionSpec& spec : Specs()) {
    if (const std::optional<OptionValue> value = spec.get(options, flags))
      CheckBuildOption(spec, *value);
  }
}

}  // namespace cwloc
