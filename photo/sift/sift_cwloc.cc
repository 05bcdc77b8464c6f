// SiftOptions::Implementation::kCwloc: our own implementation of the algorithm VLFeat's
// sift.c runs (Lowe's SIFT as VLFeat documents it), written so that every float operation a
// pixel sees happens in VLFeat's order and precision. It is faster because of how it computes,
// never what:
//  - separable Gaussian smoothing streamed row by row, vectorized across pixels (VLFeat
//    convolves one column at a time through a transposed temporary image);
//  - each octave's levels are made in bands of rows that slide down the image, so no whole
//    level is held (a level of the doubled photo is 25 MB at 1536 x 1024); DoG values are
//    computed where detection reads them;
//  - detection runs over all octaves first; orientations and descriptors are computed only
//    for the DoG levels COLMAP's max_num_features rule keeps (COLMAP describes every level
//    and then drops the finest ones), in a second pass that makes those octaves' levels again
//    band by band, with the gradient of the rows their keypoints read;
//  - the descriptor skips window pixels that fall outside the 4x4 spatial bins.
// The scale space is in sift_scale_space.*, detection in sift_detect.*, orientations and
// descriptors in sift_describe.*, their row kernels in sift_kernels.*; this file runs them in
// order. docs/sift.md has the measurements.
#include "photo/sift/sift_cwloc.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "base/parallel_for.h"
#include "photo/sift/sift_describe.h"
#include "photo/sift/sift_detect.h"
#include "photo/sift/sift_levels.h"
#include "photo/sift/sift_scale_space.h"

