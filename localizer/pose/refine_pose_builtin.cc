// The builtin refiner of refine_pose.h: cwloc's own Levenberg-Marquardt on the problem that
// refine_pose_ceres.cc hands to Ceres, following the trust-region rules of Ceres 2.1 (its
// TrustRegionMinimizer with the LEVENBERG_MARQUARDT strategy, DENSE_QR, Jacobi scaling and the
// Solver::Options defaults) so that both take the same steps and stop at the same point:
//   - the residual blocks are weighted by rho'(s), s = |r|^2 (Ceres' loss corrector, which
//     drops its curvature term where rho'' < 0: everywhere for the Cauchy loss);
//   - the Jacobian's columns are scaled by 1 / (1 + |column|), computed once at the start;
//   - the step solves (J^T J + diag(D) / mu) x = -J^T r with D = diag(J^T J) clamped to
//     [1e-6, 1e32] and mu the trust-region radius (1e4 at first);
//   - a step is taken when (cost - new cost) / (the linear model's decrease) > 1e-3, then mu
//     is divided by max(1/3, 1 - (2 rho - 1)^3); else mu is halved, quartered, ...; a step
//     whose model does not decrease is invalid, and 5 of them in a row fail the solve;
//   - a candidate with a point behind the camera (or a non-finite residual) costs infinity;
//   - a gravity prior is one more residual block without loss, on the rotation only;
//   - it stops at |cost change| <= 1e-10 cost, a step of at most 1e-10 (|x| + 1e-10) after a
//     first accepted one, a gradient of max norm <= 1e-10, max_iterations, or mu <= 1e-32.
// The rotation moves on the left by Ceres' quaternion increment (cos |d|, sin |d| d / |d|).
// Derivatives are analytic. Determinism across platforms: scalar loops in a fixed order, no
// threads, and CMake compiles this file with -ffp-contract=off (aarch64 would fuse a*b+c).
#include <algorithm>
#include <cmath>
#include <limits>

#include "localizer/pose/refine_pose_solver.h"
#include "localizer/pose/reprojection_residual.h"
#include "robust/cholesky.h"

