#include "solvers/three_quadrics.h"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <cmath>

namespace cwloc {
namespace {

using Coeffs = Eigen::Matrix<double, 3, 10>;
using Solutions = Eigen::Matrix<double, 3, 8>;

// Polynomial in the hidden variable z, ascending powers, degree <= 8.
struct Poly {
  std::array<double, 9> c{};
  int degree = 0;

  static Poly Constant(double a) {
    Poly p;
    p.c[0] = a;
    return p;
  }
  static Poly Linear(double a0, double a1) {
    Poly p;
    p.c[0] = a0;
    p.c[1] = a1;
    p.degree = 1;
    return p;
  }
  double operator()(double z) const {
    double v = c[degree];
    for (int i = degree - 1; i >= 0; --i) v = v * z + c[i];
    return v;
  }
};

Poly operator+(const Poly& a, const Poly& b) {
  Poly r;
  r.degree = std::max(a.degree, b.degree);
  for (int i = 0; i <= r.degree; ++i) r.c[i] = a.c[i] + b.c[i];
  return r;
}

Poly operator-(const Poly& a, const Poly& b) {
  Poly r;
  r.degree = std::max(a.degree, b.degree);
  for (int i = 0; i <= r.degree; ++i) r.c[i] = a.c[i] - b.c[i];
  return r;
}

Poly operator*(const Poly& a, const Poly& b) {
  Poly r;
  r.degree = std::min(a.degree + b.degree, 8);  // callers stay within degree 8
  for (int i = 0; i <= a.degree; ++i) {
    for (int j = 0; j <= b.degree && i + j <= 8; ++j) r.c[i + j] += a.c[i] * b.c[j];
  }
  return r;
}

Poly operator*(double s, const Poly& a) {
  Poly r = a;
  for (int i = 0; i <= r.degree; ++i) r.c[i] *= s;
  return r;
}

// A linear form px * x + py * y + p1 with coefficients polynomial in z.
struct LinearForm {
  Poly x, y, one;
};

LinearForm operator-(const LinearForm& a, const LinearForm& b) {
  return {a.x - b.x, a.y - b.y, a.one - b.one};
}

// The root of p in [left, right] where p changes sign (f_left = p(left)): Newton steps, with a
// bisection whenever Newton would leave the bracket or shrinks the step too slowly (a
// high-degree polynomial far from its root converges only linearly).
double RefineBracketedRoot(const Poly& p, const Poly& dp, double left, double right, double f_left,
                           double tolerance) {
  double x = 0.5 * (left + right);
  double step = right - left;
  double step_before = step;
  for (int iter = 0; iter < 200; ++iter) {
    const double fx = p(x);
    if (fx == 0.0) return x;
    if ((fx < 0.0) == (f_left < 0.0)) {
      left = x;
      f_left = fx;
    } else {
      right = x;
    }
    const double dfx = dp(x);
    const double newton = dfx != 0.0 ? x - fx / dfx : x;
    if (dfx == 0.0 || !(newton > left && newton < right) ||
        std::abs(2.0 * fx) > std::abs(step_before * dfx)) {
      step_before = step;
      step = 0.5 * (right - left);
      x = left + step;
    } else {
      step_before = step;
      step = x - newton;
      x = newton;
    }
    if (std::abs(step) <= tolerance * std::max(1.0, std::abs(x))) return x;
  }
  return x;
}

// Real roots of p (degree d, p.c[d] != 0) in [lo, hi], ascending, to relative precision
// `tolerance`. Roots of p' split the interval into pieces where p is monotonic; each holds at
// most one root, found by Newton steps safeguarded by bisection. The derivatives' roots only
// delimit those pieces and need less precision.
int RealRootsInInterval(const Poly& p, double lo, double hi, double tolerance, double* roots) {
  const int d = p.degree;
  if (d == 0) return 0;
  if (d == 1) {
    const double r = -p.c[0] / p.c[1];
    if (r >= lo && r <= hi) {
      roots[0] = r;
      return 1;
    }
    return 0;
  }
  Poly dp;
  dp.degree = d - 1;
  for (int i = 1; i <= d; ++i) dp.c[i - 1] = i * p.c[i];
  double critical[8];
  const int num_critical = RealRootsInInterval(dp, lo, hi, std::max(tolerance, 1e-9), critical);

  int n = 0;
  double a = lo;
  double fa = p(a);
  for (int k = 0; k <= num_critical; ++k) {
    const double b = k < num_critical ? critical[k] : hi;
    const double fb = p(b);
    if (fa == 0.0) {
      if (n == 0 || roots[n - 1] != a) roots[n++] = a;
    } else if ((fa < 0.0) != (fb < 0.0) && fb != 0.0) {
      roots[n++] = RefineBracketedRoot(p, dp, a, b, fa, tolerance);
    }
    a = b;
    fa = fb;
  }
  if (fa == 0.0 && (n == 0 || roots[n - 1] != a)) roots[n++] = a;
  return n;
}

Eigen::Vector3d Evaluate(const Coeffs& c, const Eigen::Vector3d& p) {
  const double x = p(0), y = p(1), z = p(2);
  return c.col(0) * x * x + c.col(1) * x * y + c.col(2) * x * z + c.col(3) * y * y +
         c.col(4) * y * z + c.col(5) * z * z + c.col(6) * x + c.col(7) * y + c.col(8) * z +
         c.col(9);
}

// Newton steps on the three equations; returns false if the point is not a solution.
bool Polish(const Coeffs& c, Eigen::Vector3d* point) {
  Eigen::Vector3d& p = *point;
  Eigen::Vector3d r = Evaluate(c, p);
  for (int iter = 0; iter < 6; ++iter) {
    const double x = p(0), y = p(1), z = p(2);
    Eigen::Matrix3d jac;
    jac.col(0) = 2.0 * c.col(0) * x + c.col(1) * y + c.col(2) * z + c.col(6);
    jac.col(1) = c.col(1) * x + 2.0 * c.col(3) * y + c.col(4) * z + c.col(7);
    jac.col(2) = c.col(2) * x + c.col(4) * y + 2.0 * c.col(5) * z + c.col(8);
    if (!(std::abs(jac.determinant()) > 0.0)) break;
    const Eigen::Vector3d p_new = p - jac.inverse() * r;  // a 3x3 inverse is closed form
    const Eigen::Vector3d r_new = Evaluate(c, p_new);
    if (!(r_new.squaredNorm() < r.squaredNorm())) break;
    p = p_new;
    r = r_new;
  }
  // Equations are scaled to unit max coefficient; the monomials' size sets the tolerance.
  return p.allFinite() && r.lpNorm<Eigen::Infinity>() < 1e-6 * (1.0 + p.squaredNorm());
}

// Coefficients after substituting p = m * q + shift, via the symmetric 4x4 form.
Coeffs ChangeCoordinates(const Coeffs& c, const Eigen::Matrix3d& m, const Eigen::Vector3d& shift) {
  Eigen::Matrix4d h = Eigen::Matrix4d::Identity();
  h.topLeftCorner<3, 3>() = m;
  h.topRightCorner<3, 1>() = shift;
  Coeffs out;
  for (int k = 0; k < 3; ++k) {
    Eigen::Matrix4d q;
    q << c(k, 0), 0.5 * c(k, 1), 0.5 * c(k, 2), 0.5 * c(k, 6), 0.5 * c(k, 1), c(k, 3),
        0.5 * c(k, 4), 0.5 * c(k, 7), 0.5 * c(k, 2), 0.5 * c(k, 4), c(k, 5), 0.5 * c(k, 8),
        0.5 * c(k, 6), 0.5 * c(k, 7), 0.5 * c(k, 8), c(k, 9);
    const Eigen::Matrix4d qn = h.transpose() * q * h;
    out.row(k) << qn(0, 0), 2.0 * qn(0, 1), 2.0 * qn(0, 2), qn(1, 1), 2.0 * qn(1, 2), qn(2, 2),
        2.0 * qn(0, 3), 2.0 * qn(1, 3), 2.0 * qn(2, 3), qn(3, 3);
  }
  return out;
}

// Conditioning of eliminating {x^2, xy, y^2}: |det| relative to the entries' size.
double EliminationQuality(const Coeffs& c) {
  Eigen::Matrix3d g;
  g << c.col(0), c.col(1), c.col(3);
  const double scale = g.norm();
  return scale > 0.0 ? std::abs(g.determinant()) / (scale * scale * scale) : 0.0;
}

// Hidden-variable resultant in z. Solving the equations for x^2, xy, y^2 gives
// s = alpha_s x + beta_s y + gamma_s (alpha, beta linear and gamma quadratic in z). Then
// E1 = x (xy) - y (x^2), E2 = x (y^2) - y (xy) and E3 = y E1, each reduced with those rules,
// are linear forms in (x, y, 1) that vanish at every solution, so the determinant of their
// 3x3 coefficient matrix, a polynomial of degree 8 in z, vanishes at the solutions' z.
int SolveHiddenZ(const Coeffs& c, Solutions* solutions) {
  Eigen::Matrix3d g;
  g << c.col(0), c.col(1), c.col(3);
  const Eigen::Matrix3d g_inv = g.inverse();
  if (!g_inv.allFinite()) return 0;
  LinearForm rule[3];  // x^2, xy, y^2
  for (int s = 0; s < 3; ++s) {
    Poly alpha, beta, gamma;
    for (int k = 0; k < 3; ++k) {
      const double w = -g_inv(s, k);
      alpha = alpha + w * Poly::Linear(c(k, 6), c(k, 2));
      beta = beta + w * Poly::Linear(c(k, 7), c(k, 4));
      Poly f;
      f.c = {c(k, 9), c(k, 8), c(k, 5)};
      f.degree = 2;
      gamma = gamma + w * f;
    }
    rule[s] = {alpha, beta, gamma};
  }
  const LinearForm& x2 = rule[0];
  const LinearForm& xy = rule[1];
  const LinearForm& y2 = rule[2];
  auto times_x = [&](const LinearForm& l) -> LinearForm {
    return {l.x * x2.x + l.y * xy.x + l.one, l.x * x2.y + l.y * xy.y, l.x * x2.one + l.y * xy.one};
  };
  auto times_y = [&](const LinearForm& l) -> LinearForm {
    return {l.x * xy.x + l.y * y2.x, l.x * xy.y + l.y * y2.y + l.one, l.x * xy.one + l.y * y2.one};
  };
  const LinearForm e1 = times_x(xy) - times_y(x2);
  const LinearForm e2 = times_x(y2) - times_y(xy);
  const LinearForm e3 = times_y(e1);  // x E1 and y E2 depend on E1, E2; y E1 does not

  Poly det = e1.x * (e2.y * e3.one - e2.one * e3.y) - e1.y * (e2.x * e3.one - e2.one * e3.x) +
             e1.one * (e2.x * e3.y - e2.y * e3.x);
  double max_coeff = 0.0;
  for (int i = 0; i <= det.degree; ++i) max_coeff = std::max(max_coeff, std::abs(det.c[i]));
  if (!(max_coeff > 0.0) || !std::isfinite(max_coeff)) return 0;
  while (det.degree > 0 && std::abs(det.c[det.degree]) <= 1e-14 * max_coeff) --det.degree;
  if (det.degree == 0) return 0;
  // Fujiwara's bound on the roots' magnitude: 2 max_k |c[d-k] / c[d]|^(1/k).
  double bound = 0.0;
  for (int k = 1; k <= det.degree; ++k) {
    const double ratio = std::abs(det.c[det.degree - k] / det.c[det.degree]);
    bound = std::max(bound, std::pow(k == det.degree ? 0.5 * ratio : ratio, 1.0 / k));
  }
  bound = 2.0 * bound * (1.0 + 1e-12) + 1e-300;
  double roots[8];
  const int num_roots = RealRootsInInterval(det, -bound, bound, 1e-14, roots);

  int n = 0;
  for (int i = 0; i < num_roots; ++i) {
    const double z = roots[i];
    Eigen::Matrix3d m;
    m << e1.x(z), e1.y(z), e1.one(z), e2.x(z), e2.y(z), e2.one(z), e3.x(z), e3.y(z), e3.one(z);
    // (x, y, 1) spans the null space: the best conditioned cross product of two rows.
    const Eigen::Vector3d cand[3] = {m.row(0).cross(m.row(1)), m.row(0).cross(m.row(2)),
                                     m.row(1).cross(m.row(2))};
    int best = 0;
    for (int k = 1; k < 3; ++k) {
      if (cand[k].squaredNorm() > cand[best].squaredNorm()) best = k;
    }
    const Eigen::Vector3d v = cand[best];
    if (!(std::abs(v(2)) > 1e-12 * v.norm())) continue;  // a solution at infinity
    Eigen::Vector3d p(v(0) / v(2), v(1) / v(2), z);
    if (!Polish(c, &p)) continue;
    // Two nearby roots may polish to the same solution.
    bool duplicate = false;
    for (int k = 0; k < n && !duplicate; ++k) {
      duplicate = (solutions->col(k) - p).norm() <= 1e-9 * (1.0 + p.norm());
    }
    if (!duplicate) solutions->col(n++) = p;
  }
  return n;
}

}  // namespace

int SolveThreeQuadrics(const Eigen::Matrix<double, 3, 10>& coeffs,
                       Eigen::Matrix<double, 3, 8>* solutions) {
  Coeffs c = coeffs;
  for (int k = 0; k < 3; ++k) {
    const double m = c.row(k).cwiseAbs().maxCoeff();
    if (!(m > 0.0) || !std::isfinite(m)) return 0;
    c.row(k) /= m;
  }
  // Hide the variable whose elimination is best conditioned: a permutation p = perm * q moves
  // it to the third position.
  Eigen::Matrix3d best_perm = Eigen::Matrix3d::Identity();
  Coeffs best = c;
  double best_quality = EliminationQuality(c);
  for (int hidden = 0; hidden < 2; ++hidden) {
    Eigen::Matrix3d perm = Eigen::Matrix3d::Identity();
    perm.col(hidden).swap(perm.col(2));
    const Coeffs permuted = ChangeCoordinates(c, perm, Eigen::Vector3d::Zero());
    const double quality = EliminationQuality(permuted);
    if (quality > best_quality) {
      best_quality = quality;
      best = permuted;
      best_perm = perm;
    }
  }
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  if (best_quality < 1e-8) {
    // No variable eliminates well (e.g. a solution at infinity for all of them): a fixed,
    // deterministic generic rotation and shift.
    best_perm = Eigen::Quaterniond(0.8224, 0.3310, -0.2842, 0.3703).normalized().toRotationMatrix();
    shift = Eigen::Vector3d(0.3127, -0.4581, 0.2219);
    best = ChangeCoordinates(c, best_perm, shift);
  }
  const int n = SolveHiddenZ(best, solutions);
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d p = best_perm * solutions->col(i) + shift;
    if (Polish(c, &p)) solutions->col(kept++) = p;
  }
  return kept;
}

}  // namespace cwloc
