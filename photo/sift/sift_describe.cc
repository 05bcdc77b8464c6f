#include "photo/sift/sift_describe.h"

#include "photo/sift/sift_kernels.h"

namespace cwloc::sift_internal {
namespace {

float NormalizeHistogram(float* begin, float* end) {
  float norm = 0.0f;
  for (float* it = begin; it != end; ++it) norm += (*it) * (*it);
  norm = vl_fast_sqrt_f(norm) + VL_EPSILON_F;
  for (float* it = begin; it != end; ++it) *it /= norm;
  return norm;
}

}  // namespace

void Gradient(const Plane& level, Rows rows, GradientPlanes* grad, WorkerPool& pool) {
  const int h = level.h;
  pool.For(size_t(std::max(rows.hi - rows.lo, 0)), [&](size_t row) {
    const int y = rows.lo + int(row);
    GradientRow(y > 0 ? level.Row(y - 1) : nullptr, level.Row(y),
                y < h - 1 ? level.Row(y + 1) : nullptr, level.w, grad->mod.Row(y),
                grad->angle.Row(y));
  });
}

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

}  // namespace cwloc::sift_internal
