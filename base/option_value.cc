#include "base/option_value.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <type_traits>

#include "base/error.h"

namespace cwloc {
namespace {

// A real range in words: "a value in (0, 1]", "degrees in (0, 90]", "a number of pixels > 0".
std::string RealRangeText(const ValueRange& range) {
  if (std::isfinite(range.max)) {
    return (range.unit.empty() ? std::string("a value") : std::string(range.unit)) + " in " +
           (range.min_open ? "(" : "[") + NumberText(range.min) + ", " + NumberText(range.max) +
           (range.max_open ? ")" : "]");
  }
  return (range.unit.empty() ? std::string("a value") : "a number of " + std::string(range.unit)) +
         (range.min_open ? " > " : " >= ") + NumberText(range.min);
}

// "a, b or c" of items as text.
template <typename T, typename ToText>
std::string ListText(std::span<const T> items, ToText to_text) {
  std::string text;
  for (size_t i = 0; i < items.size(); ++i) {
    if (i > 0) text += i + 1 == items.size() ? " or " : ", ";
    text += to_text(items[i]);
  }
  return text;
}

// "0 (full descriptors) or 4, 8, 16, 32 or 64".
std::string ChoicesText(const ValueRange& range) {
  const auto number = [](uint32_t choice) { return std::to_string(choice); };
  if (range.first_choice_note.empty() || range.choices.size() < 2)
    return ListText(range.choices, number);
  return std::to_string(range.choices[0]) + " (" + std::string(range.first_choice_note) + ") or " +
         ListText(range.choices.subspan(1), number);
}

// A bound of a whole-number type: its largest value is no double for 64 bits.
template <typename T>
std::string WholeText(double bound) {
  return bound >= double(std::numeric_limits<T>::max())
             ? std::to_string(std::numeric_limits<T>::max())
             : NumberText(bound);
}

template <typename T>
bool ParseAll(std::string_view text, T* value) {
  const char* end = text.data() + text.size();
  const auto [ptr, error] = std::from_chars(text.data(), end, *value);
  return error == std::errc() && ptr == end;
}

}  // namespace

void RefuseUnknownOption(std::string_view flag) {
  throw InputError("unknown option '" + std::string(flag) + "'");
}

void RefuseValue(std::string_view flag, std::string_view shown, const std::string& expected) {
  throw InputError("--" + std::string(flag) + " " + std::string(shown) + ": expected " + expected);
}

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
  return ListText(names, [](std::string_view name) { return std::string(name); });
}

namespace {

void CheckReal(std::string_view flag, const ValueRange& range, double value) {
  const bool in_range = std::isfinite(value) &&
                        (range.min_open ? value > range.min : value >= range.min) &&
                        (range.max_open ? value < range.max : value <= range.max);
  if (!in_range) RefuseValue(flag, NumberText(value), RealRangeText(range));
}

template <typename T>
void CheckWhole(std::string_view flag, const ValueRange& range, double number,
                std::string_view shown) {
  if (!range.choices.empty()) {
    if (std::find(range.choices.begin(), range.choices.end(), number) == range.choices.end())
      RefuseValue(flag, shown, ChoicesText(range));
    return;
  }
  const double low = std::max(range.min, double(std::numeric_limits<T>::min()));
  const double high = std::min(range.max, double(std::numeric_limits<T>::max()));
  if (number >= low && number <= high) return;
  const bool unbounded = high == double(std::numeric_limits<T>::max());
  RefuseValue(flag, shown,
              number < low && unbounded ? "at least " + WholeText<T>(low)
                                        : WholeText<T>(low) + " to " + WholeText<T>(high));
}

// A number that should be whole, shown as the user gave it.
template <typename T>
T WholeFrom(std::string_view flag, const ValueRange& range, double number, std::string_view shown) {
  if (!std::isfinite(number) || number != std::floor(number))
    RefuseValue(flag, shown, "a whole number");
  CheckWhole<T>(flag, range, number, shown);
  // 2^64 passes the range of uint64, whose largest value rounds to it as a double.
  if (number >= std::ldexp(1.0, std::numeric_limits<T>::digits))
    RefuseValue(flag, shown, "at most " + WholeText<T>(number));
  return static_cast<T>(number);
}

template <typename T>
T WholeFromText(std::string_view flag, const ValueRange& range, std::string_view text) {
  T value;
  if (ParseAll(text, &value)) {
    CheckWhole<T>(flag, range, double(value), text);
    return value;
  }
  double number;  // "-1", "1e3" and numbers too big for T hear the range
  if (!ParseAll(text, &number)) RefuseValue(flag, text, "a whole number");
  return WholeFrom<T>(flag, range, number, text);
}

}  // namespace

void CheckOptionValue(std::string_view flag, const ValueRange& range, const OptionValue& value) {
  std::visit(
      [&](const auto& v) {
        using T = std::decay_t<decltype(v)>;
        if constexpr (std::is_same_v<T, std::string>) {
          if (!range.names.empty() &&
              std::find(range.names.begin(), range.names.end(), v) == range.names.end())
            RefuseValue(flag, v, NamesText(range.names));
        } else if constexpr (std::is_same_v<T, double>) {
          CheckReal(flag, range, v);
        } else if constexpr (std::is_integral_v<T> && !std::is_same_v<T, bool>) {
          CheckWhole<T>(flag, range, double(v), std::to_string(v));
        }  // switches and paths have no range
      },
      value);
}

OptionValue ParseOptionValue(std::string_view flag, const ValueRange& range, size_t type,
                             std::string_view text) {
  switch (type) {
    case OptionTypeIndex<bool>():
      if (text == "true" || text == "1") return true;
      if (text == "false" || text == "0") return false;
      RefuseValue(flag, text, "true or false");
    case OptionTypeIndex<int32_t>():
      return WholeFromText<int32_t>(flag, range, text);
    case OptionTypeIndex<uint32_t>():
      return WholeFromText<uint32_t>(flag, range, text);
    case OptionTypeIndex<uint64_t>():
      return WholeFromText<uint64_t>(flag, range, text);
    case OptionTypeIndex<double>(): {
      double number;
      if (!ParseAll(text, &number)) RefuseValue(flag, text, "a number");
      CheckReal(flag, range, number);
      return number;
    }
    case OptionTypeIndex<std::string>(): {
      OptionValue name{std::string(text)};
      CheckOptionValue(flag, range, name);
      return name;
    }
    default:
      return std::filesystem::path(text);
  }
}

OptionValue OptionValueFromNumber(std::string_view flag, const ValueRange& range, size_t type,
                                  double number) {
  switch (type) {
    case OptionTypeIndex<bool>():
      if (number == 1) return true;
      if (number == 0) return false;
      RefuseValue(flag, NumberText(number), "true or false (1 or 0)");
    case OptionTypeIndex<int32_t>():
      return WholeFrom<int32_t>(flag, range, number, NumberText(number));
    case OptionTypeIndex<uint32_t>():
      return WholeFrom<uint32_t>(flag, range, number, NumberText(number));
    case OptionTypeIndex<uint64_t>():
      return WholeFrom<uint64_t>(flag, range, number, NumberText(number));
    case OptionTypeIndex<double>():
      CheckReal(flag, range, number);
      return number;
    default:
      RefuseValue(flag, NumberText(number),
                  range.names.empty() ? "a name" : NamesText(range.names));
  }
}

std::string FormatOptionValue(const OptionValue& value) {
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

}  // namespace cwloc
