#include "solvers/p3p.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

namespace cwloc {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

// Largest real root of x^3 + b x^2 + c x + d (a real cubic always has one), Newton-polished.
double LargestRealCubicRoot(double b, double c, double d) {
  // Depressed form y^3 + p y + q with x = y - b/3.
  const double b3 = b / 3.0;
  const double p = c - b * b3;
  const double q = b3 * (2.0 * b3 * b3 - c) + d;
  const double disc = 0.25 * q * q + p * p * p / 27.0;
  double y = 0.0;
  if (disc > 0.0) {
    // One real root (Cardano). The cube root of the larger-magnitude term avoids cancellation.
    const double u = std::cbrt(-0.5 * q - std::copysign(std::sqrt(disc), q));
    y = u == 0.0 ? 0.0 : u - p / (3.0 * u);
  } else {
    // Three real roots; the k = 0 branch of the trigonometric form is the largest.
    const double r = std::sqrt(std::max(0.0, -p / 3.0));
    if (r > 0.0) {
      const double arg = std::clamp(-q / (2.0 * r * r * r), -1.0, 1.0);
      y = 2.0 * r * std::cos(std::acos(arg) / 3.0);
    }
  }
  double x = y - b3;
  auto cubic = [&](double v) { return ((v + b) * v + c) * v + d; };
  double f = cubic(x);
  for (int i = 0; i < 3 && f != 0.0; ++i) {
    const double df = (3.0 * x + 2.0 * b) * x + c;
    if (df == 0.0) break;
    const double x_new = x - f / df;
    const double f_new = cubic(x_new);
    if (!(std::abs(f_new) < std::abs(f))) break;  // a double root makes Newton stall
    x = x_new;
    f = f_new;
  }
  return x;
}

// tr(adj(a) * b) for 3x3 matrices; adj(a) has the rows (a1 x a2), (a2 x a0), (a0 x a1).
double TraceAdjProduct(const Matrix3d& a, const Matrix3d& b) {
  return a.col(1).cross(a.col(2)).dot(b.col(0)) + a.col(2).cross(a.col(0)).dot(b.col(1)) +
         a.col(0).cross(a.col(1)).dot(b.col(2));
}

// Unit eigenvector of the symmetric matrix m for the simple eigenvalue sigma: the best
// conditioned cross product of two rows of (m - sigma I). Zero if sigma is not simple.
Vector3d SymmetricEigenvector(const Matrix3d& m, double sigma) {
  const Matrix3d a = m - sigma * Matrix3d::Identity();
  const Vector3d c[3] = {a.row(0).cross(a.row(1)), a.row(0).cross(a.row(2)),
                         a.row(1).cross(a.row(2))};
  int best = 0;
  for (int i = 1; i < 3; ++i) {
    if (c[i].squaredNorm() > c[best].squaredNorm()) best = i;
  }
  const double norm = c[best].norm();
  return norm > 0.0 ? Vector3d(c[best] / norm) : Vector3d::Zero();
}

// Orthonormal frame of a triangle: first axis along p1 - p0, second in the triangle's plane.
Matrix3d TriangleFrame(const Vector3d& p0, const Vector3d& p1, const Vector3d& p2) {
  Matrix3d frame;
  const Vector3d e0 = (p1 - p0).normalized();
  const Vector3d v = p2 - p0;
  const Vector3d e1 = (v - e0.dot(v) * e0).normalized();
  frame << e0, e1, e0.cross(e1);
  return frame;
}

struct DepthProblem {
  double a12, a13, a23;  // squared world distances
  double b12, b13, b23;  // cosines between the bearings

  // Residuals of lambda_i^2 + lambda_j^2 - 2 b_ij lambda_i lambda_j = a_ij.
  Vector3d Residuals(const Vector3d& l) const {
    return Vector3d(l(0) * l(0) + l(1) * l(1) - 2.0 * b12 * l(0) * l(1) - a12,
                    l(0) * l(0) + l(2) * l(2) - 2.0 * b13 * l(0) * l(2) - a13,
                    l(1) * l(1) + l(2) * l(2) - 2.0 * b23 * l(1) * l(2) - a23);
  }

