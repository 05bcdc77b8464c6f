// The C++ API over the localizer core: converts its public types to the internal ones and
// every internal exception to api::Error.
#include <algorithm>
#include <new>
#include <span>
#include <variant>
#include <vector>

#include "app/camera_spec.h"
#include "app/feature_file.h"
#include "app/option_table.h"
#include "app/photo_query.h"
#include "app/query_assembly.h"
#include "app/result_json.h"
#include "base/error.h"
#include "cwloc/cwloc.hpp"
#include "cwloc/version.h"
#include "delta/apply_delta.h"
#include "format/index.h"
#include "localizer/localizer.h"
#include "localizer/rig_localizer.h"
#include "localizer/tracker.h"

namespace cwloc::api {
namespace {

Error InvalidArgument(const std::string& message) {
  return Error(ErrorCode::kInvalidArgument, message);
}

// Runs fn; an InputError it throws is the caller's argument, not a bad file.
template <typename Fn>
void ValidateOrThrowInvalidArgument(Fn fn) {
  try {
    fn();
  } catch (const InputError& e) {
    throw InvalidArgument(e.what());
  }
}

// Runs fn and returns its value; every exception leaves as api::Error.
template <typename Fn>
auto Translated(Fn fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const Error&) {
    throw;
  } catch (const InputError& e) {
    throw Error(ErrorCode::kBadInput, e.what());
  } catch (const std::bad_alloc&) {
    throw Error(ErrorCode::kOutOfMemory, "out of memory");
  } catch (const std::exception& e) {
    throw Error(ErrorCode::kInternal, std::string("internal error: ") + e.what());
  }
}

// The API's fields in the option table's order (OptionTable()).
std::vector<OptionValue> FieldValues(const Options& o) {
  return {
#define CWLOC_OPTION(field, type, ...) OptionValue(std::in_place_type<type>, o.field),
#include "app/option_table.inc"
#undef CWLOC_OPTION
  };
}

// The options through the table, as cwloc-localize takes them: the same checks and messages,
// each value checked once as it lands through its spec.
QueryOptions ToQueryOptions(const Options& o) {
  const std::span<const OptionSpec> table = OptionTable();
  const std::vector<OptionValue> fields = FieldValues(o);
  QueryOptions options;
  ValidateOrThrowInvalidArgument([&] {
    for (size_t i = 0; i < table.size(); ++i) {
      CheckOption(table[i], fields[i]);
      table[i].set(&options, fields[i]);
    }
    CheckOptionRules(options);
  });
  return options;
}

// Sets the field of the table's option at `index` to a checked value.
void AssignField(size_t index, const OptionValue& value, Options* o) {
  size_t i = 0;
#define CWLOC_OPTION(field, type, ...) \
  if (index == i++) {                  \
    o->field = std::get<type>(value);  \
    return;                            \
  }
#include "app/option_table.inc"
#undef CWLOC_OPTION
}

QueryCamera ToQueryCamera(const Camera& camera) {
  QueryCamera query_camera;
  ValidateOrThrowInvalidArgument([&] {
    if (camera.calibration == Calibration::kUnknown) {
      query_camera = ImageSizeCamera(camera.width, camera.height, "camera");
      return;
    }
    query_camera =
        MakeKnownCamera(camera.model, camera.width, camera.height, camera.params, "camera");
    if (camera.calibration == Calibration::kFocalPrior) {
      query_camera = FocalPriorCamera(MeanFocalLength(query_camera.model_id, query_camera.params),
                                      camera.width, camera.height, IntrinsicsSource::kCameraOption);
    } else if (camera.calibration != Calibration::kKnown) {
      throw InputError("camera: unknown calibration " +
                       std::to_string(static_cast<int>(camera.calibration)));
    }
  });
  query_camera.source = IntrinsicsSource::kCameraOption;
  return query_camera;
}

PriorInputs ToPriorInputs(const Options& options) {
  PriorInputs priors;
  if (const auto& prior = options.position_prior) {
    priors.position = *prior;
    priors.position->source = PriorSource::kOption;
  }
  priors.gravity = options.gravity;
  return priors;
}

// One call's options, made internal once, and the assembly of its query (camera and priors)
// by cwloc-localize's rules (QueryAssembler).
struct CallOptions {
  CallOptions(const Options& o, const std::optional<Camera>& camera)
      : options(ToQueryOptions(o)), assembler(options, Cameras(camera), ToPriorInputs(o)) {}

