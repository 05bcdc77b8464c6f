#include "io/option_table.h"

#include <array>
#include <charconv>
#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "base/error.h"
#include "photo/sift/sift_extractor.h"

namespace cwloc {
namespace {

// The range column's vocabulary.
constexpr ValueRange AnyValue() { return {}; }
constexpr ValueRange Between(double min, double max) {
  ValueRange range;
  range.min = min;
  range.max = max;
  return range;
}
constexpr ValueRange AtLeast(double min) {
  return Between(min, std::numeric_limits<double>::infinity());
}
constexpr ValueRange AboveUpTo(double min, double max, std::string_view unit) {
  ValueRange range = Between(min, max);
  range.min_open = true;
  range.unit = unit;
  return range;
}
constexpr ValueRange Above(double min, std::string_view unit) {
  return AboveUpTo(min, std::numeric_limits<double>::infinity(), unit);
}
constexpr ValueRange Inside(double min, double max) {
  ValueRange range = AboveUpTo(min, max, "");
  range.max_open = true;
  return range;
}
template <size_t N>
constexpr ValueRange OneOf(const std::array<std::string_view, N>& names) {
  ValueRange range;
  range.names = names;
  return range;
}

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

template <typename T>
constexpr size_t TypeIndex() {
  return OptionValue(std::in_place_type<T>).index();
}

#define CWLOC_OPTION(field, type, flag, target, range, help)                       \
  OptionSpec{                                                                      \
      flag,                                                                        \
      help,                                                                        \
      range,                                                                       \
      TypeIndex<type>(),                                                           \
      [](const QueryOptions& o) { return OptionValue(type(ApiValue(o.target))); }, \
      [](QueryOptions* o, const OptionValue& v) { Assign(std::get<type>(v), &o->target); }},
// Function-local, so that an Options built during another file's static initialisation
// finds the table made.
std::span<const OptionSpec> Specs() {
  static const OptionSpec specs[] = {
#include "io/option_table.inc"
  };
  return specs;
}
#undef CWLOC_OPTION

[[noreturn]] void Refuse(const OptionSpec& spec, std::string_view shown,
                         const std::string& expected) {
  throw InputError("--" + std::string(spec.flag) + " " + std::string(shown) + ": expected " +
                   expected);
}

// The shortest text that reads back as the value; whole numbers without an exponent.
std::string NumberText(double value) {
  std::array<char, 32> text;
  const bool whole = std::abs(value) < 1e21 && value == std::floor(value);
  const auto end =
      whole ? std::to_chars(text.data(), text.data() + text.size(), value, std::chars_format::fixed)
                  .ptr
            : std::to_chars(text.data(), text.data() + text.size(), value).ptr;
  return std::string(text.data(), end);
}

std::string NamesText(std::span<const std::string_view> names) {
  std::string text;
  for (size_t i = 0; i < names.size(); ++i) {
    if (i > 0) text += i + 1 == names.size() ? " or " : ", ";
    text += names[i];
  }
  return text;
}

// A real option's range in words: "a value in (0, 1]", "a number of pixels > 0".
std::string RealRangeText(const ValueRange& range) {
  if (std::isfinite(range.max)) {
    return (range.unit.empty() ? std::string("a value") : std::string(range.unit)) + " in " +
           (range.min_open ? "(" : "[") + NumberText(range.min) + ", " + NumberText(range.max) +
           (range.max_open ? ")" : "]");
  }
  return (range.unit.empty() ? std::string("a value") : "a number of " + std::string(range.unit)) +
         (range.min_open ? " > " : " >= ") + NumberText(range.min);
}

bool InRealRange(const ValueRange& range, double value) {
  return std::isfinite(value) && (range.min_open ? value > range.min : value >= range.min) &&
         (range.max_open ? value < range.max : value <= range.max);
}

// A whole-number option's bounds: its range within what its type holds.
template <typename T>
std::pair<double, double> WholeBounds(const ValueRange& range) {
  return {std::max(range.min, double(std::numeric_limits<T>::min())),
          std::min(range.max, double(std::numeric_limits<T>::max()))};
}

// A bound of a whole-number type: its largest value is no double for 64 bits.
template <typename T>
std::string WholeText(double bound) {
  return bound >= double(std::numeric_limits<T>::max())
             ? std::to_string(std::numeric_limits<T>::max())
             : NumberText(bound);
}

template <typename T>
void CheckWholeRange(const OptionSpec& spec, double number, std::string_view shown) {
  const auto [low, high] = WholeBounds<T>(spec.range);
  if (number >= low && number <= high) return;
  const bool unbounded = high == double(std::numeric_limits<T>::max());
  Refuse(spec, shown,
         number < low && unbounded ? "at least " + WholeText<T>(low)
                                   : WholeText<T>(low) + " to " + WholeText<T>(high));
}

template <typename T>
OptionValue WholeFromNumber(const OptionSpec& spec, double number) {
  const std::string shown = NumberText(number);
  if (!std::isfinite(number) || number != std::floor(number)) Refuse(spec, shown, "a whole number");
  CheckWholeRange<T>(spec, number, shown);
  // 2^64 passes the range of uint64, whose largest value rounds to it as a double.
  if (number >= std::ldexp(1.0, std::numeric_limits<T>::digits))
    Refuse(spec, shown, "at most " + WholeText<T>(number));
  return static_cast<T>(number);
}

template <typename T>
bool ParseAll(std::string_view text, T* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, *value);
  return error == std::errc() && ptr == end;
}

template <typename T>
OptionValue WholeFromText(const OptionSpec& spec, std::string_view text) {
  T value;
  if (ParseAll(text, &value)) {
    CheckOption(spec, value);
    return value;
  }
  double number;  // "-1", "1e3" and numbers too big for T hear the range
  if (!ParseAll(text, &number)) Refuse(spec, text, "a whole number");
  return WholeFromNumber<T>(spec, number);
}

}  // namespace

