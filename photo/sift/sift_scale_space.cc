#include "photo/sift/sift_scale_space.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "base/huge_pages.h"
#include "photo/sift/sift_kernels.h"

namespace cwloc::sift_internal {

std::unique_ptr<float[], Plane::Free> Plane::Allocate(size_t n) {
  // Linux's default transparent-huge-page mode is "madvise": a plane of 2 MiB or more, aligned
  // to 2 MiB and advised, takes one page fault per 2 MiB instead of 512. A one-photo run took
  // ~21000 faults, about a tenth of its time.
  constexpr size_t kHugePage = size_t(2) << 20;
  const size_t bytes = n * sizeof(float);
  const size_t alignment = bytes >= kHugePage ? kHugePage : 64;
  const size_t rounded = (bytes + alignment - 1) / alignment * alignment;
  void* p = std::aligned_alloc(alignment, rounded);
  if (!p) throw std::bad_alloc();
  if (alignment == kHugePage) AdviseHugePages(p, rounded);
  return std::unique_ptr<float[], Free>(static_cast<float*>(p));
}

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

void DownsampleRows(const Plane& in, int d, Rows rows, Plane* out) {
  const int step = 1 << d;
  for (int y = (rows.lo + step - 1) / step; y * step < rows.hi && y < out->h; ++y) {
    const float* src = in.Row(y * step);
    float* dst = out->Row(y);
    for (int x = 0; x < out->w; ++x) dst[x] = src[size_t(x) * size_t(step)];
  }
}

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

}  // namespace cwloc::sift_internal
