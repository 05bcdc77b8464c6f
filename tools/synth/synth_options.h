#pragma once

// cwloc-synth's knobs as given on the command line, the demo preset, and their validation:
// turns knobs into SceneOptions, or throws InputError with a message naming the knob.

#include <cstdint>
#include <optional>
#include <string>

#include "tools/synth/city_geo.h"
#include "tools/synth/city_scene.h"

namespace cwloc::synth {

// Unset knobs take the preset's value, then the default.
struct SynthKnobs {
  std::string preset;  // "" or "demo"
  uint64_t seed = 1;
  std::optional<int64_t> views;   // approximate model views; sets the city size
  std::optional<int64_t> blocks;  // explicit number of blocks (overrides views)
  std::optional<int64_t> queries;
  std::optional<int64_t> features_per_image;
  std::optional<double> clutter_fraction;
  std::optional<double> repetition;
  std::optional<int64_t> motifs;
  std::optional<double> instance_noise;
  std::optional<std::string> camera_model;  // SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL, RADIAL
  std::optional<int64_t> width, height;
  std::optional<double> focal;
  std::optional<double> radial;  // k (k1 for RADIAL)
  std::optional<double> camera_spacing;
  std::optional<double> keypoint_noise;
  std::optional<double> point_noise;
  std::optional<double> path_step;     // metres between the frames of a walk; unset: no walk
  std::optional<int64_t> rig_cameras;  // cameras per query frame (a rig when 2 or more)
  int64_t threads = 0;
  // On the globe (city_geo.h); the others need --geo.
  std::optional<std::string> geo;  // "LAT LON HEIGHT": WGS84 degrees, ellipsoidal metres
  std::optional<double> gps_noise;
  std::optional<double> gps_outliers;
  std::optional<double> prior_position_error;
  std::optional<double> prior_radius;
  std::optional<double> prior_gravity_error;  // degrees
};

inline constexpr int64_t kDefaultViews = 200000;
inline constexpr int64_t kMaxViews = 200000000;

// Validates the knobs and derives the scene options (the city size from `views` unless
// `blocks` is given). Throws InputError naming the offending knob.
SceneOptions MakeSceneOptions(const SynthKnobs& knobs);

// Validates the --geo knobs and derives the geo options (defaults in city_geo.h). Throws
// InputError naming the offending knob, also for a --geo knob given without --geo.
GeoOptions MakeGeoOptions(const SynthKnobs& knobs);

// The fewest views --views accepts with these options (a one-block city of 16 m sides).
int64_t MinimumViews(const SceneOptions& options);

}  // namespace cwloc::synth
