#include "tools/synth/synth_options.h"

#include <cmath>
#include <sstream>

#include "format/base/error.h"
#include "format/camera/camera_models.h"

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

}  // namespace

int64_t MinimumViews(const SceneOptions& options) {
  return int64_t(std::ceil(EstimatedViewsPerFacadeMetre(options) * 4 * kMinBlockSide));
}

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

  // The camera, shared by all images.
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
  o.camera.camera_id = 1;
  o.camera.width = uint64_t(width);
  o.camera.height = uint64_t(height);
  if (model == "SIMPLE_PINHOLE") {
    o.camera.model_id = CameraModelId::kSimplePinhole;
    o.camera.params = {focal, cx, cy};
  } else if (model == "PINHOLE") {
    o.camera.model_id = CameraModelId::kPinhole;
    o.camera.params = {focal, focal, cx, cy};
  } else if (model == "SIMPLE_RADIAL") {
    o.camera.model_id = CameraModelId::kSimpleRadial;
    o.camera.params = {focal, cx, cy, radial};
  } else if (model == "RADIAL") {
    o.camera.model_id = CameraModelId::kRadial;
    o.camera.params = {focal, cx, cy, radial, 0};
  } else {
    throw InputError(
        "--camera-model must be SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL or RADIAL (got '" + model +
        "')");
  }

  // The city size: explicit blocks, or as many as the target number of views needs.
  const std::optional<int64_t> blocks = knobs.blocks  ? knobs.blocks
                                        : knobs.views ? std::nullopt
                                                      : preset.blocks;
  if (blocks) {
    Require(*blocks >= 1 && *blocks <= 100000,
            "--blocks must be in [1, 100000] (got " + Str(*blocks) + ")");
    o.layout.blocks_x = int(std::ceil(std::sqrt(double(*blocks))));
    o.layout.blocks_y = int((*blocks + o.layout.blocks_x - 1) / o.layout.blocks_x);
    return o;
  }
  const int64_t views = Pick(knobs.views, preset.views, kDefaultViews);
  Require(views > 0, "--views must be positive (got " + Str(views) + ")");
  Require(views <= kMaxViews,
          "--views must be at most " + Str(kMaxViews) + " (got " + Str(views) + ")");
  const int64_t minimum = MinimumViews(o);
  Require(views >= minimum, "--views " + Str(views) + " is too small to make a city: at least " +
                                Str(minimum) + " views are needed with --features-per-image " +
                                Str(features) + " and --camera-spacing " +
                                Str(o.layout.camera_spacing));
  const double per_metre = EstimatedViewsPerFacadeMetre(o);
  const double mean_side = 0.5 * (o.layout.min_block_side + o.layout.max_block_side);
  const double per_block = per_metre * 4 * mean_side;
  const double wanted = double(views) / per_block;
  // A near-square grid; block sides are scaled so that the facade length (and so the number of
  // views) matches the target. Below one block's worth, one smaller block.
  const int64_t bx = std::max<int64_t>(1, std::llround(std::sqrt(wanted)));
  const int64_t by = std::max<int64_t>(1, std::llround(wanted / double(bx)));
  const double scale = wanted / double(bx * by);
  o.layout.min_block_side *= scale;
  o.layout.max_block_side *= scale;
  o.layout.blocks_x = int(bx);
  o.layout.blocks_y = int(by);
  return o;
}

}  // namespace cwloc::synth
