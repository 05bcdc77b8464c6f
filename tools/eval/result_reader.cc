#include "tools/eval/result_reader.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <unordered_map>

#include "base/error.h"
#include "tools/eval/ground_truth.h"

namespace cwloc::eval {
namespace {

using nlohmann::json;

std::string_view LeftTrimmed(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  return begin == std::string::npos ? std::string_view() : std::string_view(s).substr(begin);
}

// Reads a fixed-size array of finite numbers, or throws with the field's name.
template <size_t N>
std::array<double, N> NumberArray(const json& object, const char* key, const std::string& where,
                                  const char* field) {
  const auto it = object.find(key);
  std::array<double, N> values{};
  const bool ok = it != object.end() && it->is_array() && it->size() == N;
  for (size_t i = 0; ok && i < N; ++i) {
    if (!(*it)[i].is_number() || !std::isfinite(values[i] = (*it)[i].get<double>())) {
      throw InputError(where + "\"" + field + "\" must be an array of " + std::to_string(N) +
                       " finite numbers");
    }
  }
  if (!ok)
    throw InputError(where + "\"" + field + "\" must be an array of " + std::to_string(N) +
                     " finite numbers");
  return values;
}

// "pose": {"qvec": [4], "tvec": [3]} of `object`, which `field` names in messages.
Pose ReadPose(const json& object, const std::string& where, const std::string& field) {
  const auto pose = object.find("pose");
  if (pose == object.end() || !pose->is_object())
    throw InputError(where + "\"success\" is true but there is no \"" + field + "\" object");
  const std::string qvec = field + ".qvec", tvec = field + ".tvec";
  const auto q = NumberArray<4>(*pose, "qvec", where, qvec.c_str());
  const auto t = NumberArray<3>(*pose, "tvec", where, tvec.c_str());
  const Eigen::Quaterniond rotation(q[0], q[1], q[2], q[3]);
  if (rotation.norm() < 1e-12) throw InputError(where + "\"" + qvec + "\" is zero");
  return Pose{rotation.normalized(), Eigen::Vector3d(t[0], t[1], t[2])};
}

// A rig frame's record: one result per image, the first its reference camera.
std::vector<QueryResult> ParseRigRecord(const json& record, const std::string& frame,
                                        const std::string& where) {
  const auto images = record.find("images");
  if (images == record.end() || !images->is_array() || images->empty())
    throw InputError(where + "a rig frame's \"images\" must be a non-empty array");
  std::vector<QueryResult> results;
  for (size_t i = 0; i < images->size(); ++i) {
    const json& image = (*images)[i];
    const std::string field = "images[" + std::to_string(i) + "]";
    const auto name = image.is_object() ? image.find("name") : image.end();
    if (name == image.end() || !name->is_string() || name->get<std::string>().empty())
      throw InputError(where + "\"" + field + ".name\" must be a non-empty string");
    QueryResult result;
    result.name = name->get<std::string>();
    result.rig_frame = frame;
    result.rig_reference = i == 0;
    if (image.contains("pose")) {
      result.pose = ReadPose(image, where, field + ".pose");
      result.status = ResultStatus::kLocalized;
    }
    results.push_back(std::move(result));
  }
  return results;
}

QueryResult ParseJsonLine(const std::string& line, const std::string& where,
                          std::vector<QueryResult>* rig_images) {
  const json record = json::parse(line, nullptr, /*allow_exceptions=*/false);
  if (record.is_discarded()) throw InputError(where + "not valid JSON");
  if (!record.is_object())
    throw InputError(where + "expected a JSON object (one cwloc-localize result per line)");
  QueryResult result;
  const auto name = record.find("name");
  if (name == record.end() || !name->is_string() || name->get<std::string>().empty()) {
    throw InputError(where + "expected a non-empty string \"name\"");
  }
  result.name = name->get<std::string>();
  const auto success = record.find("success");
  if (success == record.end() || !success->is_boolean())
    throw InputError(where + "expected a boolean \"success\"");

  if (record.contains("rig")) {
    *rig_images = ParseRigRecord(record, result.name, where);
    return result;
  }
  if (success->get<bool>()) {
    result.pose = ReadPose(record, where, "pose");
    result.status = ResultStatus::kLocalized;
  } else {
    result.status = record.contains("error") ? ResultStatus::kError : ResultStatus::kNotLocalized;
  }

  if (const auto geo = record.find("geo"); geo != record.end()) {
    if (!geo->is_object()) throw InputError(where + "\"geo\" must be an object");
    // Only the position is compared; enu and the attitude angles are not read.
    double values[3];
    const char* keys[] = {"latitude_deg", "longitude_deg", "height_m"};
    for (int k = 0; k < 3; ++k) {
      const auto value = geo->find(keys[k]);
      if (value == geo->end() || !value->is_number() ||
          !std::isfinite(values[k] = value->get<double>())) {
        throw InputError(where + "\"geo." + keys[k] + "\" must be a finite number");
      }
    }
    result.geo = Geodetic{values[0], values[1], values[2]};
    // "FILE:LINE: "geo": latitude 91 is outside [-90, 90]"
    ValidateGeodetic(*result.geo, where + "\"geo\"");
  }

  if (const auto covariance = record.find("covariance"); covariance != record.end()) {
    const auto pose = covariance->is_object() ? covariance->find("pose") : covariance->end();
    Eigen::Matrix3d position;
    bool valid = pose != covariance->end() && pose->is_array() && pose->size() == 6;
    for (int r = 0; valid && r < 6; ++r) {
      const json& row = (*pose)[r];
      valid = row.is_array() && row.size() == 6;
      for (int c = 0; valid && c < 6; ++c) {
        valid = row[c].is_number() && std::isfinite(row[c].get<double>());
        if (valid && r >= 3 && c >= 3) position(r - 3, c - 3) = row[c].get<double>();
      }
    }
    if (!valid) throw InputError(where + "\"covariance.pose\" must be 6 x 6 finite numbers");
    result.position_covariance = position;
  }

  if (const auto times = record.find("times_ms"); times != record.end()) {
    if (!times->is_object()) throw InputError(where + "\"times_ms\" must be an object");
    StageTimes stage_times{};
    for (size_t s = 0; s < kStageNames.size(); ++s) {
      const auto value = times->find(kStageNames[s]);
      if (value == times->end() && std::string_view(kStageNames[s]) == "extraction") continue;
      if (value == times->end() || !value->is_number() || !std::isfinite(value->get<double>())) {
        throw InputError(where + "\"times_ms." + kStageNames[s] + "\" must be a number");
      }
      stage_times[s] = value->get<double>();
    }
    result.times_ms = stage_times;
  }
  if (const auto tracking = record.find("tracking"); tracking != record.end()) {
    const auto mode = tracking->is_object() ? tracking->find("mode") : tracking->end();
    if (mode == tracking->end() || !mode->is_string() ||
        (*mode != "tracked" && *mode != "relocalized" && *mode != "lost")) {
      throw InputError(where + "\"tracking.mode\" must be tracked, relocalized or lost");
    }
    result.tracking_mode = mode->get<std::string>();
  }
  if (const auto ranked = record.find("ranked_images"); ranked != record.end()) {
    if (!ranked->is_array()) throw InputError(where + "\"ranked_images\" must be an array");
    for (const auto& image : *ranked) {
      const auto id = image.is_object() ? image.find("image_id") : image.end();
      if (id == image.end() || !id->is_number_unsigned()) {
        throw InputError(where +
                         "\"ranked_images\" entries need a non-negative integer \"image_id\"");
      }
      result.ranked_image_ids.push_back(id->get<uint32_t>());
    }
  }
  return result;
}

}  // namespace

const char* ResultFormatName(ResultFormat format) {
  return format == ResultFormat::kJsonLines ? "json-lines" : "poses";
}

RunResults ReadResults(const std::filesystem::path& path) {
  RunResults run;
  run.path = path;
  const std::vector<std::string> lines = ReadLines(path);
  for (const std::string& line : lines) {
    const std::string_view trimmed = LeftTrimmed(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    run.format = trimmed[0] == '{' ? ResultFormat::kJsonLines : ResultFormat::kPoses;
    break;
  }

  if (run.format == ResultFormat::kJsonLines) {
    for (size_t i = 0; i < lines.size(); ++i) {
      if (LeftTrimmed(lines[i]).empty()) continue;
      std::vector<QueryResult> rig_images;
      QueryResult result = ParseJsonLine(lines[i], Where(path, int(i) + 1), &rig_images);
      if (rig_images.empty()) rig_images.push_back(std::move(result));
      for (QueryResult& image : rig_images) {
        image.line = int(i) + 1;
        run.queries.push_back(std::move(image));
      }
    }
  } else {
    for (NamedPose& entry : ReadPosesFile(path)) {
      QueryResult result;
      result.name = std::move(entry.name);
      result.status = ResultStatus::kLocalized;
      result.pose = entry.pose;
      result.line = entry.line;
      run.queries.push_back(std::move(result));
    }
  }

  // Two answers for one query would make the counts ambiguous.
  std::unordered_map<std::string, int> first_line;
  for (const QueryResult& result : run.queries) {
    const auto [it, inserted] = first_line.emplace(result.name, result.line);
    if (!inserted) {
      throw InputError(Where(path, result.line) + "duplicate result for " + result.name +
                       " (first on line " + std::to_string(it->second) + ")");
    }
  }
  return run;
}

}  // namespace cwloc::eval