namespace cwloc::sift_internal {
namespace {

// What an octave's levels are made from.
struct OctaveSource {
  int o;
  Plane plane;  // the photo (first octave) or the octave below's level s_min + S, downsampled
  bool doubled;
  double base_sigma;
  // The first octave's level kKeptLevel, made whole (not in a band) during detection when it
  // fits kMaxKeptLevelBytes: describing keypoints of that level or above then makes their
  // levels from it, not from the photo.
  Plane kept_level;
};

// Describing the first octave's keypoints needs its levels again, and COLMAP's cap keeps its
// finer levels only for small photos or large caps: for 1536 x 1024 photos at 6000 and 8192
// features, levels 2 and 1 (of -1 .. 4). Keeping level 1 of the doubled photo (25 MB) spares
// the second pass the upsampling and three of its four smoothings.
constexpr int kKeptLevel = 1;  // = s_min + 2
constexpr size_t kMaxKeptLevelBytes = size_t(32) << 20;

// Every keypoint of every octave in VLFeat's order (octave, level, row, column), and each
// octave's source for the description pass.
void DetectAll(const GreyImage& image, const Geometry& g, const SiftOptions& options,
               WorkerPool& pool, std::vector<Key>* keys, std::vector<OctaveSource>* sources) {
  Plane input;
  input.Resize(int(image.width), int(image.height));
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    input.data()[i] = float(image.pixels[i]) / 255.0f;
  }
  OctaveSource source{g.o_min, std::move(input), g.o_min < 0, 0, Plane()};
  if (g.o_min > 0) {
    const int w = ShiftLeft(source.plane.w, -g.o_min), h = ShiftLeft(source.plane.h, -g.o_min);
    Plane smaller;
    smaller.Resize(w, h);
    DownsampleRows(source.plane, g.o_min, {0, source.plane.h}, &smaller);
    source.plane = std::move(smaller);
  }
  {
    const double sa = g.sigma0 * std::pow(g.sigmak, g.s_min);
    const double sb = g.sigman * std::pow(2.0, -g.o_min);
    if (sa > sb) source.base_sigma = std::sqrt(sa * sa - sb * sb);
  }
  const int s_best = std::min(g.s_min + g.S, g.s_max);
  for (int oi = 0; oi < g.O; ++oi) {
    const int o = g.o_min + oi;
    const int w = ShiftLeft(int(image.width), -o), h = ShiftLeft(int(image.height), -o);
    if (w < 3 || h < 3) break;  // no pixel with 8 neighbours: VLFeat finds nothing either
    sources->push_back(std::move(source));
    OctaveSource& current = sources->back();
    const bool keep_level = oi == 0 && g.s_min < kKeptLevel && kKeptLevel <= g.s_max - 2 &&
                            size_t(w) * size_t(h) * sizeof(float) <= kMaxKeptLevelBytes;
    OctaveLevels levels(g, current.plane, current.doubled, current.base_sigma, pool);
    if (keep_level) {
      current.kept_level.Resize(w, h);
      levels.KeepWhole(kKeptLevel, &current.kept_level, 0);
    }
    const int wn = ShiftLeft(int(image.width), -(o + 1)),
              hn = ShiftLeft(int(image.height), -(o + 1));
    const bool next = oi + 1 < g.O && wn >= 3 && hn >= 3;
    source = OctaveSource{o + 1, Plane(), false, 0, Plane()};
    if (next) source.plane.Resize(wn, hn);
    std::vector<std::vector<Key>> level_keys(size_t(g.s_max - g.s_min - 2));
    for (int d0 = 0; d0 < h; d0 += kBandRows) {
      const Rows band{d0, std::min(h, d0 + kBandRows)};
      levels.Cover(
          std::vector<Rows>(size_t(g.s_max - g.s_min + 1), Widen(band, kDetectionReach, h)));
      const Rows detect{std::max(band.lo, 1), std::min(band.hi, h - 1)};
      for (int s = g.s_min + 1; s <= g.s_max - 2 && !detect.empty(); ++s) {
        const Plane* gauss[4] = {&levels.Level(s - 1), &levels.Level(s), &levels.Level(s + 1),
                                 &levels.Level(s + 2)};
        DetectLevel(gauss, s, o, g, options.peak_threshold, options.edge_threshold, detect, pool,
                    &level_keys[size_t(s - g.s_min - 1)]);
      }
      if (next) DownsampleRows(levels.Level(s_best), 1, band, &source.plane);
    }
    for (const auto& level : level_keys) keys->insert(keys->end(), level.begin(), level.end());
    const double sa = g.sigma0 * std::pow(float(g.sigmak), float(g.s_min));
    const double sb = g.sigma0 * std::pow(float(g.sigmak), float(s_best - g.S));
    if (sa > sb) source.base_sigma = std::sqrt(sa * sa - sb * sb);
  }
}

// A keypoint's orientations (VLFeat finds up to four).
struct KeyAngles {
  double angle[4];
  int count;
};

// Orientations and descriptors of keys[begin, end), all in octave `source.o`: the octave's
// levels are made again, band by band, with the gradient of each level's rows its keypoints
// read. Key j's orientations go to angles[j - begin] and its descriptors (the first `slots`
// orientations') to descriptors + (j - begin) * slots * 128.
void DescribeOctave(const std::vector<Key>& keys, size_t begin, size_t end, OctaveSource& source,
                    const Geometry& g, const SiftOptions& options, WorkerPool& pool, int slots,
                    KeyAngles* angles, uint8_t* descriptors) {
  OctaveLevels levels(g, source.plane, source.doubled, source.base_sigma, pool);
  const int h = levels.h;
  const size_t num_levels = size_t(g.s_max - g.s_min - 2);  // s_min + 1 .. s_max - 2
  std::vector<int> reach(num_levels, -1);                   // -1: no keypoint
  std::vector<std::vector<size_t>> by_band(size_t((h + kBandRows - 1) / kBandRows));
  int lowest_level = g.s_max;
  for (size_t j = begin; j < end; ++j) {
    int& r = reach[size_t(keys[j].is - g.s_min - 1)];
    r = std::max(r, KeyReach(keys[j]));
    by_band[size_t(std::clamp(KeyRow(keys[j]), 0, h - 1) / kBandRows)].push_back(j);
    lowest_level = std::min(lowest_level, keys[j].is);
  }
  if (source.kept_level.size() > 0 && lowest_level >= kKeptLevel) {
    levels.KeepWhole(kKeptLevel, &source.kept_level, h);
  }
  std::vector<GradientPlanes> grads(num_levels);
  for (size_t b = 0; b < by_band.size(); ++b) {
    const Rows band{int(b) * kBandRows, std::min(h, int(b + 1) * kBandRows)};
    std::vector<Rows> need(num_levels + 1);  // levels s_min .. s_max - 2
    std::vector<Rows> grad_rows(num_levels);
    for (size_t l = 0; l < num_levels; ++l) {
      if (reach[l] < 0) continue;
      grad_rows[l] = Widen(band, reach[l], h);
      need[l + 1] = Widen(grad_rows[l], 1, h);
    }
    levels.Cover(need);
    for (size_t l = 0; l < num_levels; ++l) {
      if (reach[l] < 0) continue;
      const Rows rows = grad_rows[l];
      const int from = Slide(&grads[l].mod, levels.w, h, rows, pool);
      Slide(&grads[l].angle, levels.w, h, rows, pool);
      Gradient(levels.Level(g.s_min + 1 + int(l)), {from, rows.hi}, &grads[l], pool);
    }
    const std::vector<size_t>& band_keys = by_band[b];
    pool.For(band_keys.size(), [&](size_t i) {
      const size_t j = band_keys[i];
      const Key& k = keys[j];
      const GradientPlanes& grad = grads[size_t(k.is - g.s_min - 1)];
      KeyAngles& a = angles[j - begin];
      if (options.upright) {
        a.count = 1;
        a.angle[0] = 0.0;
      } else {
        a.count = Orientations(k, grad, a.angle);
      }
      for (int slot = 0; slot < std::min(a.count, slots); ++slot) {
        float raw[kSiftDescriptorDim];
        Descriptor(k, a.angle[slot], grad, raw);
        FinishDescriptor(
            raw, options.normalization,
            descriptors + ((j - begin) * size_t(slots) + size_t(slot)) * kSiftDescriptorDim);
      }
    });
  }
}

}  // namespace

