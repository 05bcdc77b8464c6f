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
// docs/sift.md has the measurements.
#include "photo/sift/sift_cwloc.h"

extern "C" {
#include <vl/mathop.h>
}

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <stdexcept>

#include "format/base/parallel_for.h"
#include "photo/sift/sift_kernels.h"
#include "photo/sift/sift_levels.h"

namespace cwloc::sift_internal {
namespace {

constexpr int kNumBinsPerSide = 4;  // VLFeat's NBP
constexpr int kNumAngleBins = 8;    // VLFeat's NBO
constexpr double kMagnif = 3.0;

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

  static std::unique_ptr<float[], Free> Allocate(size_t n) {
    constexpr size_t kAlignment = 64;
    void* p = std::aligned_alloc(kAlignment,
                                 (n * sizeof(float) + kAlignment - 1) / kAlignment * kAlignment);
    if (!p) throw std::bad_alloc();
    return std::unique_ptr<float[], Free>(static_cast<float*>(p));
  }
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
Rows Widen(Rows r, int by, int h) {
  return r.empty() ? r : Rows{std::max(r.lo - by, 0), std::min(r.hi + by, h)};
}
Rows Union(Rows a, Rows b) {
  if (a.empty()) return b;
  if (b.empty()) return a;
  return {std::min(a.lo, b.lo), std::max(a.hi, b.hi)};
}

// Copies `rows` rows of `w` floats from src to dst; in parallel when the two do not overlap.
void MoveRows(float* dst, const float* src, int rows, int w, WorkerPool& pool) {
  const size_t row_bytes = size_t(w) * sizeof(float);
  if (rows <= 0) return;
  if (dst + size_t(rows) * size_t(w) > src && src + size_t(rows) * size_t(w) > dst) {
    std::memmove(dst, src, size_t(rows) * row_bytes);
    return;
  }
  constexpr int kRowsPerTask = 16;
  pool.For(size_t((rows + kRowsPerTask - 1) / kRowsPerTask), [&](size_t task) {
    const int first = int(task) * kRowsPerTask, count = std::min(kRowsPerTask, rows - first);
    std::memcpy(dst + size_t(first) * size_t(w), src + size_t(first) * size_t(w),
                size_t(count) * row_bytes);
  });
}

// Makes `band` (a w x h image's rows) hold rows `want`, keeping the rows it already holds there;
// returns the first row it still has to compute. Bands only slide down the image.
int Slide(Plane* band, int w, int h, Rows want, WorkerPool& pool) {
  const bool same = band->w == w && band->h == h;
  const int kept = same && want.lo >= band->y0 && want.lo < band->end()
                       ? std::min(want.hi, band->end()) - want.lo
                       : 0;
  const size_t n = size_t(w) * size_t(want.hi - want.lo);
  if (n > band->capacity) {
    Plane bigger;
    bigger.Hold(w, h, want.lo, want.hi - want.lo);
    MoveRows(bigger.data(), band->Row(want.lo), kept, w, pool);
    *band = std::move(bigger);
  } else {
    MoveRows(band->data(), band->Row(want.lo), kept, w, pool);
    band->Hold(w, h, want.lo, want.hi - want.lo);
  }
  return want.lo + kept;
}

// VLFeat's keypoint fields (float position and scale, integer level).
struct Key {
  int o, ix, iy, is;
  float x, y, s, sigma;
};

// VLFeat's smoothing kernel: width max(ceil(4 sigma), 1), taps exp(-d^2/2) with d computed
// in float, normalized by their float sum.
int HalfWidth(double sigma) { return std::max(int(std::ceil(4.0 * sigma)), 1); }

std::vector<float> GaussianKernel(double sigma) {
  const int half = HalfWidth(sigma);
  std::vector<float> kernel(size_t(2 * half + 1));
  float sum = 0;
  for (int j = 0; j < 2 * half + 1; ++j) {
    const float d = float(j - half) / float(sigma);
    kernel[size_t(j)] = float(std::exp(-0.5 * (d * d)));
    sum += kernel[size_t(j)];
  }
  for (float& k : kernel) k /= sum;
  return kernel;
}

// Rows `rows` of `in` smoothed with VLFeat's Gaussian into `out` (which holds them): first
// along columns, then along rows, each output pixel summing its taps from the first (top/left)
// to the last with the edge pixel repeated, exactly VLFeat's vl_imconvcol_vf order; vectorized
// across the pixels of a row. `in` holds rows `rows` widened by HalfWidth(sigma).
void Smooth(const Plane& in, Plane* out, double sigma, Rows rows, WorkerPool& pool) {
  const std::vector<float> kernel = GaussianKernel(sigma);
  const int half = int(kernel.size() / 2);
  const int w = in.w, h = in.h;
  constexpr int kRowsPerTask = 16;
  const int num_tasks = (rows.hi - rows.lo + kRowsPerTask - 1) / kRowsPerTask;
  const int taps = int(kernel.size());
  constexpr int kGroup = kConvolveRowsAtOnce;
  static_assert(kRowsPerTask % kGroup == 0);
  pool.For(size_t(std::max(num_tasks, 0)), [&](size_t task) {
    // The column pass of kGroup rows at once lands in the middle of `padded`, which repeats
    // each row's edge pixels `half` times on both sides for the row pass.
    const size_t padded_w = size_t(w + 2 * half);
    std::vector<float> padded(kGroup * padded_w);
    std::vector<const float*> taps_rows(kernel.size() + kGroup - 1);
    const int y_begin = rows.lo + int(task) * kRowsPerTask;
    const int y_end = std::min(rows.hi, y_begin + kRowsPerTask);
    for (int y = y_begin; y < y_end; y += kGroup) {
      const int n = std::min(kGroup, y_end - y);
      for (int k = 0; k < taps + n - 1; ++k) {
        taps_rows[size_t(k)] = in.Row(std::clamp(y - half + k, 0, h - 1));
      }
      float* columns[kGroup];
      for (int j = 0; j < n; ++j) columns[j] = padded.data() + size_t(j) * padded_w + half;
      ConvolveTapsRows(taps_rows.data(), kernel.data(), taps, w, n, columns);
      for (int j = 0; j < n; ++j) {
        float* a = columns[j];
        std::fill(a - half, a, a[0]);
        std::fill(a + w, a + w + half, a[w - 1]);
        for (int k = 0; k < taps; ++k) taps_rows[size_t(k)] = a - half + k;
        ConvolveTaps(taps_rows.data(), kernel.data(), taps, w, out->Row(y + j));
      }
    }
  });
}

// Rows `rows` of `in` doubled in both sides, as VLFeat's copy_and_upsample_rows applied twice
// makes them: the new pixels the means of their neighbours (along rows first), the last row and
// column repeated.
void UpsampleRows(const Plane& in, Plane* out, Rows rows, WorkerPool& pool) {
  const int w = in.w, h = in.h;
  auto double_row = [&](int y, float* dst) {
    const float* src = in.Row(y);
    for (int x = 0; x + 1 < w; ++x) {
      dst[2 * x] = src[x];
      dst[2 * x + 1] = float(0.5 * (src[x] + src[x + 1]));
    }
    dst[2 * w - 2] = dst[2 * w - 1] = src[w - 1];
  };
  constexpr int kRowsPerTask = 16;
  pool.For(size_t(std::max(rows.hi - rows.lo + kRowsPerTask - 1, 0) / kRowsPerTask),
           [&](size_t task) {
             std::vector<float> a(size_t(2 * w)), b(size_t(2 * w));
             const int y_begin = rows.lo + int(task) * kRowsPerTask;
             for (int y2 = y_begin; y2 < std::min(rows.hi, y_begin + kRowsPerTask); ++y2) {
               const int y = y2 / 2;
               float* dst = out->Row(y2);
               if (y2 % 2 == 0 || y + 1 >= h) {
                 double_row(y, dst);
                 continue;
               }
               double_row(y, a.data());
               double_row(y + 1, b.data());
               for (int x = 0; x < 2 * w; ++x) dst[x] = float(0.5 * (a[size_t(x)] + b[size_t(x)]));
             }
           });
}

// Every 2^d-th pixel of every 2^d-th row, from (0, 0), of `in`'s rows `rows` into the w x h
// plane `out`.
void DownsampleRows(const Plane& in, int d, Rows rows, Plane* out) {
  const int step = 1 << d;
  for (int y = (rows.lo + step - 1) / step; y * step < rows.hi && y < out->h; ++y) {
    const float* src = in.Row(y * step);
    float* dst = out->Row(y);
    for (int x = 0; x < out->w; ++x) dst[x] = src[size_t(x) * size_t(step)];
  }
}

struct Geometry {
  int S, s_min, s_max, o_min, O;
  double sigma0, sigmak, sigman, dsigma0;
};

Geometry MakeGeometry(const SiftOptions& options) {
  Geometry g;
  g.S = options.octave_resolution;
  g.s_min = -1;
  g.s_max = g.S + 1;
  g.o_min = options.first_octave;
  g.O = options.num_octaves;
  g.sigman = 0.5;
  g.sigmak = std::pow(2.0, 1.0 / g.S);
  g.sigma0 = 1.6 * g.sigmak;
  g.dsigma0 = g.sigma0 * std::sqrt(1.0 - 1.0 / (g.sigmak * g.sigmak));
  return g;
}

int ShiftLeft(int x, int n) { return n >= 0 ? x << n : x >> -n; }

// Refinement moves a candidate by at most this many rows and reads one more either side.
constexpr int kDetectionReach = 6;

// Candidates on rows `rows` (within 1 .. h - 2) and their refined keypoints, of DoG level s, in
// VLFeat's order (rows, then columns); appends to `keys`. gauss holds the Gaussian levels
// s-1 .. s+2, each on rows `rows` widened by kDetectionReach: DoG level t is G(t + 1) - G(t),
// computed where it is read (the same float subtraction VLFeat stores), so no DoG is held.
void DetectLevel(const Plane* gauss[4], int s, int o, const Geometry& g, double tp, double te,
                 Rows rows, WorkerPool& pool, std::vector<Key>* keys) {
  const int w = gauss[1]->w, h = gauss[1]->h;
  const double xper = std::pow(2.0, o);
  const float prefilter = float(0.8 * tp) * (1 - 1e-6f);
  const double low = 0.8 * tp;
  std::vector<std::vector<Key>> row_keys(size_t(std::max(rows.hi - rows.lo, 0)));
  const ptrdiff_t xo = 1, yo = w;
  // Level k's pixel at image index i is at[k][i - first[k]].
  const float* at_level[4];
  ptrdiff_t first[4];
  for (int k = 0; k < 4; ++k) {
    at_level[k] = gauss[k]->data();
    first[k] = ptrdiff_t(gauss[k]->y0) * yo;
  }
  // DoG level s + ds (ds in -1, 0, 1) at image index i.
  auto dog = [&](int ds, ptrdiff_t i) {
    return at_level[ds + 2][i - first[ds + 2]] - at_level[ds + 1][i - first[ds + 1]];
  };
  pool.For(row_keys.size(), [&](size_t task) {
    const int y0 = rows.lo + int(task);
    std::vector<Key>& out = row_keys[task];
    thread_local std::vector<int32_t> candidates;
    candidates.resize(size_t(w));
    const float* around[4][3];  // levels s - 1 .. s + 2, rows y0 - 1 .. y0 + 1
    for (int t = 0; t < 4; ++t) {
      for (int r = 0; r < 3; ++r) around[t][r] = gauss[t]->Row(y0 - 1 + r);
    }
    const int num_candidates = FindExtremumCandidates(around, w, prefilter, candidates.data());
    for (int c = 0; c < num_candidates; ++c) {
      const int x0 = candidates[size_t(c)];
      const float v = around[2][1][x0] - around[1][1][x0];
      const ptrdiff_t centre = ptrdiff_t(y0) * yo + x0;
      auto extremum = [&](auto cmp) {
        for (int ds : {0, 1, -1}) {
          for (ptrdiff_t dy : {-yo, ptrdiff_t(0), yo}) {
            for (ptrdiff_t dx : {-xo, ptrdiff_t(0), xo}) {
              if (ds == 0 && dy == 0 && dx == 0) continue;
              if (!cmp(v, dog(ds, centre + dy + dx))) return false;
            }
          }
        }
        return true;
      };
      const bool is_max = v >= +low && extremum([](float a, float b) { return a > b; });
      const bool is_min = !is_max && v <= -low && extremum([](float a, float b) { return a < b; });
      if (!is_max && !is_min) continue;

      // VLFeat's refinement: up to 5 Newton steps, moving by one pixel when the offset
      // exceeds 0.6; then the peak, edge and offset tests.
      int x = x0, y = y0, dx = 0, dy = 0;
      double Dx = 0, Dy = 0, Ds = 0, Dxx = 0, Dyy = 0, Dss = 0, Dxy = 0, Dxs = 0, Dys = 0;
      double b[3] = {0, 0, 0};
      ptrdiff_t at_index = 0;
      auto at = [&](int ddx, int ddy, int dds) { return dog(dds, at_index + ddx * xo + ddy * yo); };
      for (int iter = 0; iter < 5; ++iter) {
        x += dx;
        y += dy;
        at_index = ptrdiff_t(y) * yo + x;
        Dx = 0.5 * (at(+1, 0, 0) - at(-1, 0, 0));
        Dy = 0.5 * (at(0, +1, 0) - at(0, -1, 0));
        Ds = 0.5 * (at(0, 0, +1) - at(0, 0, -1));
        Dxx = (at(+1, 0, 0) + at(-1, 0, 0) - 2.0 * at(0, 0, 0));
        Dyy = (at(0, +1, 0) + at(0, -1, 0) - 2.0 * at(0, 0, 0));
        Dss = (at(0, 0, +1) + at(0, 0, -1) - 2.0 * at(0, 0, 0));
        Dxy = 0.25 * (at(+1, +1, 0) + at(-1, -1, 0) - at(-1, +1, 0) - at(+1, -1, 0));
        Dxs = 0.25 * (at(+1, 0, +1) + at(-1, 0, -1) - at(-1, 0, +1) - at(+1, 0, -1));
        Dys = 0.25 * (at(0, +1, +1) + at(0, -1, -1) - at(0, -1, +1) - at(0, +1, -1));
        // Solve A b = -D by Gaussian elimination with partial pivoting (A column-major).
        double A[9] = {Dxx, Dxy, Dxs, Dxy, Dyy, Dys, Dxs, Dys, Dss};
        auto Aat = [&](int i, int j) -> double& { return A[i + j * 3]; };
        b[0] = -Dx;
        b[1] = -Dy;
        b[2] = -Ds;
        for (int j = 0; j < 3; ++j) {
          double maxa = 0, maxabsa = 0;
          int maxi = -1;
          for (int i = j; i < 3; ++i) {
            const double a = Aat(i, j);
            const double absa = std::abs(a);
            if (absa > maxabsa) {
              maxa = a;
              maxabsa = absa;
              maxi = i;
            }
          }
          if (maxabsa < 1e-10f) {
            b[0] = b[1] = b[2] = 0;
            break;
          }
          const int i = maxi;
          for (int jj = j; jj < 3; ++jj) {
            std::swap(Aat(i, jj), Aat(j, jj));
            Aat(j, jj) /= maxa;
          }
          std::swap(b[j], b[i]);
          b[j] /= maxa;
          for (int ii = j + 1; ii < 3; ++ii) {
            const double f = Aat(ii, j);
            for (int jj = j; jj < 3; ++jj) Aat(ii, jj) -= f * Aat(j, jj);
            b[ii] -= f * b[j];
          }
        }
        for (int i = 2; i > 0; --i) {
          const double f = b[i];
          for (int ii = i - 1; ii >= 0; --ii) b[ii] -= f * Aat(ii, i);
        }
        dx = ((b[0] > 0.6 && x < w - 2) ? 1 : 0) + ((b[0] < -0.6 && x > 1) ? -1 : 0);
        dy = ((b[1] > 0.6 && y < h - 2) ? 1 : 0) + ((b[1] < -0.6 && y > 1) ? -1 : 0);
        if (dx == 0 && dy == 0) break;
      }
      const double val = at(0, 0, 0) + 0.5 * (Dx * b[0] + Dy * b[1] + Ds * b[2]);
      const double score = (Dxx + Dyy) * (Dxx + Dyy) / (Dxx * Dyy - Dxy * Dxy);
      const double xn = x + b[0], yn = y + b[1], sn = s + b[2];
      const bool good = std::abs(val) > tp && score < (te + 1) * (te + 1) / te && score >= 0 &&
                        std::abs(b[0]) < 1.5 && std::abs(b[1]) < 1.5 && std::abs(b[2]) < 1.5 &&
                        xn >= 0 && xn <= w - 1 && yn >= 0 && yn <= h - 1 && sn >= g.s_min &&
                        sn <= g.s_max;
      if (good) {
        out.push_back({o, x, y, s, float(xn * xper), float(yn * xper), float(sn),
                       float(g.sigma0 * std::pow(2.0, sn / g.S) * xper)});
      }
    }
  });
  for (auto& row : row_keys) keys->insert(keys->end(), row.begin(), row.end());
}

// VLFeat's update_gradient for one level: per pixel (modulus, angle in [0, 2 pi)), central
// differences inside, one-sided at the borders; the modulus by VLFeat's fast sqrt and the
// angle by its fast atan2.
struct GradientPlanes {
  Plane mod, angle;
};

// Rows `rows` of the gradient (held by grad) from `level` (holding them widened by one).
void Gradient(const Plane& level, Rows rows, GradientPlanes* grad, WorkerPool& pool) {
  const int h = level.h;
  pool.For(size_t(std::max(rows.hi - rows.lo, 0)), [&](size_t row) {
    const int y = rows.lo + int(row);
    GradientRow(y > 0 ? level.Row(y - 1) : nullptr, level.Row(y),
                y < h - 1 ? level.Row(y + 1) : nullptr, level.w, grad->mod.Row(y),
                grad->angle.Row(y));
  });
}

// The window radii (pixels of the keypoint's octave) of VLFeat's orientation histogram and
// descriptor.
// VLFeat's floor(3 * sigmaw), sigmaw = 1.5 sigma rounded first.
int OrientationRadius(double sigma) { return std::max(int(std::floor(3.0 * (1.5 * sigma))), 1); }
double DescriptorBinSize(double sigma) { return kMagnif * sigma + VL_EPSILON_D; }
int DescriptorRadius(double sigma) {
  return int(
      std::floor(std::sqrt(2.0) * DescriptorBinSize(sigma) * (kNumBinsPerSide + 1) / 2.0 + 0.5));
}

// The keypoint's row in its octave, and how many rows either side its orientations and
// descriptors read.
int KeyRow(const Key& k) { return int(k.y / std::pow(2.0, k.o) + 0.5); }
int KeyReach(const Key& k) {
  const double sigma = k.sigma / std::pow(2.0, k.o);
  return std::max(OrientationRadius(sigma), DescriptorRadius(sigma));
}

// VLFeat's vl_sift_calc_keypoint_orientations on the gradient of the keypoint's level, which
// holds the rows KeyReach(k) either side of KeyRow(k).
int Orientations(const Key& k, const GradientPlanes& grad, double angles[4]) {
  const int w = grad.mod.w, h = grad.mod.h;
  const double xper = std::pow(2.0, k.o);
  const double x = k.x / xper, y = k.y / xper, sigma = k.sigma / xper;
  const int xi = int(x + 0.5), yi = int(y + 0.5);
  const double sigmaw = 1.5 * sigma;
  const int W = OrientationRadius(sigma);
  constexpr int nbins = 36;
  if (xi < 0 || xi > w - 1 || yi < 0 || yi > h - 1) return 0;
  double hist[nbins] = {};
  const FastExpn& expn = FastExpn::Get();
  const float* pt_mod = grad.mod.Row(yi) + xi;
  const float* pt_angle = grad.angle.Row(yi) + xi;
  for (int ys = std::max(-W, -yi); ys <= std::min(W, h - 1 - yi); ++ys) {
    for (int xs = std::max(-W, -xi); xs <= std::min(W, w - 1 - xi); ++xs) {
      const double dx = double(xi + xs) - x;
      const double dy = double(yi + ys) - y;
      const double r2 = dx * dx + dy * dy;
      if (r2 >= W * W + 0.6) continue;
      const double wgt = expn(r2 / (2 * sigmaw * sigmaw));
      const ptrdiff_t off = ptrdiff_t(ys) * w + xs;
      const double mod = pt_mod[off];
      const double ang = pt_angle[off];
      // VLFeat's sift.c defines VL_SIFT_BILINEAR_ORIENTATIONS: split between two bins.
      const double fbin = nbins * ang / (2 * VL_PI);
      const int bin = int(vl_floor_d(fbin - 0.5));
      const double rbin = fbin - bin - 0.5;
      hist[(bin + nbins) % nbins] += (1 - rbin) * mod * wgt;
      hist[(bin + 1) % nbins] += (rbin)*mod * wgt;
    }
  }
  for (int iter = 0; iter < 6; ++iter) {
    double prev = hist[nbins - 1];
    const double first = hist[0];
    int i;
    for (i = 0; i < nbins - 1; i++) {
      const double newh = (prev + hist[i] + hist[(i + 1) % nbins]) / 3.0;
      prev = hist[i];
      hist[i] = newh;
    }
    hist[i] = (prev + hist[i] + first) / 3.0;
  }
  double maxh = 0;
  for (double v : hist) maxh = std::max(maxh, v);
  int n = 0;
  for (int i = 0; i < nbins; ++i) {
    const double h0 = hist[i];
    const double hm = hist[(i - 1 + nbins) % nbins];
    const double hp = hist[(i + 1 + nbins) % nbins];
    if (h0 > 0.8 * maxh && h0 > hm && h0 > hp) {
      const double di = -0.5 * (hp - hm) / (hp + hm - 2 * h0);
      angles[n++] = 2 * VL_PI * (i + di + 0.5) / nbins;
      if (n == 4) break;
    }
  }
  return n;
}

float NormalizeHistogram(float* begin, float* end) {
  float norm = 0.0f;
  for (float* it = begin; it != end; ++it) norm += (*it) * (*it);
  norm = vl_fast_sqrt_f(norm) + VL_EPSILON_F;
  for (float* it = begin; it != end; ++it) *it /= norm;
  return norm;
}

// VLFeat's vl_sift_calc_keypoint_descriptor: the per-pixel terms from DescribeSamples, added
// in VLFeat's order; pixels whose rotated position lies outside every spatial bin (they would
// add nothing) are skipped before any other work.
void Descriptor(const Key& k, double angle0, const GradientPlanes& grad, float* descr) {
  const int w = grad.mod.w, h = grad.mod.h;
  const double xper = std::pow(2.0, k.o);
  const double x = k.x / xper, y = k.y / xper, sigma = k.sigma / xper;
  const int xi = int(x + 0.5), yi = int(y + 0.5);
  const double st0 = std::sin(angle0), ct0 = std::cos(angle0);
  const double SBP = DescriptorBinSize(sigma);
  const int W = DescriptorRadius(sigma);
  std::fill(descr, descr + kSiftDescriptorDim, 0.0f);
  if (xi < 0 || xi >= w || yi < 0 || yi >= h - 1) return;
  const float* pt_mod = grad.mod.Row(yi) + xi;
  const float* pt_angle = grad.angle.Row(yi) + xi;
  DescriptorHistogram hist;
  hist.Clear();
  // |n| >= 2.5 puts every one of a sample's bins outside [-2, 2): it adds nothing. Per row,
  // the columns whose rotated position can fall inside |n| < 2.5, from the two slabs
  // |ct0 dx + st0 dy| < R and |-st0 dx + ct0 dy| < R (R = 2.5 SBP), widened by a pixel: a
  // cheap superset; DescribeSamples's exact test still decides.
  const double R = 2.5 * SBP;
  DescriptorSamples samples;
  auto slab = [](double a, double c, double r, double* lo, double* hi) {
    // {dx : |a dx + c| < r}
    if (std::abs(a) < 1e-9) {
      if (std::abs(c) >= r + 1e-9) *lo = 1, *hi = -1;
      return;
    }
    const double u = (-r - c) / a, v = (r - c) / a;
    *lo = std::max(*lo, std::min(u, v));
    *hi = std::min(*hi, std::max(u, v));
  };
  for (int dyi = std::max(-W, 1 - yi); dyi <= std::min(W, h - yi - 2); ++dyi) {
    const double dyd = yi + dyi - y;
    double lo = -1e300, hi = 1e300;
    slab(ct0, st0 * dyd, R, &lo, &hi);
    slab(-st0, ct0 * dyd, R, &lo, &hi);
    if (lo > hi) continue;
    const int first = std::max({-W, 1 - xi, int(std::floor(lo + x - xi)) - 1});
    const int last = std::min({W, w - xi - 2, int(std::ceil(hi + x - xi)) + 1});
    DescriptorRow row{xi + first, x, float(yi + dyi - y), ct0, st0, SBP, angle0};
    for (int dxi = first; dxi <= last; dxi += DescriptorSamples::kMax) {
      const int count = std::min(last - dxi + 1, DescriptorSamples::kMax);
      const ptrdiff_t off = ptrdiff_t(dyi) * w + dxi;
      row.first_x = xi + dxi;
      DescribeSamples(row, pt_mod + off, pt_angle + off, count, &samples);
      AccumulateSamples(samples, count, &hist);
    }
  }
  hist.CopyInnerTo(descr);
  NormalizeHistogram(descr, descr + kSiftDescriptorDim);
  for (int bin = 0; bin < kSiftDescriptorDim; ++bin) descr[bin] = std::min(descr[bin], 0.2f);
  NormalizeHistogram(descr, descr + kSiftDescriptorDim);
}

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

