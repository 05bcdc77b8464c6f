#pragma once

// The Gaussian scale space of our SIFT (sift_cwloc.cc), as VLFeat's sift.c makes it, float
// operation for float operation: an octave's levels are made in bands of rows that slide down
// the image, so no whole level of the doubled photo (25 MB at 1536 x 1024) is held.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <memory>
#include <new>
#include <vector>

#include "base/parallel_for.h"
#include "photo/sift/sift_extractor.h"

namespace cwloc::sift_internal {

// Rows y0 .. y0 + rows - 1 of a w x h single-channel float image, row-major (the whole image
// when y0 = 0 and rows = h). Storage is kept when large enough and never initialized: each
// pixel is written before it is read.
struct Plane {
  int w = 0, h = 0, y0 = 0, rows = 0;
  size_t capacity = 0;
  struct Free {
    void operator()(float* p) const { std::free(p); }
  };
  std::unique_ptr<float[], Free> storage;

  // Storage for n floats, 64-byte aligned; from 2 MiB on, on transparent huge pages where the
  // system offers them.
  static std::unique_ptr<float[], Free> Allocate(size_t n);
  void Resize(int width, int height) { Hold(width, height, 0, height); }
  // Holds rows [first, first + count), forgetting what it held.
  void Hold(int width, int height, int first, int count) {
    w = width;
    h = height;
    y0 = first;
    rows = count;
    if (size() > capacity) {
      storage = Allocate(size());
      capacity = size();
    }
  }
  size_t size() const { return size_t(w) * size_t(rows); }
  int end() const { return y0 + rows; }
  float* data() { return storage.get(); }
  const float* data() const { return storage.get(); }
  float* Row(int y) { return data() + size_t(y - y0) * size_t(w); }
  const float* Row(int y) const { return data() + size_t(y - y0) * size_t(w); }
};

// Rows [lo, hi) of an image; empty when lo >= hi.
struct Rows {
  int lo = 0, hi = 0;
  bool empty() const { return lo >= hi; }
};
inline Rows Widen(Rows r, int by, int h) {
  return r.empty() ? r : Rows{std::max(r.lo - by, 0), std::min(r.hi + by, h)};
}
inline Rows Union(Rows a, Rows b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}

// Copies `rows` rows of `w` floats from src to dst; in parallel when the two do not overlap.
void MoveRows(float* dst, const float* src, int rows, int w, WorkerPool& pool);

// Makes `band` (a w x h image's rows) hold rows `want`, keeping the rows it already holds there;
// returns the first row it still has to compute. Bands only slide down the image.
int Slide(Plane* band, int w, int h, Rows want, WorkerPool& pool);

// VLFeat's smoothing kernel: width max(ceil(4 sigma), 1), taps exp(-d^2/2) with d computed
// in float, normalized by their float sum.
inline int HalfWidth(double sigma) { return std::max(int(std::ceil(4.0 * sigma)), 1); }

std::vector<float> GaussianKernel(double sigma);

// Rows `rows` of `in` smoothed with VLFeat's Gaussian into `out` (which holds them): first
// along columns, then along rows, each output pixel summing its taps from the first (top/left)
// to the last with the edge pixel repeated, exactly VLFeat's vl_imconvcol_vf order; vectorized
// across the pixels of a row. `in` holds rows `rows` widened by HalfWidth(sigma).
void Smooth(const Plane& in, Plane* out, double sigma, Rows rows, WorkerPool& pool);

// Rows `rows` of `in` doubled in both sides, as VLFeat's copy_and_upsample_rows applied twice
// makes them: the new pixels the means of their neighbours (along rows first), the last row and
// column repeated.
void UpsampleRows(const Plane& in, Plane* out, Rows rows, WorkerPool& pool);

// Every 2^d-th pixel of every 2^d-th row, from (0, 0), of `in`'s rows `rows` into the w x h
// plane `out`.
void DownsampleRows(const Plane& in, int d, Rows rows, Plane* out);

struct Geometry {
  int S, s_min, s_max, o_min, O;
  double sigma0, sigmak, sigman, dsigma0;
};

Geometry MakeGeometry(const SiftOptions& options);

inline int ShiftLeft(int x, int n) { return n >= 0 ? x << n : x >> -n; }

// One octave's Gaussian levels, computed in bands of rows that slide down the image, each row
// once: level s_min from the octave's source (the photo, doubled or not, or the octave below's
// level downsampled), smoothed by base_sigma when that is not 0; each next level smoothed from
// the one before. A band of the doubled photo is 128 + ~100 rows, not the 2048 of a whole
// level of a 1536 x 1024 photo.
class OctaveLevels {
 public:
  OctaveLevels(const Geometry& g, const Plane& source, bool doubled, double base_sigma,
               WorkerPool& pool)
      : g_(g),
        source_(source),
        doubled_(doubled),
        base_sigma_(base_sigma),
        pool_(pool),
        w(doubled ? 2 * source.w : source.w),
        h(doubled ? 2 * source.h : source.h),
        bands_(size_t(g.s_max - g.s_min + 1)) {}