namespace cwloc {
namespace {

constexpr int kMaxParams = kMaxCholeskySize;  // rotation 3, translation 3, focal length, k

// Ceres' Solver::Options defaults, and the tolerances refine_pose_ceres.cc sets.
constexpr double kFunctionTolerance = 1e-10;
constexpr double kParameterTolerance = 1e-10;
constexpr double kGradientTolerance = 1e-10;
constexpr double kInitialRadius = 1e4;
constexpr double kMaxRadius = 1e16;
constexpr double kMinRadius = 1e-32;
constexpr double kMinRelativeDecrease = 1e-3;
constexpr double kMinDiagonal = 1e-6;
constexpr double kMaxDiagonal = 1e32;
constexpr int kMaxConsecutiveInvalidSteps = 5;

using Matrix = double[kMaxParams][kMaxParams];

// A residual's derivatives with respect to the point in camera coordinates, the focal length
// and k.
struct Derivatives {
  double dz[2][3];
  double df[2];
  double dk[2];
};

// d(pixel) / dz from d(pixel) / d(u, v) = [a b; b c] and d(u, v) / dz = [1 0 -u; 0 1 -v] / z.
void ThroughProjection(double a, double b, double c, double u, double v, double inv_z,
                       double dz[2][3]) {
  dz[0][0] = a * inv_z;
  dz[0][1] = b * inv_z;
  dz[0][2] = -(a * u + b * v) * inv_z;
  dz[1][0] = b * inv_z;
  dz[1][1] = c * inv_z;
  dz[1][2] = -(b * u + c * v) * inv_z;
}

struct PinholeModel {
  static void Residual(const double* z, const RefinementParameters& x, const Eigen::Vector2d& pixel,
                       double* r) {
    PinholeResidual(z, x.focal, pixel, r);
  }
  static void Differentiate(const double* z, const RefinementParameters& x, Derivatives* out) {
    const double inv_z = 1.0 / z[2];
    const double u = z[0] * inv_z;
    const double v = z[1] * inv_z;
    ThroughProjection(x.focal, 0.0, x.focal, u, v, inv_z, out->dz);
    out->df[0] = u;
    out->df[1] = v;
    out->dk[0] = 0.0;
    out->dk[1] = 0.0;
  }
};

struct RadialModel {
  static void Residual(const double* z, const RefinementParameters& x, const Eigen::Vector2d& pixel,
                       double* r) {
    RadialResidual(z, x.focal, x.k, pixel, r);
  }
  static void Differentiate(const double* z, const RefinementParameters& x, Derivatives* out) {
    const double inv_z = 1.0 / z[2];
    const double u = z[0] * inv_z;
    const double v = z[1] * inv_z;
    const double rr = u * u + v * v;
    const double d = 1.0 + x.k * rr;
    ThroughProjection(x.focal * (d + 2.0 * x.k * u * u), 2.0 * x.focal * x.k * u * v,
                      x.focal * (d + 2.0 * x.k * v * v), u, v, inv_z, out->dz);
    out->df[0] = d * u;
    out->df[1] = d * v;
    out->dk[0] = x.focal * rr * u;
    out->dk[1] = x.focal * rr * v;
  }
};

// The cost and, on request, the normal equations of the loss-weighted Jacobian in the tangent
// space (rotation increment, translation, then f and k when refined).
struct Normal {
  double cost = 0.0;
  Matrix h = {};              // J^T W J
  double g[kMaxParams] = {};  // J^T W r, the gradient
};

// What the covariance of the solution needs (LinearizeWithBuiltin, refine_pose_solver.h).
struct Sandwich {
  Matrix hessian = {};          // of the robust cost, exact
  Matrix scores = {};           // sum of the points' gradient outer products
  Matrix design = {};           // the points' J^T J, without loss weights
  Matrix prior = {};            // the gravity prior's information
  double squared_scores = 0.0;  // sum of rho'^2 |r|^2 over the points
  double curvature = 0.0;       // sum of rho' + rho'' |r|^2 over the points
  double squared_curvature = 0.0;
};

template <typename Model>
class Evaluator {
 public:
  explicit Evaluator(const RefinementProblem& problem)
      : problem_(problem),
        num_params_(6 + int{problem.refine_focal_length} +
                    int{problem.radial && problem.refine_radial_distortion}) {}

  int num_params() const { return num_params_; }