  // Level s is `whole` (the whole level, made before): Cover then makes no level up to s.
  void Give(int s, const Plane* whole) {
    given_s_ = s;
    given_ = whole;
  }

  // Makes level s_min + i hold (at least) rows need[i], and every level below it the rows the
  // smoothing reads.
  void Cover(std::vector<Rows> need) {
    const int top = g_.s_min + int(need.size()) - 1;
    for (int s = top; s > g_.s_min; --s) {
      Rows& below = need[size_t(s - 1 - g_.s_min)];
      below = Union(below, Widen(need[size_t(s - g_.s_min)], HalfWidth(LevelSigma(s)), h));
    }
    if (given_) {
      for (int s = given_s_ + 1; s <= top; ++s) SmoothLevel(s, need[size_t(s - g_.s_min)]);
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
    if (given_ && s == given_s_) return *given_;
    if (s > g_.s_min || base_sigma_ > 0) return bands_[size_t(s - g_.s_min)];
    return doubled_ ? doubled_band_ : source_;
  }

 private:
  // Level s's rows `rows` from level s - 1's.
  void SmoothLevel(int s, Rows rows) {
    if (rows.empty()) return;
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
  int given_s_ = 0;
  const Plane* given_ = nullptr;
};

// Rows per band: bands of 128 rows compute about 1.5x the rows of the band for the lowest level
// (its halo), once each, and give each parallel pass a few tasks per thread.
constexpr int kBandRows = 128;

// What an octave's levels are made from.
struct OctaveSource {
  int o;
  Plane plane;  // the photo (first octave) or the octave below's level s_min + S, downsampled
  bool doubled;
  double base_sigma;
  // The first octave's level kKeptLevel, whole, when it fits kMaxKeptLevelBytes: describing
  // keypoints of that level or above then makes their levels from it, not from the photo.
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
    if (keep_level) current.kept_level.Resize(w, h);
    OctaveLevels levels(g, current.plane, current.doubled, current.base_sigma, pool);
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
      if (keep_level) {
        MoveRows(current.kept_level.Row(band.lo), levels.Level(kKeptLevel).Row(band.lo),
                 band.hi - band.lo, w, pool);
      }
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
void DescribeOctave(const std::vector<Key>& keys, size_t begin, size_t end,
                    const OctaveSource& source, const Geometry& g, const SiftOptions& options,
                    WorkerPool& pool, int slots, KeyAngles* angles, uint8_t* descriptors) {
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
    levels.Give(kKeptLevel, &source.kept_level);
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
