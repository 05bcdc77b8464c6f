#include "indexer/build_option_table.h"

#include <charconv>
#include <cmath>
#include <stdexcept>
#include <type_traits>

#include "base/error.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {
namespace {

// The range column's vocabulary.
constexpr BuildValueRange AnyValue() { return {}; }
constexpr BuildValueRange Between(double min, double max) {
  BuildValueRange range;
  range.min = min;
  range.max = max;
  return range;
}
constexpr BuildValueRange AtLeast(double min) {
  return Between(min, std::numeric_limits<double>::infinity());
}
constexpr BuildValueRange Positive(std::string_view unit) {
  BuildValueRange range = AtLeast(0);
  range.min_open = true;
  range.unit = unit;
  return range;
}
template <size_t N>
constexpr BuildValueRange OneOf(const std::array<uint32_t, N>& choices,
                                std::string_view first_choice_note) {
  BuildValueRange range;
  range.choices = choices;
  range.first_choice_note = first_choice_note;
  return range;
}

// Between an option's table type and the member it lands in.
template <typename Type, typename T>
std::optional<BuildOptionValue> Get(const T& member) {
  return BuildOptionValue(std::in_place_type<Type>, Type(member));
}
template <typename Type, typename T>
std::optional<BuildOptionValue> Get(const std::optional<T>& member) {
  if (!member) return std::nullopt;
  return BuildOptionValue(std::in_place_type<Type>, Type(*member));
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
                  BuildOptionType<type>(),                                                         \
                  []([[maybe_unused]] const IndexBuildOptions& options,                            \
                     [[maybe_unused]] const IndexBuildFlags& flags) { return Get<type>(target); }, \
                  [](const BuildOptionValue& value, IndexBuildOptions* o, IndexBuildFlags* f) {    \
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

[[noreturn]] void Refuse(const BuildOptionSpec& spec, std::string_view shown,
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

// "0 (full descriptors) or 4, 8, 16, 32 or 64".
std::string ChoicesText(const BuildValueRange& range) {
  const auto list = [](std::span<const uint32_t> choices) {
    std::string text;
    for (size_t i = 0; i < choices.size(); ++i) {
      if (i > 0) text += i + 1 == choices.size() ? " or " : ", ";
      text += std::to_string(choices[i]);
    }
    return text;
  };
  if (range.first_choice_note.empty() || range.choices.size() < 2) return list(range.choices);
  return std::to_string(range.choices[0]) + " (" + std::string(range.first_choice_note) + ") or " +
         list(range.choices.subspan(1));
}

// A real option's range in words: "a positive number of metres", "a number in [0, 1]".
std::string RealRangeText(const BuildValueRange& range) {
  const std::string of = range.unit.empty() ? "" : " of " + std::string(range.unit);
  if (std::isinf(range.max)) {
    if (range.min == 0 && range.min_open) return "a positive number" + of;
    return "a number" + of + (range.min_open ? " > " : " >= ") + NumberText(range.min);
  }
  return "a number" + of + " in " + (range.min_open ? "(" : "[") + NumberText(range.min) + ", " +
         NumberText(range.max) + "]";
}

bool InRealRange(const BuildValueRange& range, double value) {
  return std::isfinite(value) && (range.min_open ? value > range.min : value >= range.min) &&
         value <= range.max;
}

// A bound of a whole-number type: its largest value is no double for 64 bits.
template <typename T>
std::string WholeText(double bound) {
  return bound >= double(std::numeric_limits<T>::max())
             ? std::to_string(std::numeric_limits<T>::max())
             : NumberText(bound);
}

// A whole number of type T (or one too large or small for it) against the range within what T
// holds: "1 to 64", "at least 1".
template <typename T>
void CheckWhole(const BuildOptionSpec& spec, double number, std::string_view shown) {
  const BuildValueRange& range = spec.range;
  if (!range.choices.empty()) {
    for (const uint32_t choice : range.choices) {
      if (number == choice) return;
    }
    Refuse(spec, shown, ChoicesText(range));
  }
  const double low = std::max(range.min, double(std::numeric_limits<T>::min()));
  const double high = std::min(range.max, double(std::numeric_limits<T>::max()));
  if (number >= low && number <= high) return;
  const bool unbounded = high == double(std::numeric_limits<T>::max());
  Refuse(spec, shown,
         number < low && unbounded ? "at least " + WholeText<T>(low)
                                   : WholeText<T>(low) + " to " + WholeText<T>(high));
}

template <typename T>
bool ParseAll(std::string_view text, T* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, *value);
  return error == std::errc() && ptr == end;
}

template <typename T>
BuildOptionValue WholeFromText(const BuildOptionSpec& spec, std::string_view text) {
  T value;
  if (ParseAll(text, &value)) return value;
  double number;  // "-1", "1e3" and numbers too big for T hear the range
  if (!ParseAll(text, &number) || !std::isfinite(number) || number != std::floor(number))
    Refuse(spec, text, "a whole number");
  CheckWhole<T>(spec, number, text);
  // 2^64 passes the range of uint64, whose largest value rounds to it as a double.
  if (number >= std::ldexp(1.0, std::numeric_limits<T>::digits))
    Refuse(spec, text, "at most " + WholeText<T>(number));
  return static_cast<T>(number);
}

}  // namespace

std::span<const BuildOptionSpec> BuildOptionTable() { return Specs(); }

const BuildOptionSpec& FindBuildOption(std::string_view flag) {
  for (const BuildOptionSpec& spec : Specs()) {
    if (spec.flag == flag) return spec;
  }
  throw InputError("unknown option '" + std::string(flag) + "'");
}

void CheckBuildOption(const BuildOptionSpec& spec, const BuildOptionValue& value) {
  if (value.index() != spec.type)
    throw std::logic_error("option --" + std::string(spec.flag) + ": value of the wrong type");
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, double>) {
          if (!InRealRange(spec.range, v)) Refuse(spec, NumberText(v), RealRangeText(spec.range));
        } else if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
          CheckWhole<T>(spec, double(v), std::to_string(v));
        }  // switches, names and paths have no range
      },
      value);
}

BuildOptionValue ParseBuildOption(const BuildOptionSpec& spec, std::string_view text) {
  switch (spec.type) {
    case BuildOptionType<bool>():
      if (text == "true" || text == "1") return true;
      if (text == "false" || text == "0") return false;
      Refuse(spec, text, "true or false");
    case BuildOptionType<int32_t>():
      return WholeFromText<int32_t>(spec, text);
    case BuildOptionType<uint32_t>():
      return WholeFromText<uint32_t>(spec, text);
    case BuildOptionType<uint64_t>():
      return WholeFromText<uint64_t>(spec, text);
    case BuildOptionType<double>(): {
      double number;
      if (!ParseAll(text, &number)) Refuse(spec, text, "a number");
      return number;
    }
    case BuildOptionType<std::string>():
      return std::string(text);
    default:
      return std::filesystem::path(text);
  }
}

std::string FormatBuildOption(const BuildOptionValue& value) {
  return std::visit(
      [](const auto& v) -> std::string {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>) {
          return v;
        } else if constexpr (std::is_same_v<T, std::filesystem::path>) {
          return v.string();
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

void ValidateBuildOptions(const IndexBuildOptions& options, const IndexBuildFlags& flags) {
  for (const BuildOptionSpec& spec : Specs()) {
    if (const std::optional<BuildOptionValue> value = spec.get(options, flags))
      CheckBuildOption(spec, *value);
  }
}

}  // namespace cwloc