  // Level s lives in `whole`, a w x h plane whose rows [0, rows_made) are made: Cover makes
  // its other rows there, not in a band (bands slide down and overlap, so the rows it makes
  // follow on). Once `whole` is complete, Cover makes no level below s.
  void KeepWhole(int s, Plane* whole, int rows_made) {
    whole_s_ = s;
    whole_ = whole;
    whole_made_ = rows_made;
  }

  // Makes level s_min + i hold (at least) rows need[i], and every level below it the rows the
  // smoothing reads.
  void Cover(std::vector<Rows> need) {
    const int top = g_.s_min + int(need.size()) - 1;
    for (int s = top; s > g_.s_min; --s) {
      Rows& below = need[size_t(s - 1 - g_.s_min)];
      below = Union(below, Widen(need[size_t(s - g_.s_min)], HalfWidth(LevelSigma(s)), h));
    }
    if (whole_ && whole_made_ == h) {
      for (int s = whole_s_ + 1; s <= top; ++s) SmoothLevel(s, need[size_t(s - g_.s_min)]);
      return;
    }
    const Rows first = need[0];
    if (!first.empty() && doubled_) {
      const Rows up = base_sigma_ > 0 ? Widen(first, HalfWidth(base_sigma_), h) : first;
      UpsampleRows(source_, &doubled_band_, {Slide(&doubled_band_, w, h, up, pool_), up.hi}, pool_);
    }
    if (!first.empty() && base_sigma_ > 0) {
      const Plane& base = doubled_ ? doubled_band_ : source_;
      Smooth(base, &bands_[0], base_sigma_, {Slide(&bands_[0], w, h, first, pool_), first.hi},
             pool_);
    }
    for (int s = g_.s_min + 1; s <= top; ++s) SmoothLevel(s, need[size_t(s - g_.s_min)]);
  }

  const Plane& Level(int s) const {
    if (whole_ && s == whole_s_) return *whole_;
    if (s > g_.s_min || base_sigma_ > 0) return bands_[size_t(s - g_.s_min)];
    return doubled_ ? doubled_band_ : source_;
  }

 private:
  // Level s's rows `rows` from level s - 1's.
  void SmoothLevel(int s, Rows rows) {
    if (rows.empty()) return;
    if (whole_ && s == whole_s_) {
      const int from = std::max(rows.lo, whole_made_);
      if (from < rows.hi) Smooth(Level(s - 1), whole_, LevelSigma(s), {from, rows.hi}, pool_);
      whole_made_ = std::max(whole_made_, rows.hi);
      return;
    }
    Plane* band = &bands_[size_t(s - g_.s_min)];
    Smooth(Level(s - 1), band, LevelSigma(s), {Slide(band, w, h, rows, pool_), rows.hi}, pool_);
  }

  // Level s is level s - 1 smoothed by this.
  double LevelSigma(int s) const { return g_.dsigma0 * std::pow(g_.sigmak, s); }

  const Geometry& g_;
  const Plane& source_;
  const bool doubled_;
  const double base_sigma_;
  WorkerPool& pool_;

 public:
  const int w, h;

 private:
  Plane doubled_band_;
  std::vector<Plane> bands_;  // [s - s_min]
  int whole_s_ = 0;
  Plane* whole_ = nullptr;
  int whole_made_ = 0;
};

// Rows per band: bands of 128 rows compute about 1.5x the rows of the band for the lowest level
// (its halo), once each, and give each parallel pass a few tasks per thread.
constexpr int kBandRows = 128;

}  // namespace cwloc::sift_internal
