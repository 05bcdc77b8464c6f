// SiftOptions::Implementation::kCwloc: our own implementation of the algorithm VLFeat's
// sift.c runs (Lowe's SIFT as VLFeat documents it), written so that every float operation a
// pixel sees happens in VLFeat's order and precision. It is faster because of how it computes,
// never what:
//  - separable Gaussian smoothing streamed row by row, vectorized across pixels (VLFeat
//    convolves one column at a time through a transposed temporary image);
//  - DoG levels computed three at a time, the candidate scan rejecting on |DoG| first;
//  - detection runs over all octaves first; orientations and descriptors are computed only
//    for the DoG levels COLMAP's max_num_features rule keeps (COLMAP describes every level
//    and then drops the finest ones), and gradients only for the levels that need them;
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

#if defined(__linux__)
#include <sys/mman.h>
#endif

#include "format/base/parallel_for.h"
#include "photo/sift/sift_kernels.h"
#include "photo/sift/sift_levels.h"

namespace cwloc::sift_internal {
namespace {

constexpr int kNumBinsPerSide = 4;  // VLFeat's NBP
constexpr int kNumAngleBins = 8;    // VLFeat's NBO
constexpr double kMagnif = 3.0;

// A single-channel float image, row-major. Resize keeps the storage when it is large enough
// and never initializes pixels: each is written before it is read.
struct Plane {
  int w = 0, h = 0;
  size_t capacity = 0;
  struct Free {
    void operator()(float* p) const { std::free(p); }
  };
  std::unique_ptr<float[], Free> storage;

  // Large planes are 2 MiB aligned and ask for transparent huge pages: one page fault per
  // 2 MiB instead of per 4 KiB (page faults were a third of the time).
  static std::unique_ptr<float[], Free> Allocate(size_t n) {
    constexpr size_t kHuge = size_t{2} << 20;
    const size_t bytes = n * sizeof(float);
    if (bytes < kHuge) return std::unique_ptr<float[], Free>(new_floats(bytes, 64));
    const size_t rounded = (bytes + kHuge - 1) / kHuge * kHuge;
    float* p = new_floats(rounded, kHuge);
#ifdef MADV_HUGEPAGE
    madvise(p, rounded, MADV_HUGEPAGE);
#endif
    return std::unique_ptr<float[], Free>(p);
  }
  static float* new_floats(size_t bytes, size_t alignment) {
    void* p = std::aligned_alloc(alignment, (bytes + alignment - 1) / alignment * alignment);
    if (!p) throw std::bad_alloc();
    return static_cast<float*>(p);
  }
  void Resize(int width, int height) {
    w = width;
    h = height;
    if (size() > capacity) {
      storage = Allocate(size());
      capacity = size();
    }
  }
  size_t size() const { return size_t(w) * size_t(h); }
  float* data() { return storage.get(); }
  const float* data() const { return storage.get(); }
  float* Row(int y) { return data() + size_t(y) * size_t(w); }
  const float* Row(int y) const { return data() + size_t(y) * size_t(w); }
};

// Planes handed back for reuse: a photo touches fresh memory only for the planes alive at
// the same time (fresh pages cost a page fault each and are zeroed by the kernel).
class PlanePool {
 public:
  Plane Take(int w, int h) {
    const size_t n = size_t(w) * size_t(h);
    size_t best = free_.size();
    for (size_t i = 0; i < free_.size(); ++i) {
      if (free_[i].capacity >= n &&
          (best == free_.size() || free_[i].capacity < free_[best].capacity)) {
        best = i;
      }
    }
    Plane plane;
    if (best < free_.size()) {
      plane = std::move(free_[best]);
      free_.erase(free_.begin() + ptrdiff_t(best));
    }
    plane.Resize(w, h);
    return plane;
  }
  void Give(Plane&& plane) {
    if (plane.capacity > 0) free_.push_back(std::move(plane));
    plane = Plane();
  }