  // False where Ceres' evaluation fails: a point not in front of the camera, or a non-finite
  // residual or derivative.
  bool Evaluate(const RefinementParameters& x, Normal* out, bool linearize,
                Sandwich* sandwich = nullptr) const {
    // R = I + 2 M for the unit quaternion (w, x, y, z), as ceres::UnitQuaternionRotatePoint.
    const double* q = x.q_wxyz;
    const double m[3][3] = {
        {-q[2] * q[2] - q[3] * q[3], q[1] * q[2] - q[0] * q[3], q[0] * q[2] + q[1] * q[3]},
        {q[0] * q[3] + q[1] * q[2], -q[1] * q[1] - q[3] * q[3], q[2] * q[3] - q[0] * q[1]},
        {q[1] * q[3] - q[0] * q[2], q[0] * q[1] + q[2] * q[3], -q[1] * q[1] - q[2] * q[2]}};
    const bool robust = problem_.loss_scale_px > 0.0;
    const double b = problem_.loss_scale_px * problem_.loss_scale_px;
    const double c = 1.0 / b;
    const int n = num_params_;
    *out = Normal();
    for (const uint32_t i : problem_.indices) {
      const Eigen::Vector3d& p = problem_.points3D[i];
      double y[3];  // R p
      for (int row = 0; row < 3; ++row) {
        y[row] = 2.0 * (m[row][0] * p(0) + m[row][1] * p(1) + m[row][2] * p(2)) + p(row);
      }
      const double z[3] = {y[0] + x.t[0], y[1] + x.t[1], y[2] + x.t[2]};
      if (!(z[2] > 0.0)) return false;
      double r[2];
      Model::Residual(z, x, problem_.pixels[i], r);
      if (!std::isfinite(r[0]) || !std::isfinite(r[1])) return false;
      const double s = r[0] * r[0] + r[1] * r[1];
      double weight = 1.0;  // rho'(s)
      if (robust) {
        const double sum = 1.0 + s * c;
        out->cost += 0.5 * (b * std::log(sum));
        weight = std::max(std::numeric_limits<double>::min(), 1.0 / sum);
      } else {
        out->cost += 0.5 * s;
      }
      if (!linearize) continue;
      Derivatives deriv;
      Model::Differentiate(z, x, &deriv);
      // The rotation increment d moves z by -2 [y]x d.
      double jac[2][kMaxParams];
      for (int row = 0; row < 2; ++row) {
        const double* dz = deriv.dz[row];
        jac[row][0] = 2.0 * (dz[2] * y[1] - dz[1] * y[2]);
        jac[row][1] = 2.0 * (dz[0] * y[2] - dz[2] * y[0]);
        jac[row][2] = 2.0 * (dz[1] * y[0] - dz[0] * y[1]);
        jac[row][3] = dz[0];
        jac[row][4] = dz[1];
        jac[row][5] = dz[2];
        int col = 6;
        if (problem_.refine_focal_length) jac[row][col++] = deriv.df[row];
        if (problem_.radial && problem_.refine_radial_distortion) jac[row][col++] = deriv.dk[row];
      }
      for (int a = 0; a < n; ++a) {
        const double w0 = weight * jac[0][a];
        const double w1 = weight * jac[1][a];
        out->g[a] += w0 * r[0] + w1 * r[1];
        for (int col = 0; col <= a; ++col) out->h[a][col] += w0 * jac[0][col] + w1 * jac[1][col];
      }
      if (sandwich != nullptr)
        AddSandwich(jac, r, weight, robust ? -c * weight * weight : 0.0, sandwich);
    }
    if (problem_.gravity.has_value()) {
      Matrix before;
      if (sandwich != nullptr)
        std::copy(&out->h[0][0], &out->h[0][0] + kMaxParams * kMaxParams, &before[0][0]);
      AddGravity(m, linearize, out);
      // A prior of unit-variance residuals: its information is curvature and score alike.
      for (int a = 0; sandwich != nullptr && a < n; ++a) {
        for (int col = 0; col <= a; ++col) {
          const double information = out->h[a][col] - before[a][col];
          sandwich->hessian[a][col] += information;
          sandwich->scores[a][col] += information;
          sandwich->prior[a][col] += information;
        }
      }
    }
    for (int a = 0; a < n; ++a) {
      if (!std::isfinite(out->g[a])) return false;
      for (int col = 0; col <= a; ++col) {
        if (!std::isfinite(out->h[a][col])) return false;
        out->h[col][a] = out->h[a][col];
      }
    }
    return std::isfinite(out->cost);
  }

 private:
  // One point's share of the sums: its exact Hessian of 0.5 rho(|r|^2), rho' J^T J + 2 rho''
  // (J^T r)(J^T r)^T, its score's outer product rho'^2 (J^T r)(J^T r)^T (lower triangles), and
  // rho' + rho'' |r|^2, that Hessian's mean curvature over the residual's two directions.
  void AddSandwich(const double (&jac)[2][kMaxParams], const double (&r)[2], double rho1,
                   double rho2, Sandwich* sandwich) const {
    double jr[kMaxParams];
    for (int a = 0; a < num_params_; ++a) jr[a] = jac[0][a] * r[0] + jac[1][a] * r[1];
    for (int a = 0; a < num_params_; ++a) {
      for (int col = 0; col <= a; ++col) {
        const double jj = jac[0][a] * jac[0][col] + jac[1][a] * jac[1][col];
        sandwich->hessian[a][col] += rho1 * jj + 2.0 * rho2 * jr[a] * jr[col];
        sandwich->scores[a][col] += rho1 * rho1 * jr[a] * jr[col];
        sandwich->design[a][col] += jj;
      }
    }
    const double squared = r[0] * r[0] + r[1] * r[1];
    const double curvature = rho1 + rho2 * squared;
    sandwich->squared_scores += rho1 * rho1 * squared;
    sandwich->curvature += curvature;
    sandwich->squared_curvature += curvature * curvature;
  }

