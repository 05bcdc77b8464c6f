#include "solvers/p4pf.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "solvers/three_quadrics.h"

namespace cwloc {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector2d;
using Eigen::Vector3d;

// Solutions with fx/fy outside [1/kMaxAspect, kMaxAspect] are not a square-pixel camera.
constexpr double kMaxAspect = 2.0;
// Flatness of the four points, sqrt(smallest / largest variance along the principal axes):
// below kOnlyPlanar the general solver's elimination is singular and only the planar solver
// runs; below kAlsoPlanar both run and the reprojection error ranks their solutions (with
// noise the homography's solution can be the better start for a nearly planar sample).
constexpr double kOnlyPlanar = 1e-10;
constexpr double kAlsoPlanar = 0.1;

// The four correspondences in well-conditioned units: image points scaled to unit mean
// radius, world points centred and scaled to unit RMS radius.
struct NormalizedProblem {
  std::array<Vector2d, 4> image;
  std::array<Vector3d, 4> world;
  double image_scale = 0.0;
  Vector3d centroid = Vector3d::Zero();
  double world_scale = 0.0;
};

// A solution in normalised units: X_c = R X' + t', f' X_c.xy / X_c.z = u.
struct Candidate {
  Matrix3d rotation;
  Vector3d translation;
  double focal;
  double error = 0.0;  // RMS reprojection error on the four points, normalised units
};

// An orthonormal basis of the vectors orthogonal to a's columns (kRows > kCols, a of full
// column rank): the last kRows - kCols columns of Q in a = QR, by Householder reflections.
// Plain loops: Eigen's fixed-size HouseholderQR took half of this file's compile time.
template <int kRows, int kCols>
Eigen::Matrix<double, kRows, kRows - kCols> OrthogonalComplement(
    Eigen::Matrix<double, kRows, kCols> a) {
  double v[kCols][kRows] = {};  // reflection k: I - tau[k] v[k] v[k]^T, v[k][k] = 1
  double tau[kCols] = {};
  for (int k = 0; k < kCols; ++k) {
    double tail = 0.0;
    for (int i = k + 1; i < kRows; ++i) tail += a(i, k) * a(i, k);
    v[k][k] = 1.0;
    if (!(tail > 0.0)) continue;  // already zero below the diagonal: no reflection
    const double c0 = a(k, k);
    const double beta = c0 >= 0.0 ? -std::sqrt(c0 * c0 + tail) : std::sqrt(c0 * c0 + tail);
    for (int i = k + 1; i < kRows; ++i) v[k][i] = a(i, k) / (c0 - beta);
    tau[k] = (beta - c0) / beta;
    for (int j = k + 1; j < kCols; ++j) {
      double dot = 0.0;
      for (int i = k; i < kRows; ++i) dot += v[k][i] * a(i, j);
      for (int i = k; i < kRows; ++i) a(i, j) -= tau[k] * v[k][i] * dot;
    }
  }
  // Column j of Q is H_0 H_1 ... H_{kCols-1} e_j.
  Eigen::Matrix<double, kRows, kRows - kCols> complement;
  for (int j = kCols; j < kRows; ++j) {
    double x[kRows] = {};
    x[j] = 1.0;
    for (int k = kCols - 1; k >= 0; --k) {
      double dot = 0.0;
      for (int i = k; i < kRows; ++i) dot += v[k][i] * x[i];
      for (int i = k; i < kRows; ++i) x[i] -= tau[k] * v[k][i] * dot;
    }
    for (int i = 0; i < kRows; ++i) complement(i, j - kCols) = x[i];
  }
  return complement;
}

// Projection equations linear in P ~ diag(fx, fy, 1) [R | t]; orthogonal rows of its left
// block give three quadrics in the null space coordinates.
void SolveGeneral(const NormalizedProblem& np, std::vector<Candidate>* candidates) {
  // Each correspondence gives p1.X - u p3.X = 0 and p2.X - v p3.X = 0 in the rows p1, p2, p3
  // of P; the equations are the columns of a^T, unknowns ordered [p1; p2; p3].
  Eigen::Matrix<double, 12, 8> at = Eigen::Matrix<double, 12, 8>::Zero();
  for (int i = 0; i < 4; ++i) {
    Eigen::Vector4d h;
    h << np.world[i], 1.0;
    at.block<4, 1>(0, 2 * i) = h;
    at.block<4, 1>(8, 2 * i) = -np.image[i](0) * h;
    at.block<4, 1>(4, 2 * i + 1) = h;
    at.block<4, 1>(8, 2 * i + 1) = -np.image[i](1) * h;
  }
  const Eigen::Matrix<double, 12, 4> null = OrthogonalComplement(at);

  // P(c) = sum_k c_k null_k with c = (x, y, z, 1). Row a's left block m_a(c) is linear in c, so
  // m_a . m_b = c^T S c with S_kl = null_k^a . null_l^b.
  Eigen::Matrix<double, 3, 10> coeffs;
  constexpr int kPairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
  for (int e = 0; e < 3; ++e) {
    const int a = kPairs[e][0], b = kPairs[e][1];
    Eigen::Matrix4d s;
    for (int k = 0; k < 4; ++k) {
      for (int l = 0; l < 4; ++l) {
        s(k, l) = null.block<3, 1>(4 * a, k).dot(null.block<3, 1>(4 * b, l));
      }
    }
    s = 0.5 * (s + s.transpose()).eval();
    coeffs.row(e) << s(0, 0), 2.0 * s(0, 1), 2.0 * s(0, 2), s(1, 1), 2.0 * s(1, 2), s(2, 2),
        2.0 * s(0, 3), 2.0 * s(1, 3), 2.0 * s(2, 3), s(3, 3);
  }

  Eigen::Matrix<double, 3, 8> solutions;
  const int num_solutions = SolveThreeQuadrics(coeffs, &solutions);
  for (int i = 0; i < num_solutions; ++i) {
    const Eigen::Matrix<double, 12, 1> p_vec =
        null * Eigen::Vector4d(solutions(0, i), solutions(1, i), solutions(2, i), 1.0);
    Eigen::Matrix<double, 3, 4> p;
    p << p_vec.segment<4>(0).transpose(), p_vec.segment<4>(4).transpose(),
        p_vec.segment<4>(8).transpose();
    if (p.leftCols<3>().determinant() < 0.0) p = -p;
    const double row3_norm = p.block<1, 3>(2, 0).norm();
    if (!(row3_norm > 0.0)) continue;
    p /= row3_norm;
    const double fx = p.block<1, 3>(0, 0).norm();
    const double fy = p.block<1, 3>(1, 0).norm();
    if (!(fx > 0.0) || !(fy > 0.0)) continue;
    if (!(std::max(fx / fy, fy / fx) <= kMaxAspect)) continue;
    Candidate c;
    c.rotation << p.block<1, 3>(0, 0) / fx, p.block<1, 3>(1, 0) / fy, p.block<1, 3>(2, 0);
    c.translation = Vector3d(p(0, 3) / fx, p(1, 3) / fy, p(2, 3));
    c.focal = 0.5 * (fx + fy);
    candidates->push_back(c);
  }
}

// Four (nearly) coplanar points: the plane-to-image homography H ~ diag(f, f, 1) [r1 r2 t]
// (Zhang's calibration constraints r1.r2 = 0, |r1| = |r2|, both linear in 1/f^2).
void SolvePlanar(const NormalizedProblem& np, const Matrix3d& axes,
                 std::vector<Candidate>* candidates) {
  // Plane basis: the two principal axes of largest spread; normal = their cross product.
  const Vector3d e1 = axes.col(2);
  const Vector3d e2 = axes.col(1);
  Matrix3d plane_frame;
  plane_frame << e1, e2, e1.cross(e2);
  Eigen::Matrix<double, 9, 8> at = Eigen::Matrix<double, 9, 8>::Zero();
  for (int i = 0; i < 4; ++i) {
    const Vector3d h(np.world[i].dot(e1), np.world[i].dot(e2), 1.0);
    at.block<3, 1>(0, 2 * i) = h;
    at.block<3, 1>(6, 2 * i) = -np.image[i](0) * h;
    at.block<3, 1>(3, 2 * i + 1) = h;
    at.block<3, 1>(6, 2 * i + 1) = -np.image[i](1) * h;
  }
  const Eigen::Matrix<double, 9, 1> h = OrthogonalComplement(at);
  Matrix3d hom;
  hom << h.segment<3>(0).transpose(), h.segment<3>(3).transpose(), h.segment<3>(6).transpose();

  // r1.r2 = 0 and |r1|^2 - |r2|^2 = 0 with r_j ~ diag(1/f, 1/f, 1) h_j: a_k w + b_k = 0 in
  // w = 1/f^2, solved in the least squares sense.
  const double a1 = hom(0, 0) * hom(0, 1) + hom(1, 0) * hom(1, 1);
  const double b1 = hom(2, 0) * hom(2, 1);
  const double a2 =
      hom(0, 0) * hom(0, 0) + hom(1, 0) * hom(1, 0) - hom(0, 1) * hom(0, 1) - hom(1, 1) * hom(1, 1);
  const double b2 = hom(2, 0) * hom(2, 0) - hom(2, 1) * hom(2, 1);
  const double w = -(a1 * b1 + a2 * b2) / (a1 * a1 + a2 * a2);
  if (!(w > 0.0) || !std::isfinite(w)) return;  // e.g. a fronto-parallel plane: f unobservable
  const double inv_f = std::sqrt(w);
  Matrix3d g = hom;
  g.topRows<2>() *= inv_f;
  const double scale = 0.5 * (g.col(0).norm() + g.col(1).norm());
  if (!(scale > 0.0)) return;
  g /= scale;
  // Put the plane's centre (the world centroid) in front of the camera.
  if (g(2, 2) < 0.0) g = -g;
  // Nearest orthonormal pair to (g1, g2), symmetric in both.
  const Vector3d sum = (g.col(0) + g.col(1)).normalized();
  const Vector3d diff = (g.col(0) - g.col(1)).normalized();
  const Vector3d r1 = (sum + diff) / std::sqrt(2.0);
  const Vector3d r2 = (sum - diff) / std::sqrt(2.0);
  Matrix3d r_plane;
  r_plane << r1, r2, r1.cross(r2);
  Candidate c;
  c.rotation = r_plane * plane_frame.transpose();
  c.translation = g.col(2);
  c.focal = 1.0 / inv_f;
  candidates->push_back(c);
}

}  // namespace

