#include "robust/cholesky.h"

#include <cmath>

namespace cwloc {

bool SolveCholesky(int n, const double* a, int stride, const double* rhs, double* y) {
  if (n < 1 || n > kMaxCholeskySize) return false;
  double l[kMaxCholeskySize][kMaxCholeskySize] = {};
  for (int j = 0; j < n; ++j) {
    double d = a[j * stride + j];
    for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
    if (!(d > 0.0)) return false;
    l[j][j] = std::sqrt(d);
    for (int i = j + 1; i < n; ++i) {
      double s = a[i * stride + j];
      for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
      l[i][j] = s / l[j][j];
    }
  }
  for (int i = 0; i < n; ++i) {
    double s = rhs[i];
    for (int k = 0; k < i; ++k) s -= l[i][k] * y[k];
    y[i] = s / l[i][i];
  }
  for (int i = n - 1; i >= 0; --i) {
    double s = y[i];
    for (int k = i + 1; k < n; ++k) s -= l[k][i] * y[k];
    y[i] = s / l[i][i];
  }
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(y[i])) return false;
  }
  return true;
}

}  // namespace cwloc