  // The gravity block w (R g_w - g_c) with R = I + 2 M: no loss (weight 1), and only the rotation
  // increment moves it, R g_w by -2 [R g_w]x d as every point.
  void AddGravity(const double (&m)[3][3], bool linearize, Normal* out) const {
    const GravityConstraint& gravity = *problem_.gravity;
    const Eigen::Vector3d& p = gravity.in_world;
    const double w = gravity.weight;
    double y[3], r[3];
    for (int row = 0; row < 3; ++row) {
      y[row] = 2.0 * (m[row][0] * p(0) + m[row][1] * p(1) + m[row][2] * p(2)) + p(row);
      r[row] = w * (y[row] - gravity.in_camera(row));
    }
    out->cost += 0.5 * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!linearize) return;
    // Row k of -2 w [y]x, as the points' rows with d(residual) / dz = w e_k.
    const double jac[3][3] = {{0.0, 2.0 * w * y[2], -2.0 * w * y[1]},
                              {-2.0 * w * y[2], 0.0, 2.0 * w * y[0]},
                              {2.0 * w * y[1], -2.0 * w * y[0], 0.0}};
    for (int a = 0; a < 3; ++a) {
      out->g[a] += jac[0][a] * r[0] + jac[1][a] * r[1] + jac[2][a] * r[2];
      for (int col = 0; col <= a; ++col) {
        out->h[a][col] +=
            jac[0][a] * jac[0][col] + jac[1][a] * jac[1][col] + jac[2][a] * jac[2][col];
      }
    }
  }

  const RefinementProblem& problem_;
  const int num_params_;
};

// x + delta: the rotation by Ceres' QuaternionManifold (exp(delta) * q, not renormalised),
// the rest additively.
RefinementParameters Plus(const RefinementProblem& problem, const RefinementParameters& x,
                          const double* delta) {
  RefinementParameters out = x;
  const double norm = std::sqrt(delta[0] * delta[0] + delta[1] * delta[1] + delta[2] * delta[2]);
  if (norm != 0.0) {
    const double s = std::sin(norm) / norm;
    const double dw = std::cos(norm), dx = s * delta[0], dy = s * delta[1], dz = s * delta[2];
    const double* q = x.q_wxyz;
    out.q_wxyz[0] = dw * q[0] - dx * q[1] - dy * q[2] - dz * q[3];
    out.q_wxyz[1] = dw * q[1] + dx * q[0] + dy * q[3] - dz * q[2];
    out.q_wxyz[2] = dw * q[2] - dx * q[3] + dy * q[0] + dz * q[1];
    out.q_wxyz[3] = dw * q[3] + dx * q[2] - dy * q[1] + dz * q[0];
  }
  for (int i = 0; i < 3; ++i) out.t[i] = x.t[i] + delta[3 + i];
  int col = 6;
  if (problem.refine_focal_length) out.focal = x.focal + delta[col++];
  if (problem.radial && problem.refine_radial_distortion) out.k = x.k + delta[col++];
  return out;
}

// The free parameters as Ceres' state vector: the quaternion, t, then f and k when refined.
int Ambient(const RefinementProblem& problem, const RefinementParameters& x, double* out) {
  int size = 0;
  for (const double value : x.q_wxyz) out[size++] = value;
  for (const double value : x.t) out[size++] = value;
  if (problem.refine_focal_length) out[size++] = x.focal;
  if (problem.radial && problem.refine_radial_distortion) out[size++] = x.k;
  return size;
}

double AmbientNorm(const RefinementProblem& problem, const RefinementParameters& x) {
  double values[kMaxParams + 1];
  const int size = Ambient(problem, x, values);
  double sum = 0.0;
  for (int i = 0; i < size; ++i) sum += values[i] * values[i];
  return std::sqrt(sum);
}

// |x - y|_2, or |x - y|_inf with max_norm.
double AmbientDistance(const RefinementProblem& problem, const RefinementParameters& x,
                       const RefinementParameters& y, bool max_norm) {
  double a[kMaxParams + 1], b[kMaxParams + 1];
  const int size = Ambient(problem, x, a);
  Ambient(problem, y, b);
  double sum = 0.0, max = 0.0;
  for (int i = 0; i < size; ++i) {
    const double d = a[i] - b[i];
    sum += d * d;
    max = std::max(max, std::abs(d));
  }
  return max_norm ? max : std::sqrt(sum);
}

// Ceres' gradient norm on a manifold: |x - Plus(x, -gradient)|_inf.
double GradientMaxNorm(const RefinementProblem& problem, const RefinementParameters& x,
                       const Normal& normal, int n) {
  double minus_gradient[kMaxParams];
  for (int i = 0; i < n; ++i) minus_gradient[i] = -normal.g[i];
  return AmbientDistance(problem, x, Plus(problem, x, minus_gradient), /*max_norm=*/true);
}

// Ceres' trust region: its radius mu grows after a step taken, by how well the linear model
// predicted the decrease, and shrinks twice as fast after each step in a row not taken.
struct TrustRegion {
  double radius = kInitialRadius;
  double decrease_factor = 2.0;

