// A result's field by its path, as C reads it (cwloc_result_value and its siblings): the names
// of the descriptions (describe.h) joined by dots, a list's item by its index ("num_inliers",
// "covariance.position_radius95", "ranked_images.0.name", "images.1.pose.rotation").

#ifndef CWLOC_RESULTS_RESULT_PATHS_H_
#define CWLOC_RESULTS_RESULT_PATHS_H_

#include <charconv>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "describe.h"

namespace cwloc {

// What a path names.
struct PathValue {
  enum class Kind { kNumber, kText, kNumbers, kObject, kList };
  Kind kind = Kind::kNumber;
  double number = 0;            // kNumber: a number, a switch (1 or 0), an enum's index
  const char* text = nullptr;   // kText, and an enum's name; lives as long as the result
  std::vector<double> numbers;  // kNumbers
  size_t size = 0;              // kList: its items; kNumbers: its numbers
  bool enumerated = false;      // kText of an enum, whose index `number` holds
};

// Why a path names nothing: an unknown name (kUnknown) or an absent value (kAbsent).
struct PathError {
  enum class Kind { kUnknown, kAbsent } kind;
  std::string message;
};

namespace result_paths {

// The path's first segment and the rest.
inline std::pair<std::string_view, std::string_view> Split(std::string_view path) {
  const size_t dot = path.find('.');
  if (dot == std::string_view::npos) return {path, {}};
  return {path.substr(0, dot), path.substr(dot + 1)};
}

template <typename T>
PathValue Resolve(const T& value, std::string_view path, const std::string& where);

// `value`, a field's at `where`, with `rest` of the path still to follow.
template <typename T>
PathValue ResolveValue(const T& value, std::string_view rest, const std::string& where,
                       const FieldInfo& info) {
  const auto leaf = [&](PathValue out) {
    if (!rest.empty())
      throw PathError{PathError::Kind::kUnknown,
                      "'" + where + "' has no field '" + std::string(rest) + "'"};
    return out;
  };
  if constexpr (IsOptional<T>::value) {
    if (!value) {
      throw PathError{PathError::Kind::kAbsent,
                      "'" + where + "' is absent" +
                          (info.help.empty() ? "" : " (" + std::string(info.help) + ")")};
    }
    return ResolveValue(*value, rest, where, info);
  } else if constexpr (kDescribed<T>) {
    if (rest.empty()) {
      PathValue out;
      out.kind = PathValue::Kind::kObject;
      return out;
    }
    return Resolve(value, rest, where + ".");
  } else if constexpr (kNumericList<T>) {
    PathValue out;
    out.kind = PathValue::Kind::kNumbers;
    out.numbers.assign(value.begin(), value.end());
    out.size = out.numbers.size();
    return leaf(std::move(out));
  } else if constexpr (IsVector<T>::value) {
    if (rest.empty()) {
      PathValue out;
      out.kind = PathValue::Kind::kList;
      out.size = value.size();
      return out;
    }
    const auto [segment, after] = Split(rest);
    size_t i = 0;
    const auto [end, error] = std::from_chars(segment.data(), segment.data() + segment.size(), i);
    if (error != std::errc() || end != segment.data() + segment.size() || i >= value.size()) {
      throw PathError{PathError::Kind::kUnknown,
                      "'" + where + "' has " + std::to_string(value.size()) + " items, no item '" +
                          std::string(segment) + "'"};
    }
    return ResolveValue(value[i], after, where + "." + std::string(segment), info);
  } else if constexpr (std::is_same_v<T, std::string>) {
    PathValue out;
    out.kind = PathValue::Kind::kText;
    out.text = value.c_str();
    return leaf(std::move(out));
  } else if constexpr (kNamedEnum<T>) {
    PathValue out;
    out.kind = PathValue::Kind::kText;
    out.text = NameOf(value).data();  // a literal: NUL-terminated
    out.number = static_cast<double>(value);
    out.enumerated = true;
    return leaf(std::move(out));
  } else {
    static_assert(std::is_arithmetic_v<T>, "a described field of a type C cannot read");
    PathValue out;
    out.number = static_cast<double>(value);
    return leaf(std::move(out));
  }
}

template <typename T>
PathValue Resolve(const T& value, std::string_view path, const std::string& where) {
  // Named copies, not a structured binding: clang 14 cannot capture one in the lambdas below.
  const auto parts = Split(path);
  const std::string_view segment = parts.first;
  const std::string_view rest = parts.second;
  std::optional<PathValue> found;
  ForEachField<T>([&](const auto& field) {
    if (!found && field.info.name == segment)
      found = ResolveValue(value.*field.member, rest, where + std::string(segment), field.info);
  });
  if (!found) {
    std::string names;
    ForEachField<T>([&](const auto& field) {
      names += (names.empty() ? "" : ", ") + std::string(field.info.name);
    });
    throw PathError{PathError::Kind::kUnknown,
                    "'" + where + std::string(segment) + "' is no field; " +
                        std::string(Description<T>::name) + " has " + names};
  }
  return std::move(*found);
}

}  // namespace result_paths

// The value `path` names in `result`; throws PathError.
template <typename T>
PathValue ResolvePath(const T& result, std::string_view path) {
  return result_paths::Resolve(result, path, "");
}

}  // namespace cwloc

#endif  // CWLOC_RESULTS_RESULT_PATHS_H_
