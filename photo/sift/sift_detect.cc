#include "photo/sift/sift_detect.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "photo/sift/sift_kernels.h"

namespace cwloc::sift_internal {
namespace {

// DoG levels s - 1 .. s + 1 read from the Gaussian levels s - 1 .. s + 2 where they are held.
class DogLevels {
 public:
  explicit DogLevels(const Plane* gauss[4]) {
    const ptrdiff_t yo = gauss[1]->w;
    for (int k = 0; k < 4; ++k) {
      at_level_[k] = gauss[k]->data();
      first_[k] = ptrdiff_t(gauss[k]->y0) * yo;
    }
  }
  // DoG level s + ds (ds in -1, 0, 1) at image index i.
  float operator()(int ds, ptrdiff_t i) const {
    return at_level_[ds + 2][i - first_[ds + 2]] - at_level_[ds + 1][i - first_[ds + 1]];
  }

 private:
  // Level k's pixel at image index i is at_level_[k][i - first_[k]].
  const float* at_level_[4];
  ptrdiff_t first_[4];
};

// The DoG's gradient and Hessian at a pixel, by central differences.
struct DogDerivatives {
  double Dx = 0, Dy = 0, Ds = 0, Dxx = 0, Dyy = 0, Dss = 0, Dxy = 0, Dxs = 0, Dys = 0;
};

// Solves A b = -D by Gaussian elimination with partial pivoting (A column-major), as VLFeat
// does; b is zero when A is singular.
void SolveNewtonStep(const DogDerivatives& d, double b[3]) {
  double A[9] = {d.Dxx, d.Dxy, d.Dxs, d.Dxy, d.Dyy, d.Dys, d.Dxs, d.Dys, d.Dss};
  auto Aat = [&](int i, int j) -> double& { return A[i + j * 3]; };
  b[0] = -d.Dx;
  b[1] = -d.Dy;
  b[2] = -d.Ds;
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
}

// One DoG level's detection: the scan's candidates, VLFeat's extremum test and refinement.
class LevelDetector {
 public:
  LevelDetector(const Plane* gauss[4], int s, int o, const Geometry& g, double tp, double te)
      : gauss_(gauss),
        dog_(gauss),
        w_(gauss[1]->w),
        h_(gauss[1]->h),
        yo_(w_),
        s_(s),
        o_(o),
        g_(g),
        tp_(tp),
        te_(te),
        xper_(std::pow(2.0, o)),
        prefilter_(float(0.8 * tp) * (1 - 1e-6f)),
        low_(0.8 * tp) {}

  // Appends the keypoints of row y0 to `out`, in column order.
  void DetectRow(int y0, std::vector<Key>* out) const {
    thread_local std::vector<int32_t> candidates;
    candidates.resize(size_t(w_));
    const float* around[4][3];  // levels s - 1 .. s + 2, rows y0 - 1 .. y0 + 1
    for (int t = 0; t < 4; ++t) {
      for (int r = 0; r < 3; ++r) around[t][r] = gauss_[t]->Row(y0 - 1 + r);
    }
    const int num_candidates = FindExtremumCandidates(around, w_, prefilter_, candidates.data());
    for (int c = 0; c < num_candidates; ++c) {
      const int x0 = candidates[size_t(c)];
      const float v = around[2][1][x0] - around[1][1][x0];
      if (IsExtremum(v, ptrdiff_t(y0) * yo_ + x0)) Refine(x0, y0, out);
    }
  }

 private:
  // VLFeat's test: |v| at least 0.8 tp and v above all 26 neighbours, or below all of them.
  bool IsExtremum(float v, ptrdiff_t centre) const {
    auto extremum = [&](auto cmp) {
      for (int ds : {0, 1, -1}) {
        for (ptrdiff_t dy : {-yo_, ptrdiff_t(0), yo_}) {
          for (ptrdiff_t dx : {-kXo, ptrdiff_t(0), kXo}) {
            if (ds == 0 && dy == 0 && dx == 0) continue;
            if (!cmp(v, dog_(ds, centre + dy + dx))) return false;
          }
        }
      }
      return true;
    };
    const bool is_max = v >= +low_ && extremum([](float a, float b) { return a > b; });
    const bool is_min = !is_max && v <= -low_ && extremum([](float a, float b) { return a < b; });
    return is_max || is_min;
  }