 private:
  std::vector<Plane> free_;
};

// VLFeat's keypoint fields (float position and scale, integer level).
struct Key {
  int o, ix, iy, is;
  float x, y, s, sigma;
};

// VLFeat's smoothing kernel: width max(ceil(4 sigma), 1), taps exp(-d^2/2) with d computed
// in float, normalized by their float sum.
std::vector<float> GaussianKernel(double sigma) {
  const int half = std::max(int(std::ceil(4.0 * sigma)), 1);
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

// out = in smoothed with VLFeat's Gaussian: first along columns, then along rows, each output
// pixel summing its taps from the first (top/left) to the last with the edge pixel repeated,
// exactly VLFeat's vl_imconvcol_vf order; vectorized across the pixels of a row.
void Smooth(const Plane& in, Plane* out, double sigma, int num_threads) {
  // Callers hand in a plane from their pool; it is sized here.
  const std::vector<float> kernel = GaussianKernel(sigma);
  const int half = int(kernel.size() / 2);
  const int w = in.w, h = in.h;
  out->Resize(w, h);
  constexpr int kRowsPerTask = 16;
  const int num_tasks = (h + kRowsPerTask - 1) / kRowsPerTask;
  const int taps = int(kernel.size());
  ParallelFor(size_t(num_tasks), num_threads, [&](size_t task) {
    // The column pass lands in the middle of `padded`, which repeats its edge pixels `half`
    // times on both sides for the row pass.
    std::vector<float> padded(static_cast<size_t>(w + 2 * half));
    std::vector<const float*> rows(kernel.size());
    const int y_end = std::min(h, int(task + 1) * kRowsPerTask);
    for (int y = int(task) * kRowsPerTask; y < y_end; ++y) {
      for (int k = 0; k < taps; ++k) rows[size_t(k)] = in.Row(std::clamp(y - half + k, 0, h - 1));
      float* a = padded.data() + half;
      ConvolveTaps(rows.data(), kernel.data(), taps, w, a);
      std::fill(padded.data(), a, a[0]);
      std::fill(a + w, a + w + half, a[w - 1]);
      for (int k = 0; k < taps; ++k) rows[size_t(k)] = padded.data() + k;
      ConvolveTaps(rows.data(), kernel.data(), taps, w, out->Row(y));
    }
  });
}

// VLFeat's copy_and_upsample_rows applied twice: doubles both sides, the new pixels the
// means of their neighbours (along rows first), the last row and column repeated.
Plane Upsample(const Plane& in, PlanePool* pool) {
  const int w = in.w, h = in.h;
  Plane rows = pool->Take(2 * w, h);  // each row upsampled
  for (int y = 0; y < h; ++y) {
    const float* src = in.Row(y);
    float* dst = rows.Row(y);
    for (int x = 0; x + 1 < w; ++x) {
      dst[2 * x] = src[x];
      dst[2 * x + 1] = float(0.5 * (src[x] + src[x + 1]));
    }
    dst[2 * w - 2] = dst[2 * w - 1] = src[w - 1];
  }
  Plane out = pool->Take(2 * w, 2 * h);
  for (int y = 0; y < h; ++y) {
    const float* a = rows.Row(y);
    const float* b = rows.Row(std::min(y + 1, h - 1));
    std::copy(a, a + 2 * w, out.Row(2 * y));
    float* mid = out.Row(2 * y + 1);
    if (y + 1 < h) {
      for (int x = 0; x < 2 * w; ++x) mid[x] = float(0.5 * (a[x] + b[x]));
    } else {
      std::copy(a, a + 2 * w, mid);
    }
  }
  pool->Give(std::move(rows));
  return out;
}

// Every 2^d-th pixel of every 2^d-th row, from (0, 0), into a w x h plane.
Plane Downsample(const Plane& in, int d, int w, int h, PlanePool* pool) {
  const int step = 1 << d;
  Plane out = pool->Take(w, h);
  for (int y = 0; y < h; ++y) {
    const float* src = in.Row(y * step);
    float* dst = out.Row(y);
    for (int x = 0; x < w; ++x) dst[x] = src[size_t(x) * size_t(step)];
  }
  return out;
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

// Candidates and refined keypoints of DoG level s, in VLFeat's order (rows, then columns);
// appends to `keys`. gauss holds the Gaussian levels s-1 .. s+2: DoG level t is
// G(t + 1) - G(t), computed where it is read (the same float subtraction VLFeat stores), so no
// DoG plane is held.
void DetectLevel(const Plane* gauss[4], int s, int o, const Geometry& g, double tp, double te,
                 int num_threads, std::vector<Key>* keys) {
  const int w = gauss[1]->w, h = gauss[1]->h;
  const double xper = std::pow(2.0, o);
  const float prefilter = float(0.8 * tp) * (1 - 1e-6f);
  const double low = 0.8 * tp;
  std::vector<std::vector<Key>> row_keys(size_t(std::max(h, 0)));
  const ptrdiff_t xo = 1, yo = w;
  // DoG level s + ds (ds in -1, 0, 1) at pixel index i.
  auto dog = [gauss](int ds, ptrdiff_t i) {
    return gauss[ds + 2]->data()[i] - gauss[ds + 1]->data()[i];
  };
  ParallelFor(size_t(std::max(h - 2, 0)), num_threads, [&](size_t task) {
    const int y0 = int(task) + 1;
    std::vector<Key>& out = row_keys[size_t(y0)];
    thread_local std::vector<float> mid;
    thread_local std::vector<int32_t> candidates;
    mid.resize(size_t(w));
    candidates.resize(size_t(w));
    const float* below = gauss[1]->Row(y0);
    const float* above = gauss[2]->Row(y0);
    for (int x = 0; x < w; ++x) mid[size_t(x)] = above[x] - below[x];
    const int num_candidates = FindAtLeast(mid.data(), 1, w - 1, prefilter, candidates.data());
    for (int c = 0; c < num_candidates; ++c) {
      const int x0 = candidates[size_t(c)];
      const float v = mid[size_t(x0)];
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

void Gradient(const Plane& level, GradientPlanes* grad, int num_threads) {
  const int h = level.h;
  ParallelFor(size_t(h), num_threads, [&](size_t row) {
    const int y = int(row);
    GradientRow(y > 0 ? level.Row(y - 1) : nullptr, level.Row(y),
                y < h - 1 ? level.Row(y + 1) : nullptr, level.w, grad->mod.Row(y),
                grad->angle.Row(y));
  });
}

// VLFeat's vl_sift_calc_keypoint_orientations on the gradient of the keypoint's level.
int Orientations(const Key& k, const GradientPlanes& grad, double angles[4]) {
  const int w = grad.mod.w, h = grad.mod.h;
  const double xper = std::pow(2.0, k.o);
  const double x = k.x / xper, y = k.y / xper, sigma = k.sigma / xper;
  const int xi = int(x + 0.5), yi = int(y + 0.5);
  const double sigmaw = 1.5 * sigma;
  const int W = std::max(int(std::floor(3.0 * sigmaw)), 1);
  constexpr int nbins = 36;
  if (xi < 0 || xi > w - 1 || yi < 0 || yi > h - 1) return 0;
  double hist[nbins] = {};
  const FastExpn& expn = FastExpn::Get();
  const size_t centre = size_t(yi) * size_t(w) + size_t(xi);
  const float* pt_mod = grad.mod.data() + centre;
  const float* pt_angle = grad.angle.data() + centre;
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
  const double SBP = kMagnif * sigma + VL_EPSILON_D;
  const int W = int(std::floor(std::sqrt(2.0) * SBP * (kNumBinsPerSide + 1) / 2.0 + 0.5));
  constexpr int binto = 1, binyo = kNumAngleBins * kNumBinsPerSide, binxo = kNumAngleBins;
  std::fill(descr, descr + kSiftDescriptorDim, 0.0f);
  if (xi < 0 || xi >= w || yi < 0 || yi >= h - 1) return;
  const size_t centre = size_t(yi) * size_t(w) + size_t(xi);
  const float* pt_mod = grad.mod.data() + centre;
  const float* pt_angle = grad.angle.data() + centre;
  float* dpt = descr + (kNumBinsPerSide / 2) * binyo + (kNumBinsPerSide / 2) * binxo;
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
      for (int p = 0; p < count; ++p) {
        if (!samples.inside[p]) continue;
        // VLFeat's loop over (dbinx, dbiny, dbint), skipping the spatial bins outside 4 x 4.
        const int binx = samples.binx[p], biny = samples.biny[p], bint = samples.bint[p];
        const int t0 = (bint % kNumAngleBins) * binto, t1 = ((bint + 1) % kNumAngleBins) * binto;
        for (int dbinx = 0; dbinx < 2; ++dbinx) {
          if (binx + dbinx < -(kNumBinsPerSide / 2) || binx + dbinx >= kNumBinsPerSide / 2)
            continue;
          for (int dbiny = 0; dbiny < 2; ++dbiny) {
            if (biny + dbiny < -(kNumBinsPerSide / 2) || biny + dbiny >= kNumBinsPerSide / 2)
              continue;
            float* cell = dpt + (biny + dbiny) * binyo + (binx + dbinx) * binxo;
            const int i = dbinx * 4 + dbiny * 2;
            cell[t0] += samples.weight[i][p];
            cell[t1] += samples.weight[i + 1][p];
          }
        }
      }
    }
  }
  NormalizeHistogram(descr, descr + kSiftDescriptorDim);
  for (int bin = 0; bin < kSiftDescriptorDim; ++bin) descr[bin] = std::min(descr[bin], 0.2f);
  NormalizeHistogram(descr, descr + kSiftDescriptorDim);
}

}  // namespace

SiftFeatures ExtractSiftCwloc(const GreyImage& image, const SiftOptions& options) {
  const Geometry g = MakeGeometry(options);
  const int threads = options.num_threads;
  const double tp = options.peak_threshold, te = options.edge_threshold;
  const int num_levels = g.s_max - g.s_min + 1;
  PlanePool pool;

  // Detection over every octave; the levels orientations may need (s_min+1 .. s_max-2) are
  // kept for later.
  std::vector<Key> keys;
  std::vector<std::vector<Plane>> kept(size_t(g.O));           // [octave][s - s_min - 1]
  std::vector<Plane> levels(static_cast<size_t>(num_levels));  // this octave's, index s - s_min
  for (int oi = 0; oi < g.O; ++oi) {
    const int o = g.o_min + oi;
    const int w = ShiftLeft(int(image.width), -o), h = ShiftLeft(int(image.height), -o);
    if (w < 3 || h < 3) break;  // no pixel with 8 neighbours: VLFeat finds nothing either
    Plane base;
    if (oi == 0) {
      Plane input = pool.Take(int(image.width), int(image.height));
      for (size_t i = 0; i < image.pixels.size(); ++i) {
        input.data()[i] = float(image.pixels[i]) / 255.0f;
      }
      if (o < 0) {
        base = Upsample(input, &pool);  // first_octave < -1 runs VLFeat (sift_extractor.cc)
        pool.Give(std::move(input));
      } else if (o > 0) {
        base = Downsample(input, o, w, h, &pool);
        pool.Give(std::move(input));
      } else {
        base = std::move(input);
      }
      const double sa = g.sigma0 * std::pow(g.sigmak, g.s_min);
      const double sb = g.sigman * std::pow(2.0, -o);
      if (sa > sb) {
        Plane smoothed = pool.Take(w, h);
        Smooth(base, &smoothed, std::sqrt(sa * sa - sb * sb), threads);
        pool.Give(std::move(base));
        base = std::move(smoothed);
      }
    } else {
      const int s_best = std::min(g.s_min + g.S, g.s_max);
      // The level with twice the first level's sigma, moved into kept[oi - 1] by now.
      base = Downsample(kept[size_t(oi - 1)][size_t(s_best - g.s_min - 1)], 1, w, h, &pool);
      const double sa = g.sigma0 * std::pow(float(g.sigmak), float(g.s_min));
      const double sb = g.sigma0 * std::pow(float(g.sigmak), float(s_best - g.S));
      if (sa > sb) {
        Plane smoothed = pool.Take(w, h);
        Smooth(base, &smoothed, std::sqrt(sa * sa - sb * sb), threads);
        pool.Give(std::move(base));
        base = std::move(smoothed);
      }
    }
    // Gaussian levels as detection needs them: level s reads G(s - 1) .. G(s + 2). G(s_min) is
    // given back once read, so at most five planes of the octave are held, and no DoG plane.
    levels[0] = std::move(base);
    int made = g.s_min;
    auto make_level = [&](int s) {
      Plane& level = levels[size_t(s - g.s_min)];
      level = pool.Take(w, h);
      Smooth(levels[size_t(s - 1 - g.s_min)], &level, g.dsigma0 * std::pow(g.sigmak, s), threads);
      made = s;
    };
    for (int s = g.s_min + 1; s <= g.s_max - 2; ++s) {
      while (made < s + 2) make_level(made + 1);
      const Plane* gauss[4] = {&levels[size_t(s - 1 - g.s_min)], &levels[size_t(s - g.s_min)],
                               &levels[size_t(s + 1 - g.s_min)], &levels[size_t(s + 2 - g.s_min)]};
      DetectLevel(gauss, s, o, g, tp, te, threads, &keys);
      if (s - 1 == g.s_min) pool.Give(std::move(levels[0]));
    }
    for (int s = g.s_min; s <= g.s_max; ++s) {
      Plane& level = levels[size_t(s - g.s_min)];
      if (s >= g.s_min + 1 && s <= g.s_max - 2) {
        kept[size_t(oi)].push_back(std::move(level));
      } else {
        pool.Give(std::move(level));
      }
    }
  }

  // COLMAP's levels: runs of equal level index (not reset between octaves).
  struct Run {
    size_t begin, end;
  };
  std::vector<Run> runs;
  int prev_level = -1;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (runs.empty() || keys[i].is != prev_level) runs.push_back({i, i});
    prev_level = keys[i].is;
    runs.back().end = i + 1;
  }
  std::vector<size_t> counts;
  for (const Run& run : runs) counts.push_back(run.end - run.begin);
  const size_t first_run = FirstLevelToKeep(counts, options.max_num_features);
  const size_t first_key = runs.empty() ? 0 : runs[first_run].begin;

  // Level by level, in COLMAP's order (keys are grouped by octave, then level): the level's
  // gradient, its keypoints' orientations, then one descriptor per kept orientation. One
  // level's gradient planes are held at a time, taken from and given back to the pool, and
  // each level is given back once described.
  SiftFeatures features;
  for (size_t begin = first_key, end; begin < keys.size(); begin = end) {
    const int o = keys[begin].o, is = keys[begin].is;
    for (end = begin; end < keys.size() && keys[end].o == o && keys[end].is == is;) ++end;
    Plane& level = kept[size_t(o - g.o_min)][size_t(is - g.s_min - 1)];
    GradientPlanes grad{pool.Take(level.w, level.h), pool.Take(level.w, level.h)};
    Gradient(level, &grad, threads);
    struct Angles {
      double angle[4];
      int count;
    };
    const size_t n = end - begin;
    std::vector<Angles> angles(n);
    ParallelFor(n, threads, [&](size_t j) {
      if (options.upright) {
        angles[j].count = 1;
        angles[j].angle[0] = 0.0;
      } else {
        angles[j].count = Orientations(keys[begin + j], grad, angles[j].angle);
      }
    });
    std::vector<size_t> first_slot(n + 1, features.keypoints.size());
    for (size_t j = 0; j < n; ++j) {
      first_slot[j + 1] =
          first_slot[j] + size_t(std::min(angles[j].count, options.max_num_orientations));
    }
    features.keypoints.resize(first_slot[n]);
    features.descriptors.resize(first_slot[n] * kSiftDescriptorDim);
    ParallelFor(n, threads, [&](size_t j) {
      const Key& k = keys[begin + j];
      for (size_t slot = first_slot[j]; slot < first_slot[j + 1]; ++slot) {
        const double angle = angles[j].angle[slot - first_slot[j]];
        features.keypoints[slot] = {k.x + 0.5f, k.y + 0.5f, k.sigma, float(angle)};
        float raw[kSiftDescriptorDim];
        Descriptor(k, angle, grad, raw);
        FinishDescriptor(raw, options.normalization,
                         features.descriptors.data() + slot * kSiftDescriptorDim);
      }
    });
    pool.Give(std::move(grad.mod));
    pool.Give(std::move(grad.angle));
    pool.Give(std::move(level));
  }
  return features;
}

}  // namespace cwloc::sift_internal
