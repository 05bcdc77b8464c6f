#pragma once

// The JSON record of any described value (results/describe.h): each field at its key, a dotted
// key inside the object it names, absent values omitted or null as the field says.

#include <nlohmann/json.hpp>
#include <optional>
#include <string_view>

#include "results/describe.h"

namespace cwloc {

template <Described T>
nlohmann::ordered_json RecordJson(const T& value);

namespace record_json {

using Json = nlohmann::ordered_json;

// A field's value as the record writes it; nullopt when it has none.
template <typename T>
std::optional<Json> ValueJson(const T& value, const FieldInfo& info) {
  if constexpr (IsOptional<T>::value) {
    if (!value) return std::nullopt;
    return ValueJson(*value, info);
  } else if constexpr (Described<T>) {
    Json object = RecordJson(value);
    if (object.empty()) return std::nullopt;  // an object of absent fields (priors without any)
    return object;
  } else if constexpr (NamedEnum<T>) {
    return Json(std::string(NameOf(value)));
  } else if constexpr (std::is_floating_point_v<T>) {
    return info.json_scale != 1 ? Json(value * info.json_scale) : Json(value);
  } else if constexpr (NumericList<T>) {
    if (info.rows == 0) return Json(value);
    const size_t columns = value.size() / info.rows;
    Json rows = Json::array();
    for (int r = 0; r < info.rows; ++r) {
      Json row = Json::array();
      for (size_t c = 0; c < columns; ++c) row.push_back(value[r * columns + c]);
      rows.push_back(std::move(row));
    }
    return rows;
  } else if constexpr (IsVector<T>::value) {
    Json list = Json::array();
    for (const auto& item : value) list.push_back(*ValueJson(item, info));
    return list;
  } else {
    return Json(value);
  }
}

// The object at a dotted key's path ("matches.forward": the record's "matches"), made on first
// use, and the key's last part.
inline std::pair<Json*, std::string_view> Place(Json& record, std::string_view key) {
  Json* object = &record;
  for (size_t dot; (dot = key.find('.')) != std::string_view::npos; key.remove_prefix(dot + 1))
    object = &(*object)[std::string(key.substr(0, dot))];
  return {object, key};
}

}  // namespace record_json

template <Described T>
nlohmann::ordered_json RecordJson(const T& value) {
  nlohmann::ordered_json record = nlohmann::ordered_json::object();
  ForEachField<T>([&](const auto& field) {
    const FieldInfo& info = field.info;
    if (info.json.empty() || (field.written != nullptr && !field.written(value))) return;
    std::optional<nlohmann::ordered_json> json = record_json::ValueJson(value.*field.member, info);
    if (!json && info.when_absent == WhenAbsent::kOmit) return;
    auto [object, key] = record_json::Place(record, info.json);
    (*object)[std::string(key)] = json ? std::move(*json) : nullptr;
  });
  return record;
}

}  // namespace cwloc