  static CameraInputs Cameras(const std::optional<Camera>& camera) {
    CameraInputs cameras;
    if (camera) cameras.camera = ToQueryCamera(*camera);
    return cameras;
  }

  // The given camera and the options' priors; a camera that does not fit the image is the
  // caller's argument.
  void Complete(const QuerySource& source, Query* query) const {
    ValidateOrThrowInvalidArgument([&] { assembler.Complete(source, query); });
  }

  const QueryOptions options;
  const QueryAssembler assembler;  // refers to options
};

}  // namespace

Error::Error(ErrorCode code, const std::string& message)
    : std::runtime_error(message), code_(code) {}

Options::Options() {
  const QueryOptions defaults;
  const std::span<const OptionSpec> table = OptionTable();
  for (size_t i = 0; i < table.size(); ++i) AssignField(i, table[i].get(defaults), this);
}

void Options::Set(const std::string& name, const std::string& value) {
  Translated([&] {
    ValidateOrThrowInvalidArgument([&] {
      const OptionSpec& spec = FindOption(name);
      AssignField(&spec - OptionTable().data(), ParseOption(spec, value), this);
    });
  });
}

void Options::Set(const std::string& name, double value) {
  Translated([&] {
    ValidateOrThrowInvalidArgument([&] {
      const OptionSpec& spec = FindOption(name);
      AssignField(&spec - OptionTable().data(), OptionFromNumber(spec, value), this);
    });
  });
}

// A tracker's frame: the tracker, and the motion the caller gives.
struct TrackedFrame {
  cwloc::Tracker* tracker = nullptr;
  std::optional<double> seconds;
  std::optional<FrameMotion> motion;
};

std::optional<double> ToSeconds(std::optional<double> timestamp) {
  if (timestamp && !std::isfinite(*timestamp))
    throw InvalidArgument("timestamp: expected a finite number of seconds");
  return timestamp;
}

std::optional<FrameMotion> ToFrameMotion(const std::optional<Motion>& motion) {
  if (!motion) return std::nullopt;
  std::variant<FrameMotion, std::string> frame_motion = MetricMotion(
      motion->rotation, motion->translation, motion->sigma_rotation_deg, motion->sigma_position);
  if (const auto* problem = std::get_if<std::string>(&frame_motion))
    throw InvalidArgument("motion: " + *problem);
  return std::get<FrameMotion>(frame_motion);
}

struct Localizer::Impl {
  explicit Impl(Index opened) : index(std::move(opened)), localizer(index) {}

  Result Run(Query query, const QuerySource& source, const CallOptions& call,
             const TrackedFrame* frame) const {
    call.Complete(source, &query);
    return Localize(query, call, frame);
  }

  // A complete query: localized alone, or as the next frame of a tracker.
  Result Localize(const Query& query, const CallOptions& call, const TrackedFrame* frame) const {
    ValidateOrThrowInvalidArgument([&] { localizer.ValidatePriors(query); });
    return frame != nullptr ? frame->tracker->Track(query, frame->seconds, frame->motion)
                            : localizer.Localize(query, call.options.localizer);
  }

  Result FromFeatures(const Features& features, const Camera& camera, const Options& options,
                      const TrackedFrame* frame) const {
    return Translated([&] {
      const CallOptions call(options, camera);
      Query query;
      query.name = "query";
      query.source = "features";
      query.keypoints = features.keypoints;
      query.descriptors = features.descriptors;
      return Run(std::move(query), {"query", QuerySource::Kind::kFeatures}, call, frame);
    });
  }

  Result FromPhoto(const std::string& photo, const std::optional<Camera>& camera,
                   const Options& options, const TrackedFrame* frame) const {
    return Translated([&] {
      const CallOptions call(options, camera);
      const QuerySource source{photo, QuerySource::Kind::kPhoto, photo};
      return Run(call.assembler.Read(source), source, call, frame);
    });
  }

