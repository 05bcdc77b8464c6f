// How a result type lists its fields once for every surface: the JSON record
// (app/record_json.h), C's accessors by path (api/result_paths.h), Python's properties and stubs
// (python/src/described.h, tools/stubs/) and the schema test walk these descriptions.
// docs/architecture.md, "Results", shows how a field is added.
//
// A described type T is a plain struct with a specialization of Description<T> beside it:
//
//   template <> struct Description<GeoPose> {
//     static constexpr std::string_view name = "GeoPose", help = "A camera on the globe";
//     static constexpr auto fields = std::tuple(
//         MakeField(&GeoPose::latitude_deg,
//                   Info("latitude_deg").Json("latitude_deg").Unit("deg").Help("WGS84")), ...);
//   };
//
// Standard C++17 only: the public API installs these headers as <cwloc/...>. Include guards,
// not #pragma once: a file of the library may see both copies, which define the same types.
#ifndef CWLOC_RESULTS_DESCRIBE_H_
#define CWLOC_RESULTS_DESCRIBE_H_

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <vector>

namespace cwloc {

// How the JSON record writes a field with no value: an empty std::optional, or an object whose
// every field is absent.
enum class WhenAbsent { kOmit, kNull };

// What every surface calls a field and says of it, written as
// Info("name").Json("key").Unit("px").Help("...") (C++17: the API's headers include this).
struct FieldInfo {
  std::string_view name;  // the C++ member, the Python attribute, a segment of a C path
  // Its key in the JSON record; "a.b" puts it in the record's object "a". Empty: the record
  // leaves it out, and `why_not` says why.
  std::string_view json;
  std::string_view unit;  // "s", "px", "deg", "m", "model units"; "" for counts, flags, names
  std::string_view help;
  WhenAbsent when_absent = WhenAbsent::kOmit;
  // The record writes a number times this (seconds as milliseconds under a key "..._ms").
  double json_scale = 1;
  // An array of rows x (size / rows) numbers, row-major: the record writes its rows, Python a
  // matrix. 0: a plain list.
  int rows = 0;
  // A list of described objects that Python gives as one array per field (thousands of rows).
  bool columns = false;
  std::string_view why_not;  // why a surface does not have the field

  // Each setter copies by hand: clang will not run a member template in a constant expression
  // before the class that uses it is complete.
  constexpr FieldInfo Json(std::string_view key) const {
    FieldInfo copy = *this;
    copy.json = key;
    return copy;
  }
  constexpr FieldInfo Unit(std::string_view text) const {
    FieldInfo copy = *this;
    copy.unit = text;
    return copy;
  }
  constexpr FieldInfo Help(std::string_view text) const {
    FieldInfo copy = *this;
    copy.help = text;
    return copy;
  }
  constexpr FieldInfo NullWhenAbsent() const {
    FieldInfo copy = *this;
    copy.when_absent = WhenAbsent::kNull;
    return copy;
  }
  constexpr FieldInfo Scale(double scale) const {
    FieldInfo copy = *this;
    copy.json_scale = scale;
    return copy;
  }
  constexpr FieldInfo Rows(int count) const {
    FieldInfo copy = *this;
    copy.rows = count;
    return copy;
  }
  constexpr FieldInfo AsColumns() const {
    FieldInfo copy = *this;
    copy.columns = true;
    return copy;
  }
  constexpr FieldInfo WhyNot(std::string_view text) const {
    FieldInfo copy = *this;
    copy.why_not = text;
    return copy;
  }
};

constexpr FieldInfo Info(std::string_view name) {
  FieldInfo info;
  info.name = name;
  return info;
}

// A field of Owner (or of a base class of the described type) of type T.
template <typename Owner, typename T>
struct FieldDescriptor {
  using owner_type = Owner;
  using value_type = T;
  T Owner::*member;
  FieldInfo info;
  // When set, the JSON record writes the field only where this holds (a pose on success).
  bool (*written)(const Owner&) = nullptr;
};

template <typename Owner, typename T>
constexpr FieldDescriptor<Owner, T> MakeField(T Owner::*member, FieldInfo info,
                                              bool (*written)(const Owner&) = nullptr) {
  return {member, info, written};
}

// Specialized next to each described type: `name` and `help` (its Python class) and `fields`, a
// std::tuple of FieldDescriptor.
template <typename T>
struct Description;

// Specialized next to each enum a result reports: `names`, its spelling on every surface, in
// enum order.
template <typename E>
struct EnumNames;

template <typename T, typename = void>
inline constexpr bool kDescribed = false;
template <typename T>
inline constexpr bool kDescribed<T, std::void_t<decltype(Description<T>::fields)>> = true;
template <typename E, typename = void>
inline constexpr bool kNamedEnum = false;
template <typename E>
inline constexpr bool kNamedEnum<E, std::void_t<decltype(EnumNames<E>::names)>> = std::is_enum_v<E>;

template <typename E>
constexpr std::string_view NameOf(E value) {
  const auto& names = EnumNames<E>::names;
  const auto i = static_cast<size_t>(value);
  return i < names.size() ? names[i] : std::string_view("?");
}

// Calls fn(field) for each field of T's description, in order.
template <typename T, typename Fn>
constexpr void ForEachField(Fn&& fn) {
  std::apply([&](const auto&... field) { (fn(field), ...); }, Description<T>::fields);
}

// What a value of type T is to the surfaces.
template <typename T>
struct IsOptional : std::false_type {};
template <typename T>
struct IsOptional<std::optional<T>> : std::true_type {};
template <typename T>
struct IsVector : std::false_type {};
template <typename T>
struct IsVector<std::vector<T>> : std::true_type {};
template <typename T>
struct IsStdArray : std::false_type {};
template <typename T, size_t N>
struct IsStdArray<std::array<T, N>> : std::true_type {};

template <typename T>
inline constexpr bool kNumeric = std::is_arithmetic_v<T> && !std::is_same_v<T, bool>;
template <typename T, typename = void>
inline constexpr bool kNumericList = false;
// A list of numbers: std::array or std::vector of a number.
template <typename T>
inline constexpr bool
    kNumericList<T, std::enable_if_t<IsStdArray<T>::value || IsVector<T>::value>> =
        kNumeric<typename T::value_type>;

// The walks' vocabulary (C++20; the API's own code).
#if defined(__cpp_concepts)
template <typename T>
concept Described = kDescribed<T>;
template <typename T>
concept NamedEnum = kNamedEnum<T>;
template <typename T>
concept Numeric = kNumeric<T>;
// A list of numbers: std::array or std::vector of a Numeric.
template <typename T>
concept NumericList =
    (IsStdArray<T>::value || IsVector<T>::value) && Numeric<typename T::value_type>;
template <typename T>
concept NumericArray = IsStdArray<T>::value && Numeric<typename T::value_type>;
// A list of described objects.
template <typename T>
concept DescribedList = IsVector<T>::value && Described<typename T::value_type>;
#endif

}  // namespace cwloc

#endif  // CWLOC_RESULTS_DESCRIBE_H_
