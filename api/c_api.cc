// The C API: opaque handles over the C++ API, exceptions turned into status codes and a
// per-thread message.
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>

#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"
#include "results/result_paths.h"

struct cwloc_localizer {
  cwloc::api::Localizer localizer;
  cwloc::api::IndexInfo info;  // owns the strings cwloc_localizer_info returns
};

struct cwloc_options {
  cwloc::api::Options options;
};

struct cwloc_tracker {
  cwloc::api::Tracker tracker;
  cwloc::api::Options options;  // its frames' records echo them
};

// A query's or a rig frame's result, with the options it was made with (its JSON record echoes
// them).
struct cwloc_result {
  std::variant<cwloc::api::Result, cwloc::api::RigResult> result;
  cwloc::api::Options options;
  mutable std::string json;  // made when first asked for
};

namespace {

thread_local std::string last_error;

cwloc_status Fail(cwloc_status status, const std::string& message) {
  last_error = message;
  return status;
}

// Runs fn, which may throw; the one place exceptions become status codes.
cwloc_status Guarded(const std::function<void()>& fn) {
  try {
    fn();
    last_error.clear();
    return CWLOC_OK;
  } catch (const cwloc::api::Error& e) {
    return Fail(static_cast<cwloc_status>(e.code()), e.what());
  } catch (const std::bad_alloc&) {
    return Fail(CWLOC_ERROR_OUT_OF_MEMORY, "out of memory");
  } catch (const std::exception& e) {
    return Fail(CWLOC_ERROR_INTERNAL, std::string("internal error: ") + e.what());
  } catch (...) {
    return Fail(CWLOC_ERROR_INTERNAL, "internal error");
  }
}

std::optional<cwloc::api::Camera> ToCamera(const cwloc_camera* camera) {
  if (camera == nullptr) return std::nullopt;
  if (camera->params == nullptr && camera->num_params > 0)
    throw cwloc::api::Error(cwloc::api::ErrorCode::kInvalidArgument, "camera: params is NULL");
  cwloc::api::Camera out;
  out.model = camera->model != nullptr ? camera->model : "";
  out.width = camera->width;
  out.height = camera->height;
  out.params.assign(camera->params, camera->params + camera->num_params);
  out.calibration = static_cast<cwloc::api::Calibration>(camera->calibration);
  return out;
}

const cwloc::api::Options& OptionsOrDefault(const cwloc_options* options) {
  static const cwloc::api::Options defaults;
  return options != nullptr ? options->options : defaults;
}

// Checks the handle (a localizer or a tracker) and output arguments every query shares, then
// runs the query with these options.
template <typename Handle>
cwloc_status RunQuery(Handle* handle, cwloc_result** out, const cwloc::api::Options& options,
                      const std::function<cwloc::api::Result()>& query) {
  constexpr bool kTracker = std::is_same_v<std::remove_const_t<Handle>, cwloc_tracker>;
  if (out == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "out is NULL");
  *out = nullptr;
  if (handle == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, kTracker ? "tracker is NULL" : "localizer is NULL");
  return Guarded([&] { *out = new cwloc_result{query(), options, {}}; });
}

std::optional<double> ToTimestamp(const double* timestamp) {
  return timestamp != nullptr ? std::optional<double>(*timestamp) : std::nullopt;
}

std::optional<cwloc::api::Motion> ToMotion(const cwloc_motion* motion) {
  if (motion == nullptr) return std::nullopt;
  cwloc::api::Motion out;
  std::copy_n(motion->rotation_wxyz, 4, out.rotation.begin());
  std::copy_n(motion->translation, 3, out.translation.begin());
  out.sigma_rotation_deg = motion->sigma_rotation_deg;
  out.sigma_position = motion->sigma_position;
  return out;
}

// A query's features from C's arrays, which must be there when there are features.
cwloc::api::Features FeaturesOf(const float* keypoints, const uint8_t* descriptors,
                                uint32_t num_features) {
  if (num_features > 0 && (keypoints == nullptr || descriptors == nullptr)) {
    throw cwloc::api::Error(cwloc::api::ErrorCode::kInvalidArgument,
                            "keypoints or descriptors is NULL");
  }
  cwloc::api::Features features;
  features.keypoints.assign(keypoints, keypoints + size_t{num_features} * 2);
  features.descriptors.assign(descriptors, descriptors + size_t{num_features} * 128);
  return features;
}

// The camera features and grey images need (at least the image size).
cwloc::api::Camera RequiredCamera(const cwloc_camera* camera, const char* what) {
  const auto query_camera = ToCamera(camera);
  if (!query_camera) {
    throw cwloc::api::Error(cwloc::api::ErrorCode::kInvalidArgument,
                            std::string(what) + " (at least the image size)");
  }
  return *query_camera;
}

// The value a path names in the result, or the status and message why none; any argument may
// be NULL.
cwloc_status Resolve(const cwloc_result* result, const char* path, cwloc::PathValue* value) {
  if (result == nullptr || path == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result or path is NULL");
  try {
    *value = std::visit([&](const auto& r) { return cwloc::ResolvePath(r, path); }, result->result);
  } catch (const cwloc::PathError& e) {
    return Fail(e.kind == cwloc::PathError::Kind::kAbsent ? CWLOC_ERROR_NOT_AVAILABLE
                                                          : CWLOC_ERROR_INVALID_ARGUMENT,
                e.message);
  }
  last_error.clear();
  return CWLOC_OK;
}

// The kinds of value an accessor does not read, in its words.
cwloc_status WrongKind(const char* path, const cwloc::PathValue& value) {
  using Kind = cwloc::PathValue::Kind;
  const std::string what = value.kind == Kind::kObject ? "an object: name one of its fields"
                           : value.kind == Kind::kList ? "a list: cwloc_result_size, then an item"
                           : value.kind == Kind::kText ? "text: cwloc_result_text"
                           : value.kind == Kind::kNumbers ? "numbers: cwloc_result_values"
                                                          : "a number: cwloc_result_value";
  std::string message = "'";  // appended: GCC 12 misreads "'" + std::string (-Wrestrict)
  message.append(path).append("' is ").append(what);
  return Fail(CWLOC_ERROR_INVALID_ARGUMENT, message);
}

}  // namespace

extern "C" {

const char* cwloc_version(void) { return cwloc::api::Version(); }

const char* cwloc_last_error(void) { return last_error.c_str(); }

cwloc_status cwloc_index_apply(const char* index_path, const char* delta_path,
                               const char* output_path, int threads) {
  if (index_path == nullptr || delta_path == nullptr || output_path == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "a path is NULL");
  return Guarded(
      [&] { cwloc::api::ApplyIndexDelta(index_path, delta_path, output_path, threads); });
}

cwloc_status cwloc_localizer_open(const char* index_path, int verify, cwloc_localizer** out) {
  if (out == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "out is NULL");
  *out = nullptr;
  if (index_path == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "index_path is NULL");
  return Guarded([&] {
    cwloc::api::Localizer localizer = cwloc::api::Localizer::Open(index_path, verify != 0);
    cwloc::api::IndexInfo info = localizer.Info();
    *out = new cwloc_localizer{std::move(localizer), std::move(info)};
  });
}

void cwloc_localizer_close(cwloc_localizer* localizer) { delete localizer; }

cwloc_status cwloc_localizer_info(const cwloc_localizer* localizer, cwloc_index_info* info) {
  if (localizer == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "localizer is NULL");
  if (info == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "info is NULL");
  const cwloc::api::IndexInfo& i = localizer->info;
  *info = {
      i.path.c_str(),   i.format_version.c_str(), i.num_images,          i.num_points,
      i.num_views,      i.georeferenced ? 1 : 0,  i.origin_latitude_deg, i.origin_longitude_deg,
      i.origin_height_m};
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_options_create(cwloc_options** out) {
  if (out == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "out is NULL");
  return Guarded([&] { *out = new cwloc_options{}; });
}

void cwloc_options_destroy(cwloc_options* options) { delete options; }

cwloc_status cwloc_options_set(cwloc_options* options, const char* name, double value) {
  if (options == nullptr || name == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "options or name is NULL");
  return Guarded([&] { options->options.Set(name, value); });
}

cwloc_status cwloc_options_set_text(cwloc_options* options, const char* name, const char* value) {
  if (options == nullptr || name == nullptr || value == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "options, name or value is NULL");
  return Guarded([&] { options->options.Set(name, std::string(value)); });
}

cwloc_status cwloc_options_set_matcher(cwloc_options* options, const char* matcher) {
  if (options == nullptr || matcher == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "options or matcher is NULL");
  return cwloc_options_set_text(options, "matcher", matcher);
}

cwloc_status cwloc_options_set_position_prior(cwloc_options* options,
                                              const cwloc_position_prior* prior) {
  if (options == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "options is NULL");
  if (prior == nullptr) {
    options->options.position_prior.reset();
  } else {
    cwloc::api::PositionPrior position;
    position.latitude_deg = prior->latitude_deg;
    position.longitude_deg = prior->longitude_deg;
    if (!std::isnan(prior->height_m)) position.height_m = prior->height_m;
    position.radius_m = prior->radius_m;
    options->options.position_prior = position;
  }
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_options_set_gravity(cwloc_options* options, const double gravity_xyz[3]) {
  if (options == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "options is NULL");
  if (gravity_xyz == nullptr) {
    options->options.gravity.reset();
  } else {
    options->options.gravity =
        std::array<double, 3>{gravity_xyz[0], gravity_xyz[1], gravity_xyz[2]};
  }
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_localize_features(const cwloc_localizer* localizer, const float* keypoints,
                                     const uint8_t* descriptors, uint32_t num_features,
                                     const cwloc_camera* camera, const cwloc_options* options,
                                     cwloc_result** out) {
  return RunQuery(localizer, out, OptionsOrDefault(options), [&] {
    cwloc::api::Features features = FeaturesOf(keypoints, descriptors, num_features);
    return localizer->localizer.Localize(features, RequiredCamera(camera, "features need a camera"),
                                         OptionsOrDefault(options));
  });
}

cwloc_status cwloc_localize_photo(const cwloc_localizer* localizer, const char* path,
                                  const cwloc_camera* camera, const cwloc_options* options,
                                  cwloc_result** out) {
  return RunQuery(localizer, out, OptionsOrDefault(options), [&] {
    if (path == nullptr)
      throw cwloc::api::Error(cwloc::api::ErrorCode::kInvalidArgument, "path is NULL");
    return localizer->localizer.LocalizePhoto(path, ToCamera(camera), OptionsOrDefault(options));
  });
}

cwloc_status cwloc_localize_encoded_photo(const cwloc_localizer* localizer, const uint8_t* bytes,
                                          size_t size, const cwloc_camera* camera,
                                          const cwloc_options* options, cwloc_result** out) {
  return RunQuery(localizer, out, OptionsOrDefault(options), [&] {
    return localizer->localizer.LocalizeEncodedPhoto(bytes, size, ToCamera(camera),
                                                     OptionsOrDefault(options));
  });
}

cwloc_status cwloc_localize_grey_image(const cwloc_localizer* localizer, const uint8_t* pixels,
                                       uint32_t width, uint32_t height, size_t stride,
                                       const cwloc_camera* camera, const cwloc_options* options,
                                       cwloc_result** out) {
  return RunQuery(localizer, out, OptionsOrDefault(options), [&] {
    return localizer->localizer.LocalizeGreyImage(
        pixels, width, height, stride, RequiredCamera(camera, "a grey image needs a camera"),
        OptionsOrDefault(options));
  });
}

cwloc_status cwloc_tracker_create(const cwloc_localizer* localizer, const cwloc_options* options,
                                  cwloc_tracker** out) {
  if (out == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "out is NULL");
  *out = nullptr;
  if (localizer == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "localizer is NULL");
  return Guarded([&] {
    *out = new cwloc_tracker{cwloc::api::Tracker(localizer->localizer, OptionsOrDefault(options)),
                             OptionsOrDefault(options)};
  });
}

void cwloc_tracker_destroy(cwloc_tracker* tracker) { delete tracker; }

cwloc_status cwloc_tracker_reset(cwloc_tracker* tracker) {
  if (tracker == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "tracker is NULL");
  return Guarded([&] { tracker->tracker.Reset(); });
}

cwloc_status cwloc_track_features(cwloc_tracker* tracker, const float* keypoints,
                                  const uint8_t* descriptors, uint32_t num_features,
                                  const cwloc_camera* camera, const double* timestamp,
                                  const cwloc_motion* motion, cwloc_result** out) {
  return RunQuery(
      tracker, out, tracker == nullptr ? OptionsOrDefault(nullptr) : tracker->options, [&] {
        cwloc::api::Features features = FeaturesOf(keypoints, descriptors, num_features);
        return tracker->tracker.Track(features, RequiredCamera(camera, "features need a camera"),
                                      ToTimestamp(timestamp), ToMotion(motion));
      });
}

cwloc_status cwloc_track_photo(cwloc_tracker* tracker, const char* path, const cwloc_camera* camera,
                               const double* timestamp, const cwloc_motion* motion,
                               cwloc_result** out) {
  return RunQuery(
      tracker, out, tracker == nullptr ? OptionsOrDefault(nullptr) : tracker->options, [&] {
        if (path == nullptr)
          throw cwloc::api::Error(cwloc::api::ErrorCode::kInvalidArgument, "path is NULL");
        return tracker->tracker.TrackPhoto(path, ToCamera(camera), ToTimestamp(timestamp),
                                           ToMotion(motion));
      });
}

cwloc_status cwloc_track_grey_image(cwloc_tracker* tracker, const uint8_t* pixels, uint32_t width,
                                    uint32_t height, size_t stride, const cwloc_camera* camera,
                                    const double* timestamp, const cwloc_motion* motion,
                                    cwloc_result** out) {
  return RunQuery(
      tracker, out, tracker == nullptr ? OptionsOrDefault(nullptr) : tracker->options, [&] {
        return tracker->tracker.TrackGreyImage(
            pixels, width, height, stride, RequiredCamera(camera, "a grey image needs a camera"),
            ToTimestamp(timestamp), ToMotion(motion));
      });
}

void cwloc_result_destroy(cwloc_result* result) { delete result; }

int cwloc_result_success(const cwloc_result* result) {
  if (result == nullptr) return 0;
  return std::visit([](const auto& r) { return r.success ? 1 : 0; }, result->result);
}

cwloc_status cwloc_result_value(const cwloc_result* result, const char* path, double* value) {
  if (value == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "value is NULL");
  cwloc::PathValue found;
  if (const cwloc_status status = Resolve(result, path, &found); status != CWLOC_OK) return status;
  // An enum is both: its index here, its name as text.
  if (found.kind != cwloc::PathValue::Kind::kNumber && !found.enumerated)
    return WrongKind(path, found);
  *value = found.number;
  return CWLOC_OK;
}

cwloc_status cwloc_result_text(const cwloc_result* result, const char* path, const char** text) {
  if (text == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "text is NULL");
  cwloc::PathValue found;
  if (const cwloc_status status = Resolve(result, path, &found); status != CWLOC_OK) return status;
  if (found.kind != cwloc::PathValue::Kind::kText) return WrongKind(path, found);
  *text = found.text;
  return CWLOC_OK;
}

cwloc_status cwloc_result_values(const cwloc_result* result, const char* path, double* values,
                                 size_t capacity, size_t* count) {
  cwloc::PathValue found;
  if (const cwloc_status status = Resolve(result, path, &found); status != CWLOC_OK) return status;
  if (found.kind != cwloc::PathValue::Kind::kNumbers) return WrongKind(path, found);
  if (count != nullptr) *count = found.numbers.size();
  if (values == nullptr) return CWLOC_OK;
  if (capacity < found.numbers.size()) {
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT,
                "'" + std::string(path) + "' has " + std::to_string(found.numbers.size()) +
                    " values, more than the capacity " + std::to_string(capacity));
  }
  std::copy(found.numbers.begin(), found.numbers.end(), values);
  return CWLOC_OK;
}

cwloc_status cwloc_result_size(const cwloc_result* result, const char* path, size_t* size) {
  if (size == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "size is NULL");
  cwloc::PathValue found;
  if (const cwloc_status status = Resolve(result, path, &found); status != CWLOC_OK) return status;
  if (found.kind != cwloc::PathValue::Kind::kList && found.kind != cwloc::PathValue::Kind::kNumbers)
    return WrongKind(path, found);
  *size = found.size;
  return CWLOC_OK;
}

const char* cwloc_result_json(const cwloc_result* result) {
  if (result == nullptr) return "";
  if (result->json.empty()) {
    if (Guarded([&] {
          result->json =
              std::visit([&](const auto& r) { return cwloc::api::ToJson(r, result->options); },
                         result->result);
        }) != CWLOC_OK)
      return "";
  }
  return result->json.c_str();
}

}  // extern "C"

cwloc_status cwloc_localize_rig(const cwloc_localizer* localizer, const cwloc_rig_image* images,
                                size_t num_images, int unknown_scale, const char* name,
                                const cwloc_options* options, cwloc_result** out) {
  if (out == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "out is NULL");
  *out = nullptr;
  if (localizer == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "localizer is NULL");
  if (images == nullptr && num_images > 0)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "images is NULL");
  return Guarded([&] {
    std::vector<cwloc::api::RigImage> rig;
    for (size_t i = 0; i < num_images; ++i) {
      const cwloc_rig_image& image = images[i];
      cwloc::api::RigImage& in = rig.emplace_back();
      in.name = image.name != nullptr ? image.name : "image " + std::to_string(i + 1);
      if (image.photo_path != nullptr) {
        in.photo_path = image.photo_path;
      } else {
        in.features = FeaturesOf(image.keypoints, image.descriptors, image.num_features);
      }
      in.camera = ToCamera(image.camera);
      std::copy_n(image.cam_from_rig_rotation_wxyz, 4, in.cam_from_rig_rotation.begin());
      std::copy_n(image.cam_from_rig_translation, 3, in.cam_from_rig_translation.begin());
    }
    *out = new cwloc_result{
        localizer->localizer.LocalizeRig(rig, unknown_scale != 0, OptionsOrDefault(options),
                                         name != nullptr ? name : "frame"),
        OptionsOrDefault(options),
        {}};
  });
}