int P4Pf(const std::array<Eigen::Vector2d, 4>& points2D,
         const std::array<Eigen::Vector3d, 4>& points3D, std::vector<CameraPose>* poses,
         std::vector<double>* focal_lengths) {
  poses->clear();
  focal_lengths->clear();

  NormalizedProblem np;
  for (int i = 0; i < 4; ++i) {
    np.image_scale += points2D[i].norm();
    np.centroid += points3D[i];
  }
  np.image_scale /= 4.0;
  np.centroid /= 4.0;
  for (int i = 0; i < 4; ++i) np.world_scale += (points3D[i] - np.centroid).squaredNorm();
  np.world_scale = std::sqrt(np.world_scale / 4.0);
  if (!(np.image_scale > 0.0) || !(np.world_scale > 0.0) || !std::isfinite(np.image_scale) ||
      !std::isfinite(np.world_scale)) {
    return 0;
  }
  Matrix3d scatter = Matrix3d::Zero();
  for (int i = 0; i < 4; ++i) {
    np.image[i] = points2D[i] / np.image_scale;
    np.world[i] = (points3D[i] - np.centroid) / np.world_scale;
    scatter += np.world[i] * np.world[i].transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Matrix3d> principal(scatter);
  const Vector3d variances = principal.eigenvalues().cwiseMax(0.0);  // ascending, sum 4
  if (!(variances(1) > 1e-12 * variances(2))) return 0;              // collinear points
  const double flatness = std::sqrt(variances(0) / variances(2));

  std::vector<Candidate> candidates;
  if (flatness >= kOnlyPlanar) SolveGeneral(np, &candidates);
  if (flatness < kAlsoPlanar) SolvePlanar(np, principal.eigenvectors(), &candidates);

  // Back to the caller's units, keeping solutions with all four points in front.
  std::vector<std::pair<double, int>> order;
  std::vector<CameraPose> solved;
  std::vector<double> focals;
  for (Candidate& c : candidates) {
    const Eigen::Quaterniond rotation = Eigen::Quaterniond(c.rotation).normalized();
    const Matrix3d r = rotation.toRotationMatrix();
    double error = 0.0;
    bool in_front = true;
    for (int k = 0; k < 4; ++k) {
      const Vector3d x = r * np.world[k] + c.translation;
      in_front = in_front && x(2) > 0.0;
      error += (c.focal * x.hnormalized() - np.image[k]).squaredNorm();
    }
    // X_c = s (R X' + t') with X' = (X - centroid) / s.
    const Vector3d t = np.world_scale * c.translation - r * np.centroid;
    if (!in_front || !std::isfinite(error) || !t.allFinite()) continue;
    order.emplace_back(std::sqrt(error / 4.0), static_cast<int>(solved.size()));
    solved.emplace_back(rotation, t);
    focals.push_back(c.focal * np.image_scale);
  }
  std::sort(order.begin(), order.end());
  for (const auto& [error, index] : order) {
    poses->push_back(solved[index]);
    focal_lengths->push_back(focals[index]);
  }
  return static_cast<int>(poses->size());
}

}  // namespace cwloc