  Result FromGreyImage(const uint8_t* pixels, uint32_t width, uint32_t height, size_t stride,
                       const Camera& camera, const Options& options,
                       const TrackedFrame* frame) const {
    return Translated([&] {
      if (pixels == nullptr) throw InvalidArgument("grey image: null pointer");
      if (width == 0 || height == 0 || stride < width) {
        throw InvalidArgument("grey image: " + std::to_string(width) + " x " +
                              std::to_string(height) + " with stride " + std::to_string(stride) +
                              ": expected a positive size and stride >= width");
      }
      const CallOptions call(options, camera);
      const PhotoOptions& photo_options = call.options.photo;
      if (uint64_t{width} * height > photo_options.max_image_pixels) {
        throw InvalidArgument("grey image: " + std::to_string(uint64_t{width} * height) +
                              " pixels, more than --max-image-pixels " +
                              std::to_string(photo_options.max_image_pixels));
      }
      Query query;
      query.name = "image";
      query.source = "grey image";
      query.camera.width = width;  // the image's own size, which the camera must have
      query.camera.height = height;
      const QuerySource source{query.name, QuerySource::Kind::kImage};
      call.Complete(source, &query);  // before the extraction it would waste
      GreyImage image;
      image.width = width;
      image.height = height;
      image.pixels.resize(size_t{width} * height);
      for (uint32_t y = 0; y < height; ++y) {
        std::copy_n(pixels + y * stride, width, image.pixels.data() + size_t{y} * width);
      }
      ExtractPhotoFeatures(std::move(image), photo_options, &query);
      return Localize(query, call, frame);
    });
  }

  std::string path;
  Index index;
  cwloc::Localizer localizer;  // refers to index: Impl is never moved, only its pointer
};