  DogDerivatives DerivativesAt(ptrdiff_t at_index) const {
    auto at = [&](int ddx, int ddy, int dds) {
      return dog_(dds, at_index + ddx * kXo + ddy * yo_);
    };
    DogDerivatives d;
    d.Dx = 0.5 * (at(+1, 0, 0) - at(-1, 0, 0));
    d.Dy = 0.5 * (at(0, +1, 0) - at(0, -1, 0));
    d.Ds = 0.5 * (at(0, 0, +1) - at(0, 0, -1));
    d.Dxx = (at(+1, 0, 0) + at(-1, 0, 0) - 2.0 * at(0, 0, 0));
    d.Dyy = (at(0, +1, 0) + at(0, -1, 0) - 2.0 * at(0, 0, 0));
    d.Dss = (at(0, 0, +1) + at(0, 0, -1) - 2.0 * at(0, 0, 0));
    d.Dxy = 0.25 * (at(+1, +1, 0) + at(-1, -1, 0) - at(-1, +1, 0) - at(+1, -1, 0));
    d.Dxs = 0.25 * (at(+1, 0, +1) + at(-1, 0, -1) - at(-1, 0, +1) - at(+1, 0, -1));
    d.Dys = 0.25 * (at(0, +1, +1) + at(0, -1, -1) - at(0, -1, +1) - at(0, +1, -1));
    return d;
  }

  // VLFeat's refinement: up to 5 Newton steps, moving by one pixel when the offset exceeds 0.6;
  // then the peak, edge and offset tests. Appends the keypoint to `out` when it passes them.
  void Refine(int x0, int y0, std::vector<Key>* out) const {
    int x = x0, y = y0, dx = 0, dy = 0;
    DogDerivatives d;
    double b[3] = {0, 0, 0};
    ptrdiff_t at_index = 0;
    for (int iter = 0; iter < 5; ++iter) {
      x += dx;
      y += dy;
      at_index = ptrdiff_t(y) * yo_ + x;
      d = DerivativesAt(at_index);
      SolveNewtonStep(d, b);
      dx = ((b[0] > 0.6 && x < w_ - 2) ? 1 : 0) + ((b[0] < -0.6 && x > 1) ? -1 : 0);
      dy = ((b[1] > 0.6 && y < h_ - 2) ? 1 : 0) + ((b[1] < -0.6 && y > 1) ? -1 : 0);
      if (dx == 0 && dy == 0) break;
    }
    const double val = dog_(0, at_index) + 0.5 * (d.Dx * b[0] + d.Dy * b[1] + d.Ds * b[2]);
    const double score = (d.Dxx + d.Dyy) * (d.Dxx + d.Dyy) / (d.Dxx * d.Dyy - d.Dxy * d.Dxy);
    const double xn = x + b[0], yn = y + b[1], sn = s_ + b[2];
    const bool good = std::abs(val) > tp_ && score < (te_ + 1) * (te_ + 1) / te_ && score >= 0 &&
                      std::abs(b[0]) < 1.5 && std::abs(b[1]) < 1.5 && std::abs(b[2]) < 1.5 &&
                      xn >= 0 && xn <= w_ - 1 && yn >= 0 && yn <= h_ - 1 && sn >= g_.s_min &&
                      sn <= g_.s_max;
    if (good) {
      out->push_back({o_, x, y, s_, float(xn * xper_), float(yn * xper_), float(sn),
                      float(g_.sigma0 * std::pow(2.0, sn / g_.S) * xper_)});
    }
  }

  static constexpr ptrdiff_t kXo = 1;  // a column's step; yo_ is a row's
  const Plane* const* gauss_;
  DogLevels dog_;
  int w_, h_;
  ptrdiff_t yo_;
  int s_, o_;
  const Geometry& g_;
  double tp_, te_, xper_;
  float prefilter_;
  double low_;
};

}  // namespace

void DetectLevel(const Plane* gauss[4], int s, int o, const Geometry& g, double tp, double te,
                 Rows rows, WorkerPool& pool, std::vector<Key>* keys) {
  const LevelDetector detector(gauss, s, o, g, tp, te);
  std::vector<std::vector<Key>> row_keys(size_t(std::max(rows.hi - rows.lo, 0)));
  pool.For(row_keys.size(),
           [&](size_t task) { detector.DetectRow(rows.lo + int(task), &row_keys[task]); });
  for (auto& row : row_keys) keys->insert(keys->end(), row.begin(), row.end());
}

}  // namespace cwloc::sift_internal
