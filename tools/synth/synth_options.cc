#include "tools/synth/synth_options.h"

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <vector>

#include "base/error.h"
#include "camera/camera_models.h"

namespace cwloc::synth {
namespace {

constexpr double kMinBlockSide = 16;  // metres; below this a block is not a city block

template <typename T>
std::string Str(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

template <typename T>
T Pick(const std::optional<T>& knob, const std::optional<T>& preset, T fallback) {
  return knob ? *knob : preset ? *preset : fallback;
}

// The knobs a preset fills in when the command line leaves them unset.
struct Preset {
  std::optional<int64_t> views, blocks, queries, features_per_image, motifs;
  std::optional<double> camera_spacing;
  bool small_blocks = false;
};

Preset FindPreset(const std::string& name) {
  if (name.empty()) return {};
  if (name == "demo") {
    // A 2x2 city of small blocks: ~26k views, written in a second or two.
    Preset p;
    p.blocks = 4;
    p.queries = 20;
    p.features_per_image = 400;
    p.motifs = 64;
    p.camera_spacing = 5;
    p.small_blocks = true;
    return p;
  }
  throw InputError("--preset must be 'demo' (got '" + name + "')");
}

void Require(bool ok, const std::string& message) {
  if (!ok) throw InputError(message);
}

// "LAT LON HEIGHT": three numbers separated by blanks.
Geodetic ParseGeo(const std::string& text) {
  const std::string usage =
      "--geo must be \"LAT LON HEIGHT\" (WGS84 degrees and metres above the ellipsoid; got '" +
      text + "')";
  std::istringstream in(text);
  std::vector<double> values;
  for (std::string token; in >> token;) {
    char* end = nullptr;
    const double value = std::strtod(token.c_str(), &end);
    Require(end == token.c_str() + token.size() && std::isfinite(value), usage);
    values.push_back(value);
  }
  Require(values.size() == 3, usage);
  Geodetic g{values[0], values[1], values[2]};
  Require(g.latitude_deg >= -90 && g.latitude_deg <= 90,
          "--geo latitude must be in [-90, 90] degrees (got " + Str(g.latitude_deg) + ")");
  Require(g.longitude_deg >= -180 && g.longitude_deg <= 180,
          "--geo longitude must be in [-180, 180] degrees (got " + Str(g.longitude_deg) + ")");
  Require(g.height_m >= -1000 && g.height_m <= 10000,
          "--geo height must be in [-1000, 10000] metres (got " + Str(g.height_m) + ")");
  return g;
}

}  // namespace

GeoOptions MakeGeoOptions(const SynthKnobs& knobs) {
  GeoOptions o;
  if (!knobs.geo) {
    const std::pair<bool, const char*> geo_only[] = {
        {knobs.gps_noise.has_value(), "--gps-noise"},
        {knobs.gps_outliers.has_value(), "--gps-outliers"},
        {knobs.prior_position_error.has_value(), "--prior-position-error"},
        {knobs.prior_radius.has_value(), "--prior-radius"},
        {knobs.prior_gravity_error.has_value(), "--prior-gravity-error"}};
    for (const auto& [given, name] : geo_only) {
      Require(!given, std::string(name) + " needs --geo (it changes only the files --geo writes)");
    }
    return o;
  }
  o.origin = ParseGeo(*knobs.geo);
  o.gps_noise = Pick(knobs.gps_noise, {}, kDefaultGpsNoise);
  Require(o.gps_noise >= 0 && o.gps_noise <= 1000,
          "--gps-noise must be in [0, 1000] metres (got " + Str(o.gps_noise) + ")");
  o.gps_outliers = Pick(knobs.gps_outliers, {}, kDefaultGpsOutliers);
  Require(o.gps_outliers >= 0 && o.gps_outliers <= 0.5,
          "--gps-outliers must be in [0, 0.5] (got " + Str(o.gps_outliers) + ")");
  o.prior_position_error = Pick(knobs.prior_position_error, {}, kDefaultPriorPositionError);
  Require(o.prior_position_error >= 0 && o.prior_position_error <= 10000,
          "--prior-position-error must be in [0, 10000] metres (got " +
              Str(o.prior_position_error) + ")");
  o.prior_radius = Pick(knobs.prior_radius, {}, kDefaultPriorRadius);
  Require(o.prior_radius > 0 && o.prior_radius <= 100000,
          "--prior-radius must be in (0, 100000] metres (got " + Str(o.prior_radius) + ")");
  o.prior_gravity_error_deg = Pick(knobs.prior_gravity_error, {}, kDefaultPriorGravityErrorDeg);
  Require(o.prior_gravity_error_deg >= 0 && o.prior_gravity_error_deg <= 180,
          "--prior-gravity-error must be in [0, 180] degrees (got " +
              Str(o.prior_gravity_error_deg) + ")");
  return o;
}

int64_t MinimumViews(const SceneOptions& options) {
  return int64_t(std::ceil(EstimatedViewsPerFacadeMetre(options) * 4 * kMinBlockSide));
}

namespace {

// The camera, shared by all images.
void SetCamera(const SynthKnobs& knobs, SceneOptions* o) {
  const int64_t width = Pick(knobs.width, {}, int64_t{1024});
  const int64_t height = Pick(knobs.height, {}, int64_t{768});
  Require(width >= 64 && height >= 64 && width <= 100000 && height <= 100000,
          "--width and --height must be in [64, 100000] pixels (got " + Str(width) + "x" +
              Str(height) + ")");
  const double focal = Pick(knobs.focal, {}, 900.0);
  Require(focal > 0 && focal <= 1e6,
          "--focal must be in (0, 1000000] pixels (got " + Str(focal) + ")");
  const double radial = Pick(knobs.radial, {}, -0.01);
  Require(std::abs(radial) <= 0.5, "--radial must be in [-0.5, 0.5] (got " + Str(radial) + ")");
  const std::string model = Pick(knobs.camera_model, {}, std::string("SIMPLE_RADIAL"));
  const double cx = double(width) / 2, cy = double(height) / 2;
  o->camera.camera_id = 1;
  o->camera.width = uint64_t(width);
  o->camera.height = uint64_t(height);
  if (model == "SIMPLE_PINHOLE") {
    o->camera.model_id = CameraModelId::kSimplePinhole;
    o->camera.params = {focal, cx, cy};
  } else if (model == "PINHOLE") {
    o->camera.model_id = CameraModelId::kPinhole;
    o->camera.params = {focal, focal, cx, cy};
  } else if (model == "SIMPLE_RADIAL") {
    o->camera.model_id = CameraModelId::kSimpleRadial;
    o->camera.params = {focal, cx, cy, radial};
  } else if (model == "RADIAL") {
    o->camera.model_id = CameraModelId::kRadial;
    o->camera.params = {focal, cx, cy, radial, 0};
  } else {
    throw InputError(
        "--camera-model must be SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL or RADIAL (got '" + model +
        "')");
  }
}

// The city size: explicit blocks, or as many as the target number of views needs.
void SetCitySize(const SynthKnobs& knobs, const Preset& preset, SceneOptions* o) {
  const std::optional<int64_t> blocks = knobs.blocks  ? knobs.blocks
                                        : knobs.views ? std::nullopt
                                                      : preset.blocks;
  if (blocks) {
    Require(*blocks >= 1 && *blocks <= 100000,
            "--blocks must be in [1, 100000] (got " + Str(*blocks) + ")");
    o->layout.blocks_x = int(std::ceil(std::sqrt(double(*blocks))));
    o->layout.blocks_y = int((*blocks + o->layout.blocks_x - 1) / o->layout.blocks_x);
    return;
  }
  const int64_t views = Pick(knobs.views, preset.views, kDefaultViews);
  Require(views > 0, "--views must be positive (got " + Str(views) + ")");
  Require(views <= kMaxViews,
          "--views must be at most " + Str(kMaxViews) + " (got " + Str(views) + ")");
  const int64_t minimum = MinimumViews(*o);
  Require(views >= minimum, "--views " + Str(views) + " is too small to make a city: at least " +
                                Str(minimum) + " views are needed with --features-per-image " +
                                Str(o->features_per_image) + " and --camera-spacing " +
                                Str(o->layout.camera_spacing));
  const double per_metre = EstimatedViewsPerFacadeMetre(*o);
  const double mean_side = 0.5 * (o->layout.min_block_side + o->layout.max_block_side);
  const double per_block = per_metre * 4 * mean_side;
  const double wanted = double(views) / per_block;
  // A near-square grid; block sides are scaled so that the facade length (and so the number of
  // views) matches the target. Below one block's worth, one smaller block.
  const int64_t bx = std::max<int64_t>(1, std::llround(std::sqrt(wanted)));
  const int64_t by = std::max<int64_t>(1, std::llround(wanted / double(bx)));
  const double scale = wanted / double(bx * by);
  o->layout.min_block_side *= scale;
  o->layout.max_block_side *= scale;
  o->layout.blocks_x = int(bx);
  o->layout.blocks_y = int(by);
}

}  // namespace

SceneOptions MakeSceneOptions(const SynthKnobs& knobs) {
  const Preset preset = FindPreset(knobs.preset);
  SceneOptions o;
  o.seed = knobs.seed;
  Require(knobs.threads >= 0, "--threads must not be negative (got " + Str(knobs.threads) + ")");
  o.threads = int(std::min<int64_t>(knobs.threads, 1024));

  const int64_t queries = Pick(knobs.queries, preset.queries, int64_t{100});
  Require(queries >= 0 && queries <= 1000000,
          "--queries must be in [0, 1000000] (got " + Str(queries) + ")");
  o.queries = int(queries);
  if (knobs.path_step) {
    o.path_step = *knobs.path_step;
    Require(o.path_step >= 0.01 && o.path_step <= 20,
            "--path-step must be in [0.01, 20] metres (got " + Str(o.path_step) + ")");
  }
  const int64_t rig_cameras = Pick(knobs.rig_cameras, {}, int64_t{1});
  Require(
      rig_cameras >= 1 && rig_cameras <= kMaxRigCameras,
      "--rig-cameras must be in [1, " + Str(kMaxRigCameras) + "] (got " + Str(rig_cameras) + ")");
  o.rig_cameras = int(rig_cameras);
  const int64_t features = Pick(knobs.features_per_image, preset.features_per_image, int64_t{1500});
  Require(features >= 20 && features <= 100000,
          "--features-per-image must be in [20, 100000] (got " + Str(features) + ")");
  o.features_per_image = int(features);
  o.clutter_fraction = Pick(knobs.clutter_fraction, {}, 0.33);
  Require(o.clutter_fraction >= 0 && o.clutter_fraction < 1,
          "--clutter-fraction must be in [0, 1) (got " + Str(o.clutter_fraction) + ")");
  o.repetition = Pick(knobs.repetition, {}, 0.3);
  Require(o.repetition >= 0 && o.repetition <= 1,
          "--repetition must be in [0, 1] (got " + Str(o.repetition) + ")");
  const int64_t motifs = Pick(knobs.motifs, preset.motifs, int64_t{256});
  Require(motifs >= 0 && motifs <= 100000000,
          "--motifs must be in [0, 100000000] (got " + Str(motifs) + ")");
  Require(motifs > 0 || o.repetition == 0,
          "--motifs must be positive when --repetition is above 0 (got 0)");
  o.motifs = int(motifs);
  o.instance_noise = Pick(knobs.instance_noise, {}, 0.3);
  Require(o.instance_noise >= 0 && o.instance_noise <= 1,
          "--instance-noise must be in [0, 1] (got " + Str(o.instance_noise) + ")");
  o.keypoint_noise = Pick(knobs.keypoint_noise, {}, 0.7);
  Require(o.keypoint_noise >= 0 && o.keypoint_noise <= 5,
          "--keypoint-noise must be in [0, 5] pixels (got " + Str(o.keypoint_noise) + ")");
  o.point_noise = Pick(knobs.point_noise, {}, 0.01);
  Require(o.point_noise >= 0 && o.point_noise <= 0.5,
          "--point-noise must be in [0, 0.5] metres (got " + Str(o.point_noise) + ")");
  o.layout.camera_spacing = Pick(knobs.camera_spacing, preset.camera_spacing, 3.0);
  Require(
      o.layout.camera_spacing >= 0.5 && o.layout.camera_spacing <= 50,
      "--camera-spacing must be in [0.5, 50] metres (got " + Str(o.layout.camera_spacing) + ")");
  if (preset.small_blocks) {
    o.layout.min_block_side = 24;
    o.layout.max_block_side = 40;
  }

  SetCamera(knobs, &o);
  SetCitySize(knobs, preset, &o);
  return o;
}

}  // namespace cwloc::synth
