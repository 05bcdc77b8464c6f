#include "app/result_json.h"

#include <cstdio>
#include <filesystem>
#include <type_traits>
#include <variant>

#include "app/record_json.h"

namespace cwloc {

nlohmann::ordered_json OptionsToJson(const QueryOptions& options) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const OptionSpec& spec : OptionTable()) {
    std::visit(
        [&](const auto& value) {
          if constexpr (std::is_same_v<std::decay_t<decltype(value)>, std::filesystem::path>)
            out[std::string(spec.name)] = value.string();
          else
            out[std::string(spec.name)] = value;
        },
        spec.get(options));
  }
  return out;
}

nlohmann::ordered_json ResultToJson(const LocalizationResult& result, const QueryOptions& options) {
  nlohmann::ordered_json out = RecordJson(result);
  out["parameters"] = OptionsToJson(options);
  return out;
}

nlohmann::ordered_json RigResultToJson(const RigResult& result, const QueryOptions& options) {
  nlohmann::ordered_json out = RecordJson(result);
  out["parameters"] = OptionsToJson(options);
  return out;
}

nlohmann::ordered_json ErrorToJson(const std::string& name, const std::string& error) {
  return {{"name", name}, {"success", false}, {"error", error}};
}

std::string PoseLine(const std::string& name, const Transform& cam_from_world) {
  const auto& q = cam_from_world.rotation;
  const auto& t = cam_from_world.translation;
  char buffer[512];
  std::snprintf(buffer, sizeof(buffer), "%s %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                name.c_str(), q[0], q[1], q[2], q[3], t[0], t[1], t[2]);
  return buffer;
}

std::string PoseLine(const LocalizationResult& result) {
  return PoseLine(result.name, Transform{result.rotation, result.translation});
}

}  // namespace cwloc
