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

#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"

struct cwloc_localizer {
  cwloc::api::Localizer localizer;
  cwloc::api::IndexInfo info;  // owns the strings cwloc_localizer_info returns
};

struct cwloc_options {
  cwloc::api::Options options;
};

struct cwloc_tracker {
  cwloc::api::Tracker tracker;
  bool georeferenced = false;  // its localizer's index
};

struct cwloc_result {
  cwloc::api::Result result;
  bool georeferenced = false;  // the index's: why a result has no geo pose
};

struct cwloc_rig_result {
  cwloc::api::RigResult result;
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
// runs the query.
template <typename Handle>
cwloc_status RunQuery(Handle* handle, cwloc_result** out,
                      const std::function<cwloc::api::Result()>& query) {
  constexpr bool kTracker = std::is_same_v<std::remove_const_t<Handle>, cwloc_tracker>;
  if (out == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "out is NULL");
  *out = nullptr;
  if (handle == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, kTracker ? "tracker is NULL" : "localizer is NULL");
  bool georeferenced;
  if constexpr (kTracker) {
    georeferenced = handle->georeferenced;
  } else {
    georeferenced = handle->info.georeferenced;
  }
  return Guarded([&] { *out = new cwloc_result{query(), georeferenced}; });
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

// A result accessor's value that does not exist: NOT_AVAILABLE and why.
cwloc_status NotAvailable(const std::string& what, const std::string& why) {
  return Fail(CWLOC_ERROR_NOT_AVAILABLE, what + ": " + why);
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
    options->options.position_prior = cwloc::api::PositionPrior{
        prior->latitude_deg, prior->longitude_deg,
        std::isnan(prior->height_m) ? std::nullopt : std::optional<double>(prior->height_m),
        prior->radius_m};
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
  return RunQuery(localizer, out, [&] {
    cwloc::api::Features features = FeaturesOf(keypoints, descriptors, num_features);
    return localizer->localizer.Localize(features, RequiredCamera(camera, "features need a camera"),
                                         OptionsOrDefault(options));
  });
}

cwloc_status cwloc_localize_photo(const cwloc_localizer* localizer, const char* path,
                                  const cwloc_camera* camera, const cwloc_options* options,
                                  cwloc_result** out) {
  return RunQuery(localizer, out, [&] {
    if (path == nullptr)
      throw cwloc::api::Error(cwloc::api::ErrorCode::kInvalidArgument, "path is NULL");
    return localizer->localizer.LocalizePhoto(path, ToCamera(camera), OptionsOrDefault(options));
  });
}

cwloc_status cwloc_localize_encoded_photo(const cwloc_localizer* localizer, const uint8_t* bytes,
                                          size_t size, const cwloc_camera* camera,
                                          const cwloc_options* options, cwloc_result** out) {
  return RunQuery(localizer, out, [&] {
    return localizer->localizer.LocalizeEncodedPhoto(bytes, size, ToCamera(camera),
                                                     OptionsOrDefault(options));
  });
}

cwloc_status cwloc_localize_grey_image(const cwloc_localizer* localizer, const uint8_t* pixels,
                                       uint32_t width, uint32_t height, size_t stride,
                                       const cwloc_camera* camera, const cwloc_options* options,
                                       cwloc_result** out) {
  return RunQuery(localizer, out, [&] {
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
                             localizer->info.georeferenced};
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
  return RunQuery(tracker, out, [&] {
    cwloc::api::Features features = FeaturesOf(keypoints, descriptors, num_features);
    return tracker->tracker.Track(features, RequiredCamera(camera, "features need a camera"),
                                  ToTimestamp(timestamp), ToMotion(motion));
  });
}

cwloc_status cwloc_track_photo(cwloc_tracker* tracker, const char* path, const cwloc_camera* camera,
                               const double* timestamp, const cwloc_motion* motion,
                               cwloc_result** out) {
  return RunQuery(tracker, out, [&] {
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
  return RunQuery(tracker, out, [&] {
    return tracker->tracker.TrackGreyImage(pixels, width, height, stride,
                                           RequiredCamera(camera, "a grey image needs a camera"),
                                           ToTimestamp(timestamp), ToMotion(motion));
  });
}

void cwloc_result_destroy(cwloc_result* result) { delete result; }

int cwloc_result_success(const cwloc_result* result) {
  return result != nullptr && result->result.success ? 1 : 0;
}

const char* cwloc_result_failure_reason(const cwloc_result* result) {
  return result != nullptr ? result->result.failure_reason.c_str() : "result is NULL";
}

void cwloc_result_pose(const cwloc_result* result, double rotation_wxyz[4], double translation[3],
                       double center[3]) {
  if (result == nullptr) return;
  const cwloc::api::Result& r = result->result;
  if (rotation_wxyz != nullptr) std::copy(r.rotation.begin(), r.rotation.end(), rotation_wxyz);
  if (translation != nullptr) std::copy(r.translation.begin(), r.translation.end(), translation);
  if (center != nullptr) std::copy(r.center.begin(), r.center.end(), center);
}

void cwloc_result_camera(const cwloc_result* result, cwloc_camera* camera) {
  if (result == nullptr || camera == nullptr) return;
  const cwloc::api::Camera& c = result->result.camera;
  camera->model = c.model.c_str();
  camera->width = c.width;
  camera->height = c.height;
  camera->params = c.params.data();
  camera->num_params = c.params.size();
  camera->calibration = static_cast<cwloc_calibration>(c.calibration);
}

cwloc_status cwloc_result_value(const cwloc_result* result, const char* name, double* value) {
  if (result == nullptr || name == nullptr || value == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result, name or value is NULL");
  const std::string_view wanted = name;
#define CWLOC_RESULT_FIELD(field, type, group, key, help) \
  if (wanted == #field) {                                 \
    *value = static_cast<double>(result->result.field);   \
    return CWLOC_OK;                                      \
  }
#include "cwloc/result_fields.inc"
#undef CWLOC_RESULT_FIELD
  return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "unknown result value '" + std::string(name) + "'");
}

uint32_t cwloc_result_num_features(const cwloc_result* result) {
  return result != nullptr ? result->result.num_features : 0;
}

uint32_t cwloc_result_num_correspondences(const cwloc_result* result) {
  return result != nullptr ? result->result.correspondences : 0;
}

uint32_t cwloc_result_num_inliers(const cwloc_result* result) {
  return result != nullptr ? static_cast<uint32_t>(result->result.inliers.size()) : 0;
}

cwloc_status cwloc_result_inlier(const cwloc_result* result, uint32_t i, uint32_t* feature,
                                 float keypoint[2], uint32_t* point, double xyz[3]) {
  if (result == nullptr || i >= result->result.inliers.size())
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "inlier " + std::to_string(i) + ": out of range");
  const cwloc::api::Inlier& inlier = result->result.inliers[i];
  if (feature != nullptr) *feature = inlier.feature;
  if (keypoint != nullptr) std::copy(inlier.keypoint.begin(), inlier.keypoint.end(), keypoint);
  if (point != nullptr) *point = inlier.point;
  if (xyz != nullptr) std::copy(inlier.xyz.begin(), inlier.xyz.end(), xyz);
  return CWLOC_OK;
}

uint32_t cwloc_result_num_ranked_images(const cwloc_result* result) {
  return result != nullptr ? static_cast<uint32_t>(result->result.ranked_images.size()) : 0;
}

cwloc_status cwloc_result_ranked_image(const cwloc_result* result, uint32_t i, uint32_t* image_id,
                                       const char** name, uint32_t* votes) {
  if (result == nullptr || i >= result->result.ranked_images.size()) {
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT,
                "ranked image " + std::to_string(i) + ": out of range");
  }
  const cwloc::api::RankedImage& image = result->result.ranked_images[i];
  if (image_id != nullptr) *image_id = image.image_id;
  if (name != nullptr) *name = image.name.c_str();
  if (votes != nullptr) *votes = image.votes;
  return CWLOC_OK;
}

void cwloc_result_times(const cwloc_result* result, cwloc_stage_times* times) {
  if (result == nullptr || times == nullptr) return;
  const cwloc::api::StageTimes& t = result->result.times;
#define CWLOC_STAGE_TIME(name, help) times->name = t.name;
#include "cwloc/stage_times.inc"
#undef CWLOC_STAGE_TIME
}

cwloc_status cwloc_result_geo_pose(const cwloc_result* result, cwloc_geo_pose* pose) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  if (pose == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "pose is NULL");
  if (!result->georeferenced) return NotAvailable("geo pose", "the index is not georeferenced");
  const auto& geo = result->result.geo;
  if (!geo) return NotAvailable("geo pose", "the query was not localized");
  *pose = {
      geo->latitude_deg, geo->longitude_deg, geo->height_m, {geo->enu[0], geo->enu[1], geo->enu[2]},
      geo->heading_deg,  geo->pitch_deg,     geo->roll_deg};
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_result_position_prior(const cwloc_result* result, cwloc_position_prior* prior,
                                         uint32_t* clusters_in_radius) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  if (prior == nullptr || clusters_in_radius == nullptr)
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "prior or clusters_in_radius is NULL");
  const auto& used = result->result.position_prior;
  if (!used) return NotAvailable("position prior", "the query had none");
  *prior = {used->latitude_deg, used->longitude_deg,
            used->height_m.value_or(std::numeric_limits<double>::quiet_NaN()), used->radius_m};
  *clusters_in_radius = result->result.clusters_in_radius;
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_result_gravity_error(const cwloc_result* result, double* degrees) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  if (degrees == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "degrees is NULL");
  if (!result->result.gravity)
    return NotAvailable("gravity error", "the query had no gravity prior");
  if (!result->result.gravity_error_deg)
    return NotAvailable("gravity error", "the query was not localized");
  *degrees = *result->result.gravity_error_deg;
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_result_tracking(const cwloc_result* result, cwloc_tracking* tracking) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  if (tracking == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "tracking is NULL");
  const auto& t = result->result.tracking;
  if (!t) return NotAvailable("tracking", "the query was not a tracker's frame");
  *tracking = {static_cast<cwloc_tracking_mode>(t->mode), t->predicted_from.c_str(),
               t->prediction_error.has_value() ? 1 : 0,   t->prediction_error.value_or(0.0),
               t->prediction_error_deg.value_or(0.0),     t->seconds};
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_result_covariance(const cwloc_result* result, double pose[36],
                                     double* position_radius95) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  const auto& covariance = result->result.covariance;
  if (!covariance) {
    return NotAvailable("covariance", result->result.success
                                          ? "the pose's refinement problem is singular"
                                          : "the query was not localized");
  }
  if (pose != nullptr) std::copy(covariance->pose.begin(), covariance->pose.end(), pose);
  if (position_radius95 != nullptr) *position_radius95 = covariance->position_radius95;
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_result_covariance_calibration(const cwloc_result* result, double* rotation_scale,
                                                 double* position_scale) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  const auto& covariance = result->result.covariance;
  if (!covariance) {
    return NotAvailable("covariance calibration", result->result.success
                                                      ? "the pose's refinement problem is singular"
                                                      : "the query was not localized");
  }
  if (!covariance->calibration) {
    return NotAvailable("covariance calibration",
                        "the index has none for the query's calibration mode");
  }
  if (rotation_scale != nullptr) *rotation_scale = covariance->calibration->rotation;
  if (position_scale != nullptr) *position_scale = covariance->calibration->position;
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_result_enu_covariance(const cwloc_result* result, double enu_position[9],
                                         double* position_radius95_m) {
  if (result == nullptr) return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "result is NULL");
  if (!result->georeferenced)
    return NotAvailable("ENU covariance", "the index is not georeferenced");
  const auto& covariance = result->result.covariance;
  if (!covariance || !covariance->enu_position) {
    return NotAvailable("ENU covariance", result->result.success
                                              ? "the pose's refinement problem is singular"
                                              : "the query was not localized");
  }
  if (enu_position != nullptr) {
    std::copy(covariance->enu_position->begin(), covariance->enu_position->end(), enu_position);
  }
  if (position_radius95_m != nullptr) *position_radius95_m = *covariance->position_radius95_m;
  last_error.clear();
  return CWLOC_OK;
}

const char* cwloc_result_json(const cwloc_result* result) {
  return result == nullptr ? "" : result->result.json.c_str();
}

}  // extern "C"