  // Gauss-Newton on the three constraints; the closed form leaves ~1e-10 relative error that
  // a couple of steps remove.
  void Polish(Vector3d* lambda) const {
    Vector3d& l = *lambda;
    Vector3d r = Residuals(l);
    double cost = r.squaredNorm();
    for (int iter = 0; iter < 5 && cost > 0.0; ++iter) {
      Matrix3d jac;
      jac << 2.0 * (l(0) - b12 * l(1)), 2.0 * (l(1) - b12 * l(0)), 0.0, 2.0 * (l(0) - b13 * l(2)),
          0.0, 2.0 * (l(2) - b13 * l(0)), 0.0, 2.0 * (l(1) - b23 * l(2)), 2.0 * (l(2) - b23 * l(1));
      const double det = jac.determinant();
      if (!(std::abs(det) > 0.0)) return;
      const Vector3d l_new = l - jac.inverse() * r;
      const Vector3d r_new = Residuals(l_new);
      const double cost_new = r_new.squaredNorm();
      if (!(cost_new < cost)) return;
      l = l_new;
      r = r_new;
      cost = cost_new;
    }
  }
};

}  // namespace

int P3P(const std::array<Eigen::Vector3d, 3>& bearings,
        const std::array<Eigen::Vector3d, 3>& points, std::vector<CameraPose>* poses) {
  poses->clear();
  const Vector3d& y1 = bearings[0];
  const Vector3d& y2 = bearings[1];
  const Vector3d& y3 = bearings[2];

  DepthProblem dp;
  dp.a12 = (points[0] - points[1]).squaredNorm();
  dp.a13 = (points[0] - points[2]).squaredNorm();
  dp.a23 = (points[1] - points[2]).squaredNorm();
  dp.b12 = y1.dot(y2);
  dp.b13 = y1.dot(y3);
  dp.b23 = y2.dot(y3);
  // Coincident points (or NaN input) leave nothing to solve.
  if (!(dp.a12 > 0.0 && dp.a13 > 0.0 && dp.a23 > 0.0)) return 0;
  if (!std::isfinite(dp.b12 + dp.b13 + dp.b23 + dp.a12 + dp.a13 + dp.a23)) return 0;

  // lambda^T D lambda = 0 for a23*(eq12) - a12*(eq23) and a23*(eq13) - a13*(eq23).
  const double a12 = dp.a12, a13 = dp.a13, a23 = dp.a23;
  const double b12 = dp.b12, b13 = dp.b13, b23 = dp.b23;
  Matrix3d d1, d2;
  d1 << a23, -a23 * b12, 0.0, -a23 * b12, a23 - a12, a12 * b23, 0.0, a12 * b23, -a12;
  d2 << a23, 0.0, -a23 * b13, 0.0, -a13, a13 * b23, -a23 * b13, a13 * b23, a23 - a13;

  // det(d1 + g d2) = c3 g^3 + c2 g^2 + c1 g + c0. Any real root g makes d0 = d1 + g d2 a pair of
  // real lines whenever real solutions exist (Persson & Nordberg, sec. 3); the largest is used.
  const double c3 = d2.determinant();
  const double c2 = TraceAdjProduct(d2, d1);
  const double c1 = TraceAdjProduct(d1, d2);
  const double c0 = d1.determinant();
  const double c_max = std::max({std::abs(c0), std::abs(c1), std::abs(c2), std::abs(c3)});
  if (!(c_max > 0.0) || !std::isfinite(c_max)) return 0;
  Matrix3d d0;
  if (std::abs(c3) > 1e-14 * c_max) {
    const double g = LargestRealCubicRoot(c2 / c3, c1 / c3, c0 / c3);
    // Scaling does not change the conic; keep the entries bounded for a huge root.
    d0 = std::abs(g) > 1.0 ? Matrix3d(d1 / g + d2) : Matrix3d(d1 + g * d2);
  } else {
    d0 = d2;  // the root at infinity: d2 itself is degenerate
  }
  if (!d0.allFinite()) return 0;

  // d0 has eigenvalues sig1, sig2, 0. sig1 (e1.l)^2 + sig2 (e2.l)^2 = 0 splits into the lines
  // (e1 -+ s e2).l = 0 with s = sqrt(-sig2 / sig1).
  const double tr = d0.trace();
  const double minors = d0(0, 0) * d0(1, 1) - d0(0, 1) * d0(0, 1) + d0(0, 0) * d0(2, 2) -
                        d0(0, 2) * d0(0, 2) + d0(1, 1) * d0(2, 2) - d0(1, 2) * d0(1, 2);
  const double h = std::sqrt(std::max(0.0, 0.25 * tr * tr - minors));
  double sig1 = 0.5 * tr + h;
  double sig2 = 0.5 * tr - h;
  if (std::abs(sig1) < std::abs(sig2)) std::swap(sig1, sig2);
  if (!(std::abs(sig1) > 0.0)) return 0;
  const double ratio = -sig2 / sig1;
  if (ratio < -1e-8) return 0;  // a definite pair: no real solution
  const double s = std::sqrt(std::max(0.0, ratio));
  const Vector3d e1 = SymmetricEigenvector(d0, sig1);
  const Vector3d e2 = s > 0.0 ? SymmetricEigenvector(d0, sig2) : Vector3d::Zero();
  if (e1.squaredNorm() == 0.0) return 0;

  const Matrix3d world_frame = TriangleFrame(points[0], points[1], points[2]);
  const Vector3d world_centroid = (points[0] + points[1] + points[2]) / 3.0;
  const int num_lines = s > 0.0 ? 2 : 1;
  for (int line = 0; line < num_lines; ++line) {
    const Vector3d u = line == 0 ? Vector3d(e1 - s * e2) : Vector3d(e1 + s * e2);
    // Orthonormal basis (w1, w2) of the plane u.lambda = 0: lambda = m1 w1 + m2 w2.
    int axis = 0;
    u.cwiseAbs().minCoeff(&axis);
    const Vector3d w1 = u.cross(Vector3d::Unit(axis)).normalized();
    const Vector3d w2 = u.normalized().cross(w1);
    Eigen::Matrix<double, 3, 2> w;
    w << w1, w2;
    // On the line d1 and d2 are proportional; the larger restriction is better conditioned.
    Eigen::Matrix2d k = w.transpose() * d1 * w;
    const Eigen::Matrix2d k2 = w.transpose() * d2 * w;
    if (k2.squaredNorm() > k.squaredNorm()) k = k2;
    // k00 m1^2 + 2 k01 m1 m2 + k11 m2^2 = 0, solved for the ratio with the larger leading term.
    const bool swap = std::abs(k(1, 1)) > std::abs(k(0, 0));
    const double qa = swap ? k(1, 1) : k(0, 0);
    const double qb = k(0, 1);
    const double qc = swap ? k(0, 0) : k(1, 1);
    const double disc = qb * qb - qa * qc;
    if (disc < -1e-12 * (qb * qb + std::abs(qa * qc)) || qa == 0.0) continue;
    const double sq = std::sqrt(std::max(0.0, disc));
    const double qq = -(qb + std::copysign(sq, qb));
    double roots[2];
    int num_roots = 0;
    roots[num_roots++] = qq / qa;
    if (sq > 0.0) roots[num_roots++] = qq != 0.0 ? qc / qq : 0.0;

    for (int r = 0; r < num_roots; ++r) {
      const Eigen::Vector2d m =
          swap ? Eigen::Vector2d(1.0, roots[r]) : Eigen::Vector2d(roots[r], 1.0);
      Vector3d lambda = w * m;
      // Fix the scale with the best conditioned distance constraint.
      const Vector3d n = dp.Residuals(lambda) + Vector3d(a12, a13, a23);
      int pair = 0;
      n.maxCoeff(&pair);
      if (!(n(pair) > 0.0)) continue;
      const double a_pair = pair == 0 ? a12 : (pair == 1 ? a13 : a23);
      lambda *= std::sqrt(a_pair / n(pair));
      if (lambda.maxCoeff() < 0.0) lambda = -lambda;
      if (!(lambda.minCoeff() > 0.0)) continue;  // a point behind the camera
      dp.Polish(&lambda);
      if (!(lambda.minCoeff() > 0.0)) continue;

      const Vector3d p1 = lambda(0) * y1;
      const Vector3d p2 = lambda(1) * y2;
      const Vector3d p3 = lambda(2) * y3;
      const Matrix3d rot = TriangleFrame(p1, p2, p3) * world_frame.transpose();
      const Vector3d t = (p1 + p2 + p3) / 3.0 - rot * world_centroid;
      if (!rot.allFinite() || !t.allFinite()) continue;
      poses->emplace_back(Eigen::Quaterniond(rot).normalized(), t);
    }
  }
  return static_cast<int>(poses->size());
}

}  // namespace cwloc
