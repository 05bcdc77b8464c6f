#pragma once

// SIFT-like descriptors for the generated city. A feature is a small planar patch (a few
// edges and blobs plus texture). A view renders its 4x4x8 gradient histogram through the
// affine distortion the viewpoint causes, with the keypoint's localization, orientation and
// scale errors, then applies VLFeat's normalization and COLMAP's L1-root. Descriptors thus
// change smoothly with the viewpoint and look like COLMAP SIFT; the model was calibrated
// against COLMAP 3.8 on real photos (docs/synth.md).

#include <array>
#include <cstdint>

#include "base/split_mix64.h"

namespace cwloc::synth {

inline constexpr int kSiftDim = 128;

// A descriptor in COLMAP's L1-root domain before quantization: non-negative, unit L2 norm.
using SiftVector = std::array<float, kSiftDim>;

// SplitMix64 with the draws the generator needs. Every stream is seeded from (seed, ids) so
// the output never depends on thread scheduling.
class Rng {
 public:
  explicit Rng(uint64_t seed) : bits_(seed) {}
  // Hashes a few integers into one well-mixed seed.
  static uint64_t Seed(uint64_t a, uint64_t b, uint64_t c = 0, uint64_t d = 0);

  uint64_t Next() { return bits_.Next(); }
  double Uniform() { return double(Next() >> 11) * 0x1.0p-53; }  // [0, 1)
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  uint64_t Below(uint64_t n) { return n == 0 ? 0 : Next() % n; }  // [0, n)
  // Standard normal from four 16-bit uniforms (Irwin-Hall): one draw per sample, bounded at
  // +-3.46. Good enough for descriptor noise and cheap.
  float Normal();
  // Box-Muller normal, for geometry noise where the exact shape matters.
  double Gaussian();
  // n standard normals quantized to 256 levels (one byte each): the bulk noise of descriptors.
  void FillNormal(float* out, int n);

 private:
  SplitMix64 bits_;
};

// The shape of random patches. Tuned so that generated descriptors match real COLMAP SIFT in
// value histogram, largest elements, PCA spectrum and energy per orientation bin.
struct PatchModel {
  double dominant_amplitude = 2.57;    // the edge whose gradient set the keypoint orientation
  double opposite_probability = 0.93;  // a bar: the dominant edge's other side (bin 4)
  double extra_structures = 6.4;       // mean number of further edges and blobs
  double blob_probability = 0.42;      // share of blobs among the further structures
  double texture_density = 10.4;       // mean texture gradients per cell (point-like details)
  double texture_amplitude = 0.39;     // their mean magnitude relative to the structures
  double texture_spread = 0.66;        // log-normal spread of the texture amount between patches
  double window_sigma = 1.9;           // SIFT's Gaussian window, in cells
  double orientation_width = 1.16;     // half-width of a gradient's orientation kernel, in bins
};

// Errors of one detection and how the look changes with the view; calibrated on real true
// matches (docs/synth.md).
struct ViewNoiseModel {
  double orientation_error_deg = 2;  // keypoint orientation error (sigma)
  double shift_error = 0.05;         // keypoint localization error, in descriptor cells (sigma)
  double scale_error = 0;            // extra detected-scale error, log2 (sigma); the city passes
                                     // each keypoint's own error in ViewChange instead
  double scale_texture = 0.6;        // texture change per octave of scale change (radians of a
                                     // rotation between two texture magnitudes)
  double relief = 2.0;               // texture change per unit of sin(obliquity) (radians)
  double pixel_noise = 0.0285;       // i.i.d. image noise, expected L2 norm in the unit domain
};

// Which patch a feature shows. Instances of one motif share `patch_seed` and differ by their
// `instance_seed` with strength `instance_noise` (0: identical patch).
struct Appearance {
  uint64_t patch_seed = 0;
  uint64_t instance_seed = 0;
  double instance_noise = 0;
};

// The viewpoint relative to the feature's own frame (its x axis is the direction of its
// dominant gradient on the facade).
struct ViewChange {
  double u = 0, v = 0;    // viewing ray along the feature's axes (|(u,v)| = sin obliquity)
  double log2_scale = 0;  // log2: the scale the patch is seen at / its reference scale
  double log2_detection_error = 0;  // log2: detected / true keypoint scale
};

// Renders descriptors of views; holds the tables that make that fast. Thread-safe (const).
class SiftGenerator {
 public:
  SiftGenerator(const PatchModel& patch_model, const ViewNoiseModel& noise_model);
  const PatchModel& patch_model() const { return patch_model_; }
  const ViewNoiseModel& noise_model() const { return noise_model_; }

  // One view's descriptor (float, unit L2). `view_rng` supplies the detection errors.
  void Describe(const Appearance& appearance, const ViewChange& view, Rng& view_rng,
                SiftVector* out) const;

 private:
  PatchModel patch_model_;
  ViewNoiseModel noise_model_;
  std::array<float, 64> sample_window_;  // SIFT's Gaussian window at the 8x8 gradient samples
};

// COLMAP's FeatureDescriptorsToUnsignedByte: round(512 x), clamped to 255.
void QuantizeDescriptor(const SiftVector& descriptor, uint8_t* out);

}  // namespace cwloc::synth
