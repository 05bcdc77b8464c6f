#include "photo/sift/sift_detect.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "photo/sift/sift_kernels.h"

namespace cwloc::sift_internal {

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

}  // namespace cwloc::sift_internal