  void Accept(double relative_decrease) {
    const double t = 2.0 * relative_decrease - 1.0;
    radius = std::min(kMaxRadius, radius / std::max(1.0 / 3.0, 1.0 - t * t * t));
    decrease_factor = 2.0;
  }
  void Reject() {
    radius /= decrease_factor;
    decrease_factor *= 2.0;
  }
};

// The step of the scaled normal equations (h, g) within the trust region's radius: solves
// (h + diag(h) / radius) step = -g, diag(h) clamped. False for what Ceres calls an invalid step
// (a failed solve, or one whose linear model does not decrease, by `model_cost_change`).
bool SolveStep(int n, const Matrix& h, const double* g, double radius, double* step,
               double* model_cost_change) {
  Matrix damped = {};  // only its n x n corner is read
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) damped[i][j] = h[i][j];
    damped[i][i] += std::clamp(h[i][i], kMinDiagonal, kMaxDiagonal) / radius;
  }
  // Cholesky on the normal equations, where Ceres' DENSE_QR factors [J; D]: the same step up
  // to rounding.
  if (!SolveCholesky(n, &damped[0][0], kMaxParams, g, step)) return false;
  for (int i = 0; i < n; ++i) step[i] = -step[i];
  double linear = 0.0, quadratic = 0.0;
  for (int i = 0; i < n; ++i) {
    linear += step[i] * g[i];
    double row = 0.0;
    for (int j = 0; j < n; ++j) row += h[i][j] * step[j];
    quadratic += step[i] * row;
  }
  *model_cost_change = -(linear + 0.5 * quadratic);
  return *model_cost_change > 0.0;
}