SiftFeatures ExtractSiftCwloc(const GreyImage& image, const SiftOptions& options) {
  const Geometry g = MakeGeometry(options);
  std::vector<Key> keys;
  std::vector<OctaveSource> sources;
  WorkerPool pool(options.num_threads);
  DetectAll(image, g, options, pool, &keys, &sources);

  // COLMAP's levels: runs of equal level index (not reset between octaves).
  std::vector<size_t> counts;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (i == 0 || keys[i].is != keys[i - 1].is) counts.push_back(0);
    ++counts.back();
  }
  const size_t first_run = FirstLevelToKeep(counts, options.max_num_features);
  size_t first_key = 0;
  for (size_t run = 0; run < first_run; ++run) first_key += counts[run];

  // Octave by octave, the kept keypoints' orientations and descriptors, then the features in
  // COLMAP's order: keypoint by keypoint, its first max_num_orientations orientations.
  const int slots = std::min(options.max_num_orientations, 4);
  const size_t n = keys.size() - first_key;
  std::vector<KeyAngles> angles(n);
  std::vector<uint8_t> descriptors(n * size_t(slots) * kSiftDescriptorDim);
  for (size_t begin = first_key, end; begin < keys.size(); begin = end) {
    const int o = keys[begin].o;
    for (end = begin; end < keys.size() && keys[end].o == o;) ++end;
    DescribeOctave(keys, begin, end, sources[size_t(o - g.o_min)], g, options, pool, slots,
                   angles.data() + (begin - first_key),
                   descriptors.data() + (begin - first_key) * size_t(slots) * kSiftDescriptorDim);
  }
  SiftFeatures features;
  for (size_t i = 0; i < n; ++i) {
    const Key& k = keys[first_key + i];
    for (int slot = 0; slot < std::min(angles[i].count, slots); ++slot) {
      features.keypoints.push_back({k.x + 0.5f, k.y + 0.5f, k.sigma, float(angles[i].angle[slot])});
      const uint8_t* d =
          descriptors.data() + (i * size_t(slots) + size_t(slot)) * kSiftDescriptorDim;
      features.descriptors.insert(features.descriptors.end(), d, d + kSiftDescriptorDim);
    }
  }
  return features;
}

}  // namespace cwloc::sift_internal