cwloc_status cwloc_localize_rig(const cwloc_localizer* localizer, const cwloc_rig_image* images,
                                size_t num_images, int unknown_scale, const char* name,
                                const cwloc_options* options, cwloc_rig_result** out) {
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
    *out = new cwloc_rig_result{localizer->localizer.LocalizeRig(
        rig, unknown_scale != 0, OptionsOrDefault(options), name != nullptr ? name : "frame")};
  });
}

void cwloc_rig_result_destroy(cwloc_rig_result* result) { delete result; }

int cwloc_rig_result_success(const cwloc_rig_result* result) { return result->result.success; }

const char* cwloc_rig_result_failure_reason(const cwloc_rig_result* result) {
  return result->result.failure_reason.c_str();
}

void cwloc_rig_result_pose(const cwloc_rig_result* result, double rotation_wxyz[4],
                           double translation[3], double center[3], double* scale) {
  const cwloc::api::RigResult& r = result->result;
  if (rotation_wxyz != nullptr) std::copy_n(r.rotation.begin(), 4, rotation_wxyz);
  if (translation != nullptr) std::copy_n(r.translation.begin(), 3, translation);
  if (center != nullptr) std::copy_n(r.center.begin(), 3, center);
  if (scale != nullptr) *scale = r.scale;
}

