#include "serve/request_inputs.h"

#include <cmath>
#include <nlohmann/json.hpp>
#include <variant>
#include <vector>

#include "app/camera_spec.h"
#include "app/motion_file.h"
#include "app/query_priors.h"
#include "base/error.h"
#include "base/option_value.h"

namespace cwloc {
namespace {

using Json = nlohmann::json;

std::string Key(const std::string& key) { return "options: '" + key + "'"; }

std::string NumberText(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.17g", value);
  return text;
}

// A string as it is, or an array of numbers as the text the CLI's flag takes.
std::string TextOrNumbers(const std::string& key, const Json& value) {
  if (value.is_string()) return value.get<std::string>();
  if (value.is_array()) {
    std::string text;
    for (const Json& number : value) {
      if (!number.is_number())
        throw InputError(Key(key) + ": expected a string or an array of numbers");
      if (!text.empty()) text += ' ';
      text += NumberText(number.get<double>());
    }
    return text;
  }
  throw InputError(Key(key) + ": expected a string or an array of numbers");
}

std::string String(const std::string& key, const Json& value) {
  if (!value.is_string()) throw InputError(Key(key) + ": expected a string");
  return value.get<std::string>();
}

double Number(const std::string& key, const Json& value) {
  if (!value.is_number() || !std::isfinite(value.get<double>()))
    throw InputError(Key(key) + ": expected a finite number");
  return value.get<double>();
}

FrameMotion MotionOf(const std::string& key, const Json& value) {
  std::variant<FrameMotion, std::string> motion =
      ParseMotion(TextOrNumbers(key, value), "QW QX QY QZ TX TY TZ [SIGMA_ROT_DEG SIGMA_POS]");
  if (const auto* problem = std::get_if<std::string>(&motion))
    throw InputError(Key(key) + ": " + *problem);
  return std::get<FrameMotion>(motion);
}

void ApplyTableOption(const std::string& key, const Json& value, QueryOptions* options) {
  const OptionSpec* found = nullptr;
  try {
    found = &FindOption(key);
  } catch (const InputError& e) {
    throw InputError(std::string("options: ") + e.what());
  }
  const OptionSpec& spec = *found;
  try {
    if (value.is_boolean()) {
      SetOption(options, key, ParseOption(spec, value.get<bool>() ? "true" : "false"));
    } else if (value.is_number()) {
      SetOption(options, key, OptionFromNumber(spec, value.get<double>()));
    } else if (value.is_string()) {
      SetOption(options, key, ParseOption(spec, value.get<std::string>()));
    } else {
      throw InputError("expected a number, a string or true/false");
    }
  } catch (const InputError& e) {
    throw InputError(Key(key) + ": " + e.what());
  }
}

}  // namespace

void ApplyRequestOptions(std::string_view json_text, const RequestLimits& limits,
                         RequestInputs* inputs) {
  if (json_text.size() > kMaxOptionsBytes) {
    throw InputError("options: " + std::to_string(json_text.size()) + " bytes, more than " +
                     std::to_string(kMaxOptionsBytes));
  }
  const Json object = Json::parse(json_text, nullptr, /*allow_exceptions=*/false);
  if (object.is_discarded()) throw InputError("options: not valid JSON");
  if (!object.is_object()) throw InputError("options: expected a JSON object");
  CameraInputs& cameras = inputs->cameras;
  for (const auto& [key, value] : object.items()) {
    if (key == "camera") {
      cameras.camera = ParseCameraSpec(String(key, value), "options: 'camera'");
    } else if (key == "image_size") {
      cameras.image_size = ParseImageSize(String(key, value), "options: 'image_size'");
    } else if (key == "focal") {
      cameras.focal_px = Number(key, value);
      if (cameras.focal_px <= 0) throw InputError(Key(key) + ": expected a focal length > 0");
    } else if (key == "unknown_focal") {
      if (!value.is_boolean()) throw InputError(Key(key) + ": expected true or false");
      cameras.unknown_focal = value.get<bool>();
    } else if (key == "prior_position") {
      inputs->priors.position =
          ParsePositionPrior(TextOrNumbers(key, value), "options: 'prior_position'");
    } else if (key == "prior_gravity") {
      inputs->priors.gravity =
          ParseGravityPrior(TextOrNumbers(key, value), "options: 'prior_gravity'");
    } else if (key == "name") {
      inputs->name = String(key, value);
      if (inputs->name.empty() || inputs->name.size() > 256)
        throw InputError(Key(key) + ": expected 1 to 256 characters");
    } else if (key == "timestamp") {
      inputs->timestamp = Number(key, value);
    } else if (key == "motion") {
      inputs->motion = MotionOf(key, value);
    } else {
      ApplyTableOption(key, value, &inputs->options);
    }
  }
  if (cameras.camera && (cameras.focal_px > 0 || cameras.image_size))
    throw InputError("options: 'camera' excludes 'focal' and 'image_size'");
  ValidateQueryOptions(inputs->options);
  if (inputs->options.photo.max_image_pixels > limits.max_image_pixels) {
    throw InputError("options: 'max-image-pixels' " +
                     std::to_string(inputs->options.photo.max_image_pixels) +
                     ": this server allows at most " + std::to_string(limits.max_image_pixels));
  }
}

}  // namespace cwloc
