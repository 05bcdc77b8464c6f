#include "app/rig_input.h"

#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <variant>

#include "base/bounded_file.h"
#include "base/error.h"
#include "geo/geo_region.h"

namespace cwloc {
namespace {

using nlohmann::json;

template <size_t N>
std::array<double, N> Numbers(const json& camera, const char* key, const std::string& where) {
  const auto it = camera.find(key);
  std::array<double, N> values{};
  bool ok = it != camera.end() && it->is_array() && it->size() == N;
  for (size_t i = 0; ok && i < N; ++i) {
    ok = (*it)[i].is_number() && std::isfinite(values[i] = (*it)[i].get<double>());
  }
  if (!ok)
    throw InputError(where + ": \"" + key + "\" must be " + std::to_string(N) + " finite numbers");
  return values;
}

RigConfigCamera ParseCamera(const json& camera, const std::string& where) {
  if (!camera.is_object()) throw InputError(where + ": a camera must be a JSON object");
  RigConfigCamera out;
  const auto prefix = camera.find("image_prefix");
  if (prefix == camera.end() || !prefix->is_string())
    throw InputError(where + ": \"image_prefix\" must be a string");
  out.image_prefix = prefix->get<std::string>();
  if (const auto ref = camera.find("ref_sensor"); ref != camera.end()) {
    if (!ref->is_boolean()) throw InputError(where + ": \"ref_sensor\" must be true or false");
    out.ref_sensor = ref->get<bool>();
  }
  const bool has_pose =
      camera.contains("cam_from_rig_rotation") || camera.contains("cam_from_rig_translation");
  if (out.ref_sensor && has_pose) {
    throw InputError(where +
                     ": the reference sensor's cam_from_rig is the identity; give no "
                     "cam_from_rig_rotation or cam_from_rig_translation");
  }
  if (!out.ref_sensor) {
    if (!has_pose) {
      throw InputError(where +
                       ": a camera that is not the reference sensor needs cam_from_rig_rotation "
                       "[w, x, y, z] and cam_from_rig_translation [x, y, z]");
    }
    std::variant<CameraPose, std::string> pose =
        PoseFromParts(Numbers<4>(camera, "cam_from_rig_rotation", where),
                      Numbers<3>(camera, "cam_from_rig_translation", where));
    if (const auto* problem = std::get_if<std::string>(&pose))
      throw InputError(where + ": cam_from_rig_rotation: " + *problem);
    out.cam_from_rig = std::get<CameraPose>(pose);
  }
  if (const auto model = camera.find("camera_model_name"); model != camera.end()) {
    if (!model->is_string()) throw InputError(where + ": \"camera_model_name\" must be a string");
    out.model_name = model->get<std::string>();
    const auto params = camera.find("camera_params");
    bool ok = params != camera.end() && params->is_array() && !params->empty();
    for (size_t i = 0; ok && i < params->size(); ++i) {
      ok = (*params)[i].is_number() && std::isfinite((*params)[i].get<double>());
      if (ok) out.params.push_back((*params)[i].get<double>());
    }
    if (!ok) {
      throw InputError(where +
                       ": \"camera_model_name\" needs \"camera_params\", an array of finite "
                       "numbers");
    }
  }
  return out;
}

bool IsFeatureFile(const std::string& name) {
  return name.size() > 4 && name.compare(name.size() - 4, 4, ".txt") == 0;
}

}  // namespace

std::vector<std::vector<RigConfigCamera>> ReadRigConfig(const std::filesystem::path& path) {
  const std::vector<uint8_t> bytes = ReadFileBounded(path, kRigConfigFile);
  const json config = json::parse(bytes.begin(), bytes.end(), nullptr, false);
  const std::string file = path.string();
  if (config.is_discarded()) throw InputError(file + ": not valid JSON");
  if (!config.is_array() || config.empty()) {
    throw InputError(file +
                     ": a rig config is a JSON array of rigs, each {\"cameras\": [...]} (COLMAP "
                     "3.12's rig_config.json)");
  }
  std::vector<std::vector<RigConfigCamera>> rigs;
  std::map<std::string, std::string> prefixes;  // prefix -> where it was given
  for (size_t r = 0; r < config.size(); ++r) {
    const std::string rig_where = file + ": rig " + std::to_string(r + 1);
    const json& rig = config[r];
    const auto cameras = rig.is_object() ? rig.find("cameras") : rig.end();
    if (cameras == rig.end() || !cameras->is_array())
      throw InputError(rig_where + ": expected an object with a \"cameras\" array");
    if (cameras->empty()) throw InputError(rig_where + " names no camera");
    std::vector<RigConfigCamera>& out = rigs.emplace_back();
    int references = 0;
    for (size_t c = 0; c < cameras->size(); ++c) {
      const std::string where = rig_where + ", camera " + std::to_string(c + 1);
      out.push_back(ParseCamera((*cameras)[c], where));
      references += out.back().ref_sensor;
      const auto [it, inserted] = prefixes.emplace(out.back().image_prefix, where);
      if (!inserted) {
        throw InputError(where + ": image_prefix '" + out.back().image_prefix + "' is also " +
                         it->second.substr(file.size() + 2) + "'s");
      }
    }
    if (references != 1) {
      throw InputError(rig_where + " has " + std::to_string(references) +
                       " cameras with \"ref_sensor\": true; a rig has exactly one");
    }
  }
  return rigs;
}

std::vector<RigFrameInput> FramesOfRigs(const std::vector<std::vector<RigConfigCamera>>& rigs,
                                        const std::filesystem::path& config,
                                        const std::vector<QueryListEntry>& entries,
                                        const std::filesystem::path& list,
                                        const std::filesystem::path& base) {
  std::vector<RigFrameInput> frames;
  // (rig, name after the prefix) -> frame; per frame, its images by camera.
  std::map<std::pair<size_t, std::string>, size_t> frame_of;
  std::vector<std::map<size_t, RigFrameImage>> cameras_of;
  std::vector<size_t> rig_of;
  for (const QueryListEntry& entry : entries) {
    size_t best_rig = 0, best_camera = 0, best_length = 0;
    bool found = false;
    for (size_t r = 0; r < rigs.size(); ++r) {
      for (size_t c = 0; c < rigs[r].size(); ++c) {
        const std::string& prefix = rigs[r][c].image_prefix;
        if (entry.name.compare(0, prefix.size(), prefix) != 0) continue;
        if (!found || prefix.size() > best_length) {
          found = true;
          best_rig = r;
          best_camera = c;
          best_length = prefix.size();
        }
      }
    }
    if (!found) {
      throw InputError(list.string() + ": image '" + entry.name + "' matches no image_prefix of " +
                       config.string());
    }
    const RigConfigCamera& camera = rigs[best_rig][best_camera];
    const std::string frame_name = entry.name.substr(best_length);
    const auto [it, inserted] = frame_of.emplace(std::pair(best_rig, frame_name), frames.size());
    if (inserted) {
      frames.push_back({frame_name, {}});
      cameras_of.emplace_back();
      rig_of.push_back(best_rig);
    }
    RigFrameImage image;
    image.source = {
        entry.name,
        IsFeatureFile(entry.name) ? QuerySource::Kind::kTextFeatures : QuerySource::Kind::kPhoto,
        base / entry.name, entry.camera, list.string()};
    image.cam_from_rig = camera.cam_from_rig;
    image.model_name = camera.model_name;
    image.params = camera.params;
    const auto [placed, fresh] = cameras_of[it->second].emplace(best_camera, std::move(image));
    if (!fresh) {
      throw InputError(list.string() + ": frame '" + frame_name + "' of rig " +
                       std::to_string(best_rig + 1) + " lists camera '" + camera.image_prefix +
                       "' twice ('" + placed->second.source.name + "' and '" + entry.name + "')");
    }
  }
  for (size_t f = 0; f < frames.size(); ++f) {
    const std::vector<RigConfigCamera>& rig = rigs[rig_of[f]];
    for (size_t c = 0; c < rig.size(); ++c) {  // the reference sensor first
      if (!rig[c].ref_sensor) continue;
      if (const auto it = cameras_of[f].find(c); it != cameras_of[f].end())
        frames[f].images.push_back(std::move(it->second));
    }
    for (auto& [c, image] : cameras_of[f])
      if (!rig[c].ref_sensor) frames[f].images.push_back(std::move(image));
  }
  return frames;
}

std::vector<RigFrameInput> ReadFramesFile(const std::filesystem::path& path,
                                          const std::filesystem::path& base) {
  CheckInputFile(path, kFramesFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the frames file");
  std::vector<RigFrameInput> frames;
  std::map<std::string, int> last_line_of;  // frame -> its last line so far
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string where = path.string() + ":" + std::to_string(number);
    std::istringstream fields(line);
    std::string frame, image;
    if (!(fields >> frame) || frame[0] == '#') continue;
    std::array<double, 7> v{};
    bool ok = static_cast<bool>(fields >> image);
    std::string token;
    for (size_t i = 0; ok && i < v.size(); ++i) {
      const auto number_value = (fields >> token) ? ParseFiniteNumbers(token) : std::nullopt;
      ok = number_value && number_value->size() == 1;
      if (ok) v[i] = (*number_value)[0];
    }
    if (!ok) {
      throw InputError(where +
                       ": expected 'FRAME_ID IMAGE QW QX QY QZ TX TY TZ [MODEL W H PARAMS]' "
                       "(the image's cam_from_rig)");
    }
    std::variant<CameraPose, std::string> pose =
        PoseFromParts({v[0], v[1], v[2], v[3]}, {v[4], v[5], v[6]});
    if (const auto* problem = std::get_if<std::string>(&pose))
      throw InputError(where + ": cam_from_rig: " + *problem);
    const std::string camera = RestOfLine(fields);
    const auto [seen, first] = last_line_of.emplace(frame, number);
    if (!first) {
      if (frames.back().name != frame) {
        throw InputError(where + ": frame '" + frame +
                         "' continues after other lines (it was on line " +
                         std::to_string(seen->second) + "); the lines of a frame are consecutive");
      }
      seen->second = number;
    } else {
      frames.push_back({frame, {}});
    }
    for (const RigFrameImage& other : frames.back().images) {
      if (other.source.name == image)
        throw InputError(where + ": frame '" + frame + "' lists image '" + image + "' twice");
    }
    RigFrameImage entry;
    entry.source = {
        image, IsFeatureFile(image) ? QuerySource::Kind::kTextFeatures : QuerySource::Kind::kPhoto,
        base / image, camera, path.string()};
    entry.cam_from_rig = std::get<CameraPose>(pose);
    frames.back().images.push_back(std::move(entry));
  }
  if (in.bad()) throw InputError(path.string() + ": cannot read the frames file");
  if (frames.empty()) throw InputError(path.string() + ": no frames");
  return frames;
}

}  // namespace cwloc