template <typename Model>
bool Minimize(const RefinementProblem& problem, RefinementParameters* parameters,
              PoseRefinementSummary* summary) {
  const Evaluator<Model> evaluator(problem);
  const int n = evaluator.num_params();
  *summary = PoseRefinementSummary();
  RefinementParameters x = *parameters;
  Normal normal;
  if (!evaluator.Evaluate(x, &normal, /*linearize=*/true)) return false;
  summary->initial_cost = normal.cost;

  // Jacobi scaling, fixed at the start; h and g below are of the scaled Jacobian.
  double scale[kMaxParams];
  for (int i = 0; i < n; ++i) scale[i] = 1.0 / (1.0 + std::sqrt(normal.h[i][i]));
  Matrix h;
  double g[kMaxParams];
  const auto scale_normal = [&] {
    for (int i = 0; i < n; ++i) {
      g[i] = scale[i] * normal.g[i];
      for (int j = 0; j < n; ++j) h[i][j] = scale[i] * normal.h[i][j] * scale[j];
    }
  };
  scale_normal();

  double cost = normal.cost;
  double gradient_max_norm = GradientMaxNorm(problem, x, normal, n);
  TrustRegion trust_region;
  int invalid_in_a_row = 0;
  double x_norm = -1.0;  // Ceres sets it at the first accepted step: no parameter test before
  RefinementParameters best = x;
  double best_cost = cost;
  // Ceres' iteration log: iteration 0, then one entry per step that did not stop the solve;
  // the final cost is the smallest cost logged.
  int iteration = 0;
  int logged = 1;
  double final_cost = cost;
  bool last_step_taken = true;
  bool usable = true;
  while (true) {
    if (iteration >= problem.max_iterations) break;
    if (last_step_taken && gradient_max_norm <= kGradientTolerance) break;
    if (trust_region.radius <= kMinRadius) break;
    ++iteration;

    double step[kMaxParams];
    double model_cost_change = 0.0;
    if (!SolveStep(n, h, g, trust_region.radius, step, &model_cost_change)) {
      if (++invalid_in_a_row >= kMaxConsecutiveInvalidSteps) {
        usable = false;
        break;
      }
      trust_region.Reject();
      last_step_taken = false;
      ++logged;
      final_cost = std::min(final_cost, cost);
      continue;
    }
    invalid_in_a_row = 0;

    double delta[kMaxParams];
    for (int i = 0; i < n; ++i) delta[i] = step[i] * scale[i];
    const RefinementParameters candidate = Plus(problem, x, delta);
    Normal candidate_normal;
    const double candidate_cost = evaluator.Evaluate(candidate, &candidate_normal, false)
                                      ? candidate_normal.cost
                                      : std::numeric_limits<double>::max();
    if (x_norm >= 0.0 && AmbientDistance(problem, x, candidate, /*max_norm=*/false) <=
                             kParameterTolerance * (x_norm + kParameterTolerance)) {
      break;
    }
    if (std::abs(cost - candidate_cost) <= kFunctionTolerance * cost) break;

    const double relative_decrease = candidate_cost == std::numeric_limits<double>::max()
                                         ? std::numeric_limits<double>::lowest()
                                         : (cost - candidate_cost) / model_cost_change;
    if (relative_decrease > kMinRelativeDecrease) {
      x = candidate;
      x_norm = AmbientNorm(problem, x);
      if (!evaluator.Evaluate(x, &normal, /*linearize=*/true)) {
        usable = false;
        break;
      }
      scale_normal();
      cost = normal.cost;
      gradient_max_norm = GradientMaxNorm(problem, x, normal, n);
      trust_region.Accept(relative_decrease);
      last_step_taken = true;
      if (cost < best_cost) {
        best = x;
        best_cost = cost;
      }
      final_cost = std::min(final_cost, cost);
    } else {
      trust_region.Reject();
      last_step_taken = false;
      final_cost = std::min(final_cost, candidate_cost);
    }
    ++logged;
  }
  summary->usable = usable;
  summary->iterations = logged;
  summary->final_cost = final_cost;
  if (usable) *parameters = best;
  return usable;
}

}  // namespace

bool RefineWithBuiltin(const RefinementProblem& problem, RefinementParameters* parameters,
                       PoseRefinementSummary* summary) {
  return problem.radial ? Minimize<RadialModel>(problem, parameters, summary)
                        : Minimize<PinholeModel>(problem, parameters, summary);
}

namespace {

template <typename Model>
bool Linearize(const RefinementProblem& problem, const RefinementParameters& parameters,
               Linearization* out) {
  const Evaluator<Model> evaluator(problem);
  Normal normal;
  Sandwich sandwich;
  if (!evaluator.Evaluate(parameters, &normal, /*linearize=*/true, &sandwich)) return false;
  const int n = evaluator.num_params();
  const auto to_eigen = [n](const Matrix& lower, Eigen::MatrixXd* full) {
    full->resize(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j <= i; ++j) (*full)(i, j) = (*full)(j, i) = lower[i][j];
    }
  };
  to_eigen(sandwich.hessian, &out->hessian);
  to_eigen(sandwich.scores, &out->scores);
  to_eigen(sandwich.design, &out->design);
  to_eigen(sandwich.prior, &out->prior);
  out->squared_scores = sandwich.squared_scores;
  out->curvature = sandwich.curvature;
  out->squared_curvature = sandwich.squared_curvature;
  return out->hessian.allFinite() && out->scores.allFinite() && out->design.allFinite() &&
         out->prior.allFinite() && std::isfinite(out->squared_scores) &&
         std::isfinite(out->squared_curvature);
}

}  // namespace

bool LinearizeWithBuiltin(const RefinementProblem& problem, const RefinementParameters& parameters,
                          Linearization* out) {
  return problem.radial ? Linearize<RadialModel>(problem, parameters, out)
                        : Linearize<PinholeModel>(problem, parameters, out);
}

}  // namespace cwloc