std::span<const OptionSpec> OptionTable() { return Specs(); }

const OptionSpec& FindOption(std::string_view flag) {
  for (const OptionSpec& spec : Specs()) {
    if (spec.flag == flag) return spec;
  }
  throw InputError("unknown option '" + std::string(flag) + "'");
}

void CheckOption(const OptionSpec& spec, const OptionValue& value) {
  if (value.index() != spec.type)
    throw std::logic_error("option --" + std::string(spec.flag) + ": value of the wrong type");
  const ValueRange& range = spec.range;
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>) {
          for (std::string_view name : range.names) {
            if (name == v) return;
          }
          Refuse(spec, v, NamesText(range.names));
        } else if constexpr (std::is_same_v<T, double>) {
          if (!InRealRange(range, v)) Refuse(spec, NumberText(v), RealRangeText(range));
        } else if constexpr (!std::is_same_v<T, bool>) {
          CheckWholeRange<T>(spec, double(v), std::to_string(v));
        }
      },
      value);
}

OptionValue ParseOption(const OptionSpec& spec, std::string_view text) {
  switch (spec.type) {
    case TypeIndex<bool>():
      if (text == "true" || text == "1") return true;
      if (text == "false" || text == "0") return false;
      Refuse(spec, text, "true or false");
    case TypeIndex<int32_t>():
      return WholeFromText<int32_t>(spec, text);
    case TypeIndex<uint32_t>():
      return WholeFromText<uint32_t>(spec, text);
    case TypeIndex<uint64_t>():
      return WholeFromText<uint64_t>(spec, text);
    case TypeIndex<double>(): {
      double number;
      if (!ParseAll(text, &number)) Refuse(spec, text, "a number");
      CheckOption(spec, number);
      return number;
    }
    default: {
      const OptionValue name{std::string(text)};
      CheckOption(spec, name);
      return name;
    }
  }
}

OptionValue OptionFromNumber(const OptionSpec& spec, double number) {
  switch (spec.type) {
    case TypeIndex<bool>():
      if (number == 1) return true;
      if (number == 0) return false;
      Refuse(spec, NumberText(number), "true or false (1 or 0)");
    case TypeIndex<int32_t>():
      return WholeFromNumber<int32_t>(spec, number);
    case TypeIndex<uint32_t>():
      return WholeFromNumber<uint32_t>(spec, number);
    case TypeIndex<uint64_t>():
      return WholeFromNumber<uint64_t>(spec, number);
    case TypeIndex<double>():
      CheckOption(spec, number);
      return number;
    default:
      Refuse(spec, NumberText(number), NamesText(spec.range.names));
  }
}

std::string FormatOption(const OptionValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>) {
          return v;
        } else if constexpr (std::is_same_v<T, bool>) {
          return v ? "true" : "false";
        } else if constexpr (std::is_same_v<T, double>) {
          return NumberText(v);
        } else {
          return std::to_string(v);
        }
      },
      value);
}

void SetOption(QueryOptions* options, std::string_view flag, const OptionValue& value) {
  const OptionSpec& spec = FindOption(flag);
  CheckOption(spec, value);
  spec.set(options, value);
}

void ValidateQueryOptions(const QueryOptions& options) {
  for (const OptionSpec& spec : Specs()) CheckOption(spec, spec.get(options));
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