uint32_t cwloc_rig_result_num_inliers(const cwloc_rig_result* result) {
  return result->result.num_inliers;
}

uint32_t cwloc_rig_result_num_images(const cwloc_rig_result* result) {
  return static_cast<uint32_t>(result->result.images.size());
}

cwloc_status cwloc_rig_result_image_pose(const cwloc_rig_result* result, uint32_t i,
                                         double rotation_wxyz[4], double translation[3],
                                         uint32_t* num_inliers) {
  const cwloc::api::RigResult& r = result->result;
  if (i >= r.images.size()) {
    return Fail(CWLOC_ERROR_INVALID_ARGUMENT, "image " + std::to_string(i) + ": out of range");
  }
  const cwloc::api::RigImageResult& image = r.images[i];
  if (!image.posed) return Fail(CWLOC_ERROR_NOT_AVAILABLE, "the rig was not localized");
  if (rotation_wxyz != nullptr) std::copy_n(image.rotation.begin(), 4, rotation_wxyz);
  if (translation != nullptr) std::copy_n(image.translation.begin(), 3, translation);
  if (num_inliers != nullptr) *num_inliers = image.num_inliers;
  last_error.clear();
  return CWLOC_OK;
}

cwloc_status cwloc_rig_result_covariance(const cwloc_rig_result* result, double pose[36],
                                         double* position_radius95) {
  const auto& covariance = result->result.covariance;
  if (!covariance) return Fail(CWLOC_ERROR_NOT_AVAILABLE, "the rig was not localized");
  if (pose != nullptr) std::copy_n(covariance->pose.begin(), 36, pose);
  if (position_radius95 != nullptr) *position_radius95 = covariance->position_radius95;
  last_error.clear();
  return CWLOC_OK;
}

const char* cwloc_rig_result_json(const cwloc_rig_result* result) {
  return result->result.json.c_str();
}