Localizer::Localizer(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
Localizer::Localizer(Localizer&&) noexcept = default;
Localizer& Localizer::operator=(Localizer&&) noexcept = default;
Localizer::~Localizer() = default;

Localizer Localizer::Open(const std::string& index_path, bool verify) {
  return Translated([&] {
    auto impl = std::make_unique<Impl>(Index::Open(index_path));
    impl->path = index_path;
    if (verify) {
      impl->index.file().VerifyChecksums();
      impl->index.Validate();
    }
    return Localizer(std::move(impl));
  });
}

IndexInfo Localizer::Info() const {
  const Index& index = impl_->index;
  IndexInfo info;
  info.path = impl_->path;
  info.format_version = std::to_string(index.file().header().format_major) + "." +
                        std::to_string(index.file().header().format_minor);
  info.num_images = static_cast<uint32_t>(index.images().size());
  info.num_points = static_cast<uint32_t>(index.num_points());
  info.num_views = static_cast<uint32_t>(index.num_views());
  if (const IndexGeoreference* georeference = index.georeference()) {
    info.georeferenced = true;
    info.origin_latitude_deg = georeference->origin_latitude_deg;
    info.origin_longitude_deg = georeference->origin_longitude_deg;
    info.origin_height_m = georeference->origin_height_m;
  }
  return info;
}

Result Localizer::Localize(const Features& features, const Camera& camera,
                           const Options& options) const {
  return impl_->FromFeatures(features, camera, options, nullptr);
}

Result Localizer::LocalizePhoto(const std::string& path, const std::optional<Camera>& camera,
                                const Options& options) const {
  return impl_->FromPhoto(path, camera, options, nullptr);
}

Result Localizer::LocalizeEncodedPhoto(const uint8_t* bytes, size_t size,
                                       const std::optional<Camera>& camera,
                                       const Options& options) const {
  return Translated([&] {
    if (bytes == nullptr && size > 0) throw InvalidArgument("photo bytes: null pointer");
    const CallOptions call(options, camera);
    Query query = PhotoQueryFromBytes(std::span<const uint8_t>(bytes, size), "photo bytes", "photo",
                                      call.options.photo);
    return impl_->Run(std::move(query), {"photo", QuerySource::Kind::kImage}, call, nullptr);
  });
}

Result Localizer::LocalizeGreyImage(const uint8_t* pixels, uint32_t width, uint32_t height,
                                    size_t stride, const Camera& camera,
                                    const Options& options) const {
  return impl_->FromGreyImage(pixels, width, height, stride, camera, options, nullptr);
}

RigResult Localizer::LocalizeRig(const std::vector<RigImage>& images, bool unknown_scale,
                                 const Options& options, const std::string& name) const {
  return Translated([&] {
    RigQuery query;
    query.name = name;
    query.unknown_scale = unknown_scale;
    const QueryOptions query_options = ToQueryOptions(options);
    for (const RigImage& image : images) {
      const std::string what = "rig image '" + image.name + "'";
      std::variant<CameraPose, std::string> pose =
          PoseFromParts(image.cam_from_rig_rotation, image.cam_from_rig_translation);
      if (const auto* problem = std::get_if<std::string>(&pose))
        throw InvalidArgument(what + ": cam_from_rig: " + *problem);
      const CallOptions call(options, image.camera);
      Query query_image;
      QuerySource source;
      if (image.photo_path.empty()) {
        if (!image.camera) throw InvalidArgument(what + ": features need a camera");
        query_image.keypoints = image.features.keypoints;
        query_image.descriptors = image.features.descriptors;
        source = {image.name, QuerySource::Kind::kFeatures};
      } else {
        source = {image.name, QuerySource::Kind::kPhoto, image.photo_path};
        query_image = call.assembler.Read(source);
      }
      query_image.name = image.name;
      if (query_image.source.empty()) query_image.source = what;
      call.Complete(source, &query_image);
      query.images.push_back({std::move(query_image), std::get<CameraPose>(pose)});
    }
    if (images.empty()) throw InvalidArgument("rig frame '" + name + "': no images");
    ValidateOrThrowInvalidArgument([&] {
      for (const cwloc::RigImage& image : query.images)
        impl_->localizer.ValidatePriors(image.query);
    });
    return cwloc::LocalizeRig(impl_->localizer, query, query_options.localizer);
  });
}

struct Tracker::Impl {
  Impl(const Localizer::Impl& localizer_impl, const Options& tracker_options)
      : localizer(localizer_impl),
        options(tracker_options),
        query_options(Translated([&] { return ToQueryOptions(tracker_options); })),
        tracker(localizer_impl.localizer, query_options.localizer, query_options.tracker) {}

  const Localizer::Impl& localizer;
  const Options options;
  const QueryOptions query_options;
  cwloc::Tracker tracker;
};

Tracker::Tracker(const Localizer& localizer, const Options& options)
    : impl_(std::make_unique<Impl>(*localizer.impl_, options)) {}
Tracker::Tracker(Tracker&&) noexcept = default;
Tracker& Tracker::operator=(Tracker&&) noexcept = default;
Tracker::~Tracker() = default;

Result Tracker::Track(const Features& features, const Camera& camera,
                      std::optional<double> timestamp, const std::optional<Motion>& motion) {
  return Translated([&] {
    const TrackedFrame frame{&impl_->tracker, ToSeconds(timestamp), ToFrameMotion(motion)};
    return impl_->localizer.FromFeatures(features, camera, impl_->options, &frame);
  });
}

Result Tracker::TrackPhoto(const std::string& path, const std::optional<Camera>& camera,
                           std::optional<double> timestamp, const std::optional<Motion>& motion) {
  return Translated([&] {
    const TrackedFrame frame{&impl_->tracker, ToSeconds(timestamp), ToFrameMotion(motion)};
    return impl_->localizer.FromPhoto(path, camera, impl_->options, &frame);
  });
}

Result Tracker::TrackGreyImage(const uint8_t* pixels, uint32_t width, uint32_t height,
                               size_t stride, const Camera& camera, std::optional<double> timestamp,
                               const std::optional<Motion>& motion) {
  return Translated([&] {
    const TrackedFrame frame{&impl_->tracker, ToSeconds(timestamp), ToFrameMotion(motion)};
    return impl_->localizer.FromGreyImage(pixels, width, height, stride, camera, impl_->options,
                                          &frame);
  });
}

void Tracker::Reset() { impl_->tracker.Reset(); }

Features ReadFeatureFile(const std::string& path) {
  return Translated([&] {
    Query query;
    cwloc::ReadFeatureFile(path, &query);
    return Features{std::move(query.keypoints), std::move(query.descriptors)};
  });
}

void ApplyIndexDelta(const std::string& index_path, const std::string& delta_path,
                     const std::string& output_path, int threads) {
  Translated([&] { cwloc::ApplyDelta(index_path, delta_path, output_path, threads); });
}

std::string ToJson(const Result& result, const Options& options) {
  return Translated([&] { return ResultToJson(result, ToQueryOptions(options)).dump(); });
}

std::string ToJson(const RigResult& result, const Options& options) {
  return Translated([&] { return RigResultToJson(result, ToQueryOptions(options)).dump(); });
}

const char* Version() { return kToolVersion; }

}  // namespace cwloc::api
