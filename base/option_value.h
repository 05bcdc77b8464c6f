#pragma once

// An option's value, what it accepts and how a value is refused, shared by both option tables
// (app/option_table.inc for cwloc-localize and the library, indexer/build_option_table.inc for
// cwloc-index): every refusal is an InputError "--FLAG VALUE: expected ...", worded here once.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <variant>

namespace cwloc {

// A value of an option in its table type.
using OptionValue =
    std::variant<bool, int32_t, uint32_t, uint64_t, double, std::string, std::filesystem::path>;

// The index of T in OptionValue, as the tables' specs hold an option's type.
template <typename T, size_t I = 0>
constexpr size_t OptionTypeIndex() {
  if constexpr (std::is_same_v<std::variant_alternative_t<I, OptionValue>, T>) {
    return I;
  } else {
    return OptionTypeIndex<T, I + 1>();
  }
}

// Numbers between min and max (each bound open or closed; whole-number types are further
// limited to what they hold), or, when `names` is not empty, one of those names, or, when
// `choices` is not empty, one of those whole numbers.
struct ValueRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;
  std::string_view unit;                    // said in messages: "a number of pixels > 0"
  std::span<const std::string_view> names;  // a choice's names; empty for numbers
  std::span<const uint32_t> choices;        // whole numbers accepted; empty for a range
  std::string_view first_choice_note;       // "0 (full descriptors) or 4, 8, ..."
};

// The range column's vocabulary in both tables.
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
constexpr ValueRange OneOf(std::span<const std::string_view> names) {
  ValueRange range;
  range.names = names;
  return range;
}
constexpr ValueRange OneOf(std::span<const uint32_t> choices, std::string_view first_choice_note) {
  ValueRange range;
  range.choices = choices;
  range.first_choice_note = first_choice_note;
  return range;
}

// Throws InputError "unknown option 'FLAG'".
[[noreturn]] void RefuseUnknownOption(std::string_view flag);

// The spec (of either table) with this flag name (without dashes), or RefuseUnknownOption.
template <typename Spec>
const Spec& FindOptionSpec(std::span<const Spec> specs, std::string_view flag) {
  for (const Spec& spec : specs) {
    if (spec.flag == flag) return spec;
  }
  RefuseUnknownOption(flag);
}

// Throws InputError "--FLAG SHOWN: expected EXPECTED".
[[noreturn]] void RefuseValue(std::string_view flag, std::string_view shown,
                              const std::string& expected);

// The shortest text that reads back as the value; whole numbers without an exponent.
std::string NumberText(double value);

// "a, b or c".
std::string NamesText(std::span<const std::string_view> names);

// Refuses (RefuseValue) a value outside the range. Switches and paths have no range; a name is
// checked when the range has names.
void CheckOptionValue(std::string_view flag, const ValueRange& range, const OptionValue& value);

// Text as the command lines take it ("12", "1e3", "0.7", "true", "cluster-wise", a path), or a
// number as the C API takes it, as a value of the type at index `type` in OptionValue, checked.
OptionValue ParseOptionValue(std::string_view flag, const ValueRange& range, size_t type,
                             std::string_view text);
OptionValue OptionValueFromNumber(std::string_view flag, const ValueRange& range, size_t type,
                                  double number);

// A value as --help shows it and messages quote it: "4", "0.5", "true", "cluster-wise", a path.
std::string FormatOptionValue(const OptionValue& value);

}  // namespace cwloc
