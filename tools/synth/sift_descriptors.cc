#include "tools/synth/sift_descriptors.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <numbers>

namespace cwloc::synth {
namespace {

constexpr int kCells = 4;
constexpr int kBins = 8;
constexpr int kMaxStructures = 16;
constexpr int kMaxTexture = 192;
constexpr double kTwoPi = 2 * std::numbers::pi;

// Random draws each in their own statement, in the order GCC made them: the order of operands
// is unspecified.

// One edge or blob in the patch, in canonical (fronto-parallel) patch coordinates: cells,
// centred on the keypoint, so the descriptor grid spans [-2, 2]^2.
struct Structure {
  bool blob = false;
  double x = 0, y = 0;    // a point on the edge, or the blob centre
  double nx = 1, ny = 0;  // edge: unit gradient direction; blob: (polarity, 0)
  double width = 1;       // edge blur or blob radius
  double amplitude = 1;
};

// A point-like detail: one gradient at one place, whose magnitude turns between two values
// as the scale the patch is seen at changes (fine details fade, coarser ones appear).
struct TextureGradient {
  float x, y;    // canonical position
  float gx, gy;  // unit gradient direction
  float a, b;    // magnitudes at the reference view and a quarter turn away
  float p, q;    // how fast it turns with the viewing direction (relief, shading)
};

int DrawStructures(const PatchModel& model, Rng& rng, Structure* out) {
  int n = 0;
  // The keypoint orientation is the dominant gradient's, so the dominant edge points along x.
  Structure dominant;
  dominant.x = 0.5 * rng.Normal();
  dominant.y = 0.5 * rng.Normal();
  dominant.width = rng.Uniform(0.5, 1.5);
  dominant.amplitude = model.dominant_amplitude * rng.Uniform(0.6, 1.4);
  out[n++] = dominant;
  const double bar = rng.Uniform();
  const double bar_distance = rng.Uniform(0.6, 2.0);
  const double bar_offset = bar_distance * (rng.Uniform() < 0.5 ? -1 : 1);
  const double bar_amplitude = rng.Uniform(0.5, 1.0);
  if (bar < model.opposite_probability) {
    // A bar: the other side of a thin line, gradient the other way.
    Structure opposite = dominant;
    opposite.x += bar_offset;
    opposite.nx = -1;
    opposite.amplitude *= bar_amplitude;
    out[n++] = opposite;
  }
  const int extras =
      std::min(int(rng.Below(uint64_t(2 * model.extra_structures) + 1)), kMaxStructures - n);
  for (int i = 0; i < extras; ++i) {
    Structure s;
    s.blob = rng.Uniform() < model.blob_probability;
    s.x = rng.Uniform(-2, 2);
    s.y = rng.Uniform(-2, 2);
    const double angle = rng.Uniform(0, kTwoPi);
    s.nx = s.blob ? (angle < std::numbers::pi ? 1 : -1) : std::cos(angle);
    s.ny = s.blob ? 0 : std::sin(angle);
    s.width = rng.Uniform(0.4, 1.3);
    s.amplitude = -std::log(1.0 - rng.Uniform());
    out[n++] = s;
  }
  return n;
}

// cos and sin to ~1e-4 for any angle: reduce to [-pi, pi], then Taylor polynomials on half the
// angle and the double-angle formulas.
inline void FastCosSin(float angle, float* c, float* s) {
  constexpr float kInvTwoPi = float(1 / kTwoPi);
  const float turns = angle * kInvTwoPi;
  const float nearest =
      float(int(turns + (turns >= 0 ? 0.5f : -0.5f)));  // inline, unlike nearbyint
  const float h = 0.5f * (angle - float(kTwoPi) * nearest);
  const float h2 = h * h;
  const float ch = 1 - h2 * (0.5f - h2 * (1.0f / 24 - h2 * (1.0f / 720)));
  const float sh = h * (1 - h2 * (1.0f / 6 - h2 * (1.0f / 120 - h2 * (1.0f / 5040))));
  *c = ch * ch - sh * sh;
  *s = 2 * sh * ch;
}

// Two random words per detail: position and direction from 16-bit fields, the four
// magnitudes from byte-quantized normals.
TextureGradient DrawTexture(double amplitude, Rng& rng) {
  constexpr float kUnit = 1.0f / 65536;
  const uint64_t r = rng.Next();
  TextureGradient t;
  t.x = 4.4f * (float(r & 0xffff) * kUnit) - 2.2f;
  t.y = 4.4f * (float((r >> 16) & 0xffff) * kUnit) - 2.2f;
  FastCosSin(float(kTwoPi) * float((r >> 32) & 0xffff) * kUnit, &t.gx, &t.gy);
  float n[4];
  rng.FillNormal(n, 4);
  t.a = float(amplitude) * n[0];
  t.b = float(amplitude) * n[1];
  t.p = n[2];
  t.q = n[3];
  return t;
}

int DrawTextures(const PatchModel& model, Rng& rng, TextureGradient* out) {
  const double spread = model.texture_spread;
  const double level = std::exp(spread * rng.Normal() - 0.5 * spread * spread);
  const int n = std::min(kMaxTexture, int(model.texture_density * 16 * level + rng.Uniform()));
  for (int i = 0; i < n; ++i) out[i] = DrawTexture(model.texture_amplitude, rng);
  return n;
}

// A different instance of the same motif: the same structures, slightly moved and reweighted,
// and part of the fine texture replaced.
void PerturbPatch(const PatchModel& model, double strength, Rng& rng, Structure* structures, int n,
                  TextureGradient* textures, int num_textures) {
  for (int i = 0; i < n; ++i) {
    Structure& s = structures[i];
    s.x += strength * 0.5 * rng.Normal();
    s.y += strength * 0.5 * rng.Normal();
    s.amplitude *= std::exp(strength * 0.4 * rng.Normal());
    if (!s.blob) {
      const double angle = std::atan2(s.ny, s.nx) + strength * 0.25 * rng.Normal();
      s.nx = std::cos(angle);
      s.ny = std::sin(angle);
    }
  }
  const double replace = std::min(1.0, 0.5 * strength);
  for (int i = 0; i < num_textures; ++i) {
    if (rng.Uniform() < replace) textures[i] = DrawTexture(model.texture_amplitude, rng);
  }
}

// exp(x) for x <= 0 to ~1e-5 relative: 2^x by exponent bits and a polynomial for the fraction.
inline float FastExp(float x) {
  const float y = std::max(x, -80.0f) * 1.44269504f;
  const float fl = std::floor(y);
  const float f = y - fl;
  const float p =
      1.0f +
      f * (0.693147f + f * (0.240227f + f * (0.0555041f + f * (0.00961813f + f * 0.00133336f))));
  return std::bit_cast<float>(std::bit_cast<int32_t>(p) + (int32_t(fl) << 23));
}

// atan2 to ~0.004 rad, plenty for an 8-bin orientation histogram.
inline float FastAtan2(float y, float x) {
  const float ax = std::abs(x), ay = std::abs(y);
  const float mx = std::max(ax, ay);
  if (mx == 0) return 0;
  const float z = std::min(ax, ay) / mx;
  float a = z * (0.785398f + 0.273f * (1 - z));
  if (ay > ax) a = 1.5707963f - a;
  if (x < 0) a = 3.1415927f - a;
  return y < 0 ? -a : a;
}

void NormalizeL2(SiftVector* d) {
  double sum = 0;
  for (float x : *d) sum += double(x) * x;
  if (sum <= 0) {
    d->fill(float(1 / std::sqrt(double(kSiftDim))));  // a flat patch: no gradient at all
    return;
  }
  const float inv = float(1 / std::sqrt(sum));
  for (float& x : *d) x *= inv;
}

// Normal quantiles at (i + 0.5) / 256, by bisection on erfc: exact to float precision.
std::array<float, 256> MakeNormalQuantiles() {
  std::array<float, 256> table;
  for (int i = 0; i < 256; ++i) {
    const double p = (i + 0.5) / 256;
    double lo = -6, hi = 6;
    for (int it = 0; it < 60; ++it) {
      const double mid = 0.5 * (lo + hi);
      (0.5 * std::erfc(-mid / std::numbers::sqrt2) < p ? lo : hi) = mid;
    }
    table[i] = float(0.5 * (lo + hi));
  }
  return table;
}

// Adds a gradient to the orientation bins of one cell with a triangular kernel of half-width
// `width` bins (1 = SIFT's linear interpolation between the two nearest bins).
inline void AddToCell(float magnitude, float vx, float vy, float width, float inv_width,
                      float* cell) {
  constexpr float kBinsPerRadian = float(kBins / kTwoPi);
  float bin = FastAtan2(vy, vx) * kBinsPerRadian;
  if (bin < 0) bin += kBins;
  const int first = int(std::floor(bin - width)) + 1;
  for (int b = first; b <= bin + width; ++b) {
    const float w = 1 - std::abs(b - bin) * inv_width;
    if (w > 0) cell[(b + 2 * kBins) % kBins] += magnitude * w;
  }
}

}  // namespace

uint64_t Rng::Seed(uint64_t a, uint64_t b, uint64_t c, uint64_t d) {
  uint64_t s = Rng(a ^ 0x51ed270b27c4d3a1ULL).Next();
  for (uint64_t v : {b, c, d}) s = Rng(s ^ (v * 0x9e3779b97f4a7c15ULL)).Next();
  return s;
}

float Rng::Normal() {
  const uint64_t r = Next();
  const uint32_t sum = uint32_t(r & 0xffff) + uint32_t((r >> 16) & 0xffff) +
                       uint32_t((r >> 32) & 0xffff) + uint32_t(r >> 48);
  // A sum of four U(0,1) has mean 2 and variance 1/3.
  return (float(sum) * (1.0f / 65536.0f) - 2.0f) * 1.7320508f;
}

void Rng::FillNormal(float* out, int n) {
  static const std::array<float, 256> kQuantiles = MakeNormalQuantiles();
  for (int i = 0; i < n; i += 8) {
    uint64_t r = Next();
    for (int j = i; j < std::min(n, i + 8); ++j, r >>= 8) out[j] = kQuantiles[r & 0xff];
  }
}

double Rng::Gaussian() {
  const double u1 = 1.0 - Uniform();  // (0, 1]
  const double u2 = Uniform();
  return std::sqrt(-2 * std::log(u1)) * std::cos(kTwoPi * u2);
}

SiftGenerator::SiftGenerator(const PatchModel& patch_model, const ViewNoiseModel& noise_model)
    : patch_model_(patch_model), noise_model_(noise_model) {
  const double inv_window2 = 1 / (2 * patch_model.window_sigma * patch_model.window_sigma);
  for (int s = 0; s < 64; ++s) {
    const double x = (s % 8) * 0.5 - 1.75, y = (s / 8) * 0.5 - 1.75;
    sample_window_[s] = float(std::exp(-(x * x + y * y) * inv_window2));
  }
}

namespace {

// The affine map of the patch into the view as the detector normalizes it: T, canonical patch
// to view, and T^-1, in float, then the detection's shift.
struct ViewWarp {
  float f00, f01, f10, f11;  // T
  float i00, i01, i10, i11;  // T^-1
  float shift_x, shift_y;
};

// Viewpoint: a plane seen at obliquity theta is compressed by cos(theta) along the tilt
// direction; the detector then normalizes scale (by sqrt(det)) and orientation (the dominant
// gradient back to angle 0), each with its own error, drawn from `view_rng`.
ViewWarp DrawViewWarp(const ViewChange& view, const ViewNoiseModel& noise_model, Rng& view_rng) {
  const double sin2 = std::min(view.u * view.u + view.v * view.v, 0.99);
  const double c = std::sqrt(1 - sin2);
  const double phi = std::atan2(view.v, view.u);
  const double cp = std::cos(phi), sp = std::sin(phi);
  // T0 = R(phi) diag(c, 1) R(-phi) / sqrt(c)
  const double norm = 1 / std::sqrt(c);
  double t00 = (c * cp * cp + sp * sp) * norm, t01 = (c - 1) * cp * sp * norm;
  double t10 = t01, t11 = (c * sp * sp + cp * cp) * norm;
  // The dominant gradient (1, 0) maps to T0^-T (1, 0), proportional to (t11, -t01).
  const double psi = std::atan2(-t01, t11);
  const double rotation =
      -psi + noise_model.orientation_error_deg * std::numbers::pi / 180 * view_rng.Normal();
  // A detected scale too large by 2^e makes the descriptor window cover 2^e more of the patch.
  const double scale =
      std::exp2(-view.log2_detection_error + noise_model.scale_error * view_rng.Normal());
  const double cr = std::cos(rotation) * scale, sr = std::sin(rotation) * scale;
  {
    const double a00 = cr * t00 - sr * t10, a01 = cr * t01 - sr * t11;
    const double a10 = sr * t00 + cr * t10, a11 = sr * t01 + cr * t11;
    t00 = a00, t01 = a01, t10 = a10, t11 = a11;
  }
  const double det = t00 * t11 - t01 * t10;
  ViewWarp warp;
  warp.f00 = float(t00), warp.f01 = float(t01), warp.f10 = float(t10), warp.f11 = float(t11);
  warp.i00 = float(t11 / det), warp.i01 = float(-t01 / det);
  warp.i10 = float(-t10 / det), warp.i11 = float(t00 / det);
  warp.shift_x = float(noise_model.shift_error * view_rng.Normal());
  warp.shift_y = float(noise_model.shift_error * view_rng.Normal());
  return warp;
}

// Adds the structures' gradients to the orientation histograms `h`: the image gradient at 8x8
// samples (2x2 per cell), the sum of every structure's gradient at the corresponding canonical
// point. Image gradients transform with T^-T.
void AddStructureGradients(const Structure* structures, int n, const ViewWarp& warp,
                           const std::array<float, 64>& sample_window, float width, float inv_width,
                           float* h) {
  const float i00 = warp.i00, i01 = warp.i01, i10 = warp.i10, i11 = warp.i11;
  alignas(32) float sx[64], sy[64], gx[64] = {}, gy[64] = {};
  for (int s = 0; s < 64; ++s) {
    const float x = (s % 8) * 0.5f - 1.75f - warp.shift_x;
    const float y = (s / 8) * 0.5f - 1.75f - warp.shift_y;
    sx[s] = i00 * x + i01 * y;
    sy[s] = i10 * x + i11 * y;
  }
  for (int k = 0; k < n; ++k) {
    const Structure& st = structures[k];
    const float ox = float(st.x), oy = float(st.y), nx = float(st.nx), ny = float(st.ny);
    const float half_inv_w2 = float(0.5 / (st.width * st.width));
    if (st.blob) {
      const float amplitude = float(st.nx * st.amplitude / st.width);
      for (int s = 0; s < 64; ++s) {
        const float dx = sx[s] - ox, dy = sy[s] - oy;
        const float g = amplitude * FastExp(-(dx * dx + dy * dy) * half_inv_w2);
        gx[s] += g * dx;
        gy[s] += g * dy;
      }
    } else {
      const float amplitude = float(st.amplitude);
      for (int s = 0; s < 64; ++s) {
        const float d = (sx[s] - ox) * nx + (sy[s] - oy) * ny;
        const float g = amplitude * FastExp(-d * d * half_inv_w2);
        gx[s] += g * nx;
        gy[s] += g * ny;
      }
    }
  }
  for (int s = 0; s < 64; ++s) {
    const float vx = i00 * gx[s] + i10 * gy[s], vy = i01 * gx[s] + i11 * gy[s];
    const float magnitude = sample_window[s] * std::sqrt(vx * vx + vy * vy);
    if (magnitude < 1e-9f) continue;
    AddToCell(magnitude, vx, vy, width, inv_width, h + ((s / 16) * kCells + (s % 8) / 2) * kBins);
  }
}

// Adds the texture details to `h`: they move with the view (x = T X + shift) and fade in and
// out with the scale and, as relief and shading would, with the viewing direction.
void AddTextureGradients(const TextureGradient* textures, int num_textures, const ViewWarp& warp,
                         const ViewChange& view, const PatchModel& patch_model,
                         const ViewNoiseModel& noise_model, float width, float inv_width,
                         float* h) {
  const float scale_turn = float(noise_model.scale_texture * view.log2_scale);
  const float relief_u = float(noise_model.relief * view.u);
  const float relief_v = float(noise_model.relief * view.v);
  const float inv_window2 = float(1 / (2 * patch_model.window_sigma * patch_model.window_sigma));
  for (int k = 0; k < num_textures; ++k) {
    const TextureGradient& t = textures[k];
    const float x = warp.f00 * t.x + warp.f01 * t.y + warp.shift_x;
    const float y = warp.f10 * t.x + warp.f11 * t.y + warp.shift_y;
    if (!(x > -2 && x < 2 && y > -2 && y < 2)) continue;
    const float vx = warp.i00 * t.gx + warp.i10 * t.gy, vy = warp.i01 * t.gx + warp.i11 * t.gy;
    const float turn = scale_turn + relief_u * t.p + relief_v * t.q;
    float ct, st;
    FastCosSin(turn, &ct, &st);
    const float magnitude = std::abs(ct * t.a + st * t.b) * std::sqrt(vx * vx + vy * vy) *
                            FastExp(-(x * x + y * y) * inv_window2);
    if (magnitude < 1e-9f) continue;
    const int cell = int(y + 2) * kCells + int(x + 2);
    AddToCell(magnitude, vx, vy, width, inv_width, h + cell * kBins);
  }
}

// The descriptor of histograms `h`: VLFeat's (L2 normalize, clamp at 0.2, L2 normalize), then
// COLMAP's (L1 normalize, element-wise sqrt), with the pixel noise drawn from `view_rng`.
void NormalizeWithNoise(const std::array<float, kSiftDim>& h, const ViewNoiseModel& noise_model,
                        Rng& view_rng, SiftVector* out) {
  SiftVector d;
  for (int i = 0; i < kSiftDim; ++i) d[i] = h[i];
  NormalizeL2(&d);
  for (float& x : d) x = std::min(x, 0.2f);
  NormalizeL2(&d);
  float l1 = 0;
  for (float x : d) l1 += x;
  const float inv_l1 = 1 / l1;
  const float sigma = float(noise_model.pixel_noise / std::sqrt(double(kSiftDim)));
  std::array<float, kSiftDim> noise;
  view_rng.FillNormal(noise.data(), kSiftDim);
  for (int i = 0; i < kSiftDim; ++i) {
    (*out)[i] = std::max(0.0f, std::sqrt(d[i] * inv_l1) + sigma * noise[i]);
  }
  NormalizeL2(out);
}

}  // namespace

void SiftGenerator::Describe(const Appearance& appearance, const ViewChange& view, Rng& view_rng,
                             SiftVector* out) const {
  Rng patch_rng(appearance.patch_seed);
  Structure structures[kMaxStructures];
  const int n = DrawStructures(patch_model_, patch_rng, structures);
  TextureGradient textures[kMaxTexture];
  const int num_textures = DrawTextures(patch_model_, patch_rng, textures);
  if (appearance.instance_noise > 0) {
    Rng instance_rng(appearance.instance_seed);
    PerturbPatch(patch_model_, appearance.instance_noise, instance_rng, structures, n, textures,
                 num_textures);
  }
  const ViewWarp warp = DrawViewWarp(view, noise_model_, view_rng);
  std::array<float, kSiftDim> h{};
  const float width = float(std::max(1.0, patch_model_.orientation_width));
  const float inv_width = 1 / width;
  AddStructureGradients(structures, n, warp, sample_window_, width, inv_width, h.data());
  AddTextureGradients(textures, num_textures, warp, view, patch_model_, noise_model_, width,
                      inv_width, h.data());
  NormalizeWithNoise(h, noise_model_, view_rng, out);
}

void QuantizeDescriptor(const SiftVector& descriptor, uint8_t* out) {
  for (int i = 0; i < kSiftDim; ++i) {
    // Values are non-negative, so adding 0.5 and truncating rounds half away from zero.
    out[i] = uint8_t(std::min(255.0f, 512.0f * descriptor[i] + 0.5f));
  }
}

}  // namespace cwloc::synth
