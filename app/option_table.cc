#include "app/option_table.h"

#include <stdexcept>
#include <type_traits>

#include "base/error.h"
#include "photo/sift/sift_extractor.h"

namespace cwloc {
namespace {

// Between an option's API type and the member it lands in.
template <typename T>
requires std::is_arithmetic_v<T> T ApiValue(T value) { return value; }
std::string ApiValue(Matcher matcher) { return std::string(MatcherName(matcher)); }
std::string ApiValue(PoseRefiner refiner) { return std::string(PoseRefinerName(refiner)); }
std::string ApiValue(BackMatching mode) {
  return std::string(kBackMatchingNames[static_cast<size_t>(mode)]);
}

template <typename Api, typename T>
requires std::is_arithmetic_v<T>
void Assign(const Api& value, T* member) { *member = static_cast<T>(value); }
// Names were checked against the range's names by then.
void Assign(const std::string& name, Matcher* member) { *member = ParseMatcher(name).value(); }
void Assign(const std::string& name, BackMatching* member) {
  *member = ParseBackMatching(name).value();
}
void Assign(const std::string& name, PoseRefiner* member) {
  *member = ParsePoseRefiner(name).value();
}

#define CWLOC_OPTION(field, type, flag, target, range, help)                       \
  OptionSpec{                                                                      \
      flag,                                                                        \
      #field,                                                                      \
      help,                                                                        \
      range,                                                                       \
      OptionTypeIndex<type>(),                                                     \
      [](const QueryOptions& o) { return OptionValue(type(ApiValue(o.target))); }, \
      [](QueryOptions* o, const OptionValue& v) { Assign(std::get<type>(v), &o->target); }},
// Function-local, so that an Options built during another file's static initialisation
// finds the table made.
std::span<const OptionSpec> Specs() {
  static const OptionSpec specs[] = {
#include "app/option_table.inc"
  };
  return specs;
}
#undef CWLOC_OPTION

}  // namespace

std::span<const OptionSpec> OptionTable() { return Specs(); }

const OptionSpec& FindOption(std::string_view flag) { return FindOptionSpec(Specs(), flag); }

void CheckOption(const OptionSpec& spec, const OptionValue& value) {
  if (value.index() != spec.type)
    throw std::logic_error("option --" + std::string(spec.flag) + ": value of the wrong type");
  CheckOptionValue(spec.flag, spec.range, value);
}

OptionValue ParseOption(const OptionSpec& spec, std::string_view text) {
  return ParseOptionValue(spec.flag, spec.range, spec.type, text);
}

OptionValue OptionFromNumber(const OptionSpec& spec, double number) {
  return OptionValueFromNumber(spec.flag, spec.range, spec.type, number);
}

void SetOption(QueryOptions* options, std::string_view flag, const OptionValue& value) {
  const OptionSpec& spec = FindOption(flag);
  CheckOption(spec, value);
  spec.set(options, value);
}

void ValidateQueryOptions(const QueryOptions& options) {
  for (const OptionSpec& spec : Specs()) CheckOption(spec, spec.get(options));
  CheckOptionRules(options);
}

void CheckOptionRules(const QueryOptions& options) {
  const RansacOptions& ransac = options.localizer.pose.ransac;
  if (ransac.min_iterations > ransac.max_iterations) {
    throw InputError("--min-ransac-iterations " + std::to_string(ransac.min_iterations) +
                     ": expected at most --max-ransac-iterations " +
                     std::to_string(ransac.max_iterations));
  }
  try {  // what only VLFeat computes, in a build without it (docs/devices.md)
    ValidateSiftOptions(options.photo.sift);
  } catch (const std::invalid_argument& e) {
    throw InputError(e.what());
  }
  const PoseRefiner refiner = options.localizer.pose.refiner;
  if (!PoseRefinerAvailable(refiner)) {
    throw InputError("--refiner " + std::string(PoseRefinerName(refiner)) +
                     ": this build has no Ceres (configured with -DCWLOC_WITH_CERES=OFF); use "
                     "--refiner builtin");
  }
}

}  // namespace cwloc
