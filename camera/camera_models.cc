#include "camera/camera_models.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace cwloc {
namespace {

constexpr std::array<CameraModelInfo, 18> kModels = {{
    {CameraModelId::kSimplePinhole, "SIMPLE_PINHOLE", 3, true},
    {CameraModelId::kPinhole, "PINHOLE", 4, true},
    {CameraModelId::kSimpleRadial, "SIMPLE_RADIAL", 4, true},
    {CameraModelId::kRadial, "RADIAL", 5, true},
    {CameraModelId::kOpenCV, "OPENCV", 8, true},
    {CameraModelId::kOpenCVFisheye, "OPENCV_FISHEYE", 8, true},
    {CameraModelId::kFullOpenCV, "FULL_OPENCV", 12, true},
    {CameraModelId::kFOV, "FOV", 5, true},
    {CameraModelId::kSimpleRadialFisheye, "SIMPLE_RADIAL_FISHEYE", 4, true},
    {CameraModelId::kRadialFisheye, "RADIAL_FISHEYE", 5, true},
    {CameraModelId::kThinPrismFisheye, "THIN_PRISM_FISHEYE", 12, true},
    {CameraModelId::kRadTanThinPrismFisheye, "RAD_TAN_THIN_PRISM_FISHEYE", 16, true},
    {CameraModelId::kSimpleDivision, "SIMPLE_DIVISION", 4, true},
    {CameraModelId::kDivision, "DIVISION", 5, true},
    {CameraModelId::kSimpleFisheye, "SIMPLE_FISHEYE", 3, true},
    {CameraModelId::kFisheye, "FISHEYE", 4, true},
    {CameraModelId::kEUCM, "EUCM", 6, true},
    {CameraModelId::kEquirectangular, "EQUIRECTANGULAR", 2, true},
}};

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

const CameraModelInfo* Lookup(CameraModelId model) {
  const auto index = static_cast<int32_t>(model);
  if (index < 0 || index >= static_cast<int32_t>(kModels.size())) return nullptr;
  return &kModels[static_cast<size_t>(index)];
}

// A forward-mode dual number carrying d/du and d/dv, so that the distortion functions below
// give Newton its 2x2 Jacobian exactly, without a second hand-written derivative per model.
struct Dual {
  double a = 0, du = 0, dv = 0;
};
inline Dual operator+(Dual x, Dual y) { return {x.a + y.a, x.du + y.du, x.dv + y.dv}; }
inline Dual operator*(Dual x, Dual y) {
  return {x.a * y.a, x.du * y.a + x.a * y.du, x.dv * y.a + x.a * y.dv};
}
inline Dual operator/(Dual x, Dual y) {
  const double inv = 1.0 / y.a;
  const double q = x.a * inv;
  return {q, (x.du - q * y.du) * inv, (x.dv - q * y.dv) * inv};
}
inline Dual operator+(Dual x, double c) { return {x.a + c, x.du, x.dv}; }
inline Dual operator+(double c, Dual x) { return x + c; }
inline Dual operator*(double c, Dual x) { return {c * x.a, c * x.du, c * x.dv}; }

// Models whose pixel -> normalized mapping needs an iterative inverse of the distortion.
// Distort maps undistorted coordinates (the normalized plane, or for fisheye models the
// equidistant plane theta * direction) to distorted ones; `k` points at the extra params.
template <typename T>
bool Distort(CameraModelId model, const double* k, const T& u, const T& v, T* ud, T* vd) {
  const T u2 = u * u;
  const T v2 = v * v;
  const T uv = u * v;
  const T r2 = u2 + v2;
  switch (model) {
    case CameraModelId::kSimpleRadial:
    case CameraModelId::kSimpleRadialFisheye: {
      const T s = 1.0 + k[0] * r2;
      *ud = u * s;
      *vd = v * s;
      return true;
    }
    case CameraModelId::kRadial:
    case CameraModelId::kRadialFisheye: {
      const T s = 1.0 + r2 * (k[0] + k[1] * r2);
      *ud = u * s;
      *vd = v * s;
      return true;
    }
    case CameraModelId::kOpenCV: {  // k1, k2, p1, p2
      const T s = 1.0 + r2 * (k[0] + k[1] * r2);
      *ud = u * s + 2.0 * k[2] * uv + k[3] * (r2 + 2.0 * u2);
      *vd = v * s + 2.0 * k[3] * uv + k[2] * (r2 + 2.0 * v2);
      return true;
    }
    case CameraModelId::kFullOpenCV: {  // k1, k2, p1, p2, k3, k4, k5, k6
      const T num = 1.0 + r2 * (k[0] + r2 * (k[1] + k[4] * r2));
      const T den = 1.0 + r2 * (k[5] + r2 * (k[6] + k[7] * r2));
      const T s = num / den;
      *ud = u * s + 2.0 * k[2] * uv + k[3] * (r2 + 2.0 * u2);
      *vd = v * s + 2.0 * k[3] * uv + k[2] * (r2 + 2.0 * v2);
      return true;
    }
    case CameraModelId::kOpenCVFisheye: {  // k1..k4 on theta^2
      const T s = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * (k[2] + k[3] * r2)));
      *ud = u * s;
      *vd = v * s;
      return true;
    }
    case CameraModelId::kThinPrismFisheye: {  // k1, k2, p1, p2, k3, k4, sx1, sy1
      const T s = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * (k[4] + k[5] * r2)));
      *ud = u * s + 2.0 * k[2] * uv + k[3] * (r2 + 2.0 * u2) + k[6] * r2;
      *vd = v * s + 2.0 * k[3] * uv + k[2] * (r2 + 2.0 * v2) + k[7] * r2;
      return true;
    }
    case CameraModelId::kRadTanThinPrismFisheye: {  // k0..k5, p0, p1, s0..s3
      // Radial polynomial in theta^2 first, then tangential and thin-prism terms on the result.
      // 1 + k0 t + k1 t^2 + ... + k5 t^6 with t = theta^2, Horner-style.
      T acc = k[4] + k[5] * r2;
      for (int i = 3; i >= 0; --i) acc = k[i] + r2 * acc;
      const T radial = 1.0 + r2 * acc;
      const T x = u * radial;
      const T y = v * radial;
      const T x2 = x * x;
      const T y2 = y * y;
      const T xy = x * y;
      const T q2 = x2 + y2;
      const T q4 = q2 * q2;
      *ud = x + 2.0 * k[7] * xy + k[6] * (q2 + 2.0 * x2) + k[8] * q2 + k[9] * q4;
      *vd = y + 2.0 * k[6] * xy + k[7] * (q2 + 2.0 * y2) + k[10] * q2 + k[11] * q4;
      return true;
    }
    default:
      return false;
  }
}

// Solves Distort(x) = target by Newton's method with a backtracking line search.
bool Undistort(CameraModelId model, const double* k, double tu, double tv, double* u, double* v) {
  constexpr int kMaxIterations = 100;
  const double scale = std::max(1.0, std::hypot(tu, tv));
  const double tolerance = 1e-14 * scale;  // converged
  const double acceptable = 1e-9 * scale;  // stagnated but still a valid inverse

  auto residual = [&](double x, double y, double* rx, double* ry) {
    double dx = 0, dy = 0;
    Distort(model, k, x, y, &dx, &dy);
    *rx = dx - tu;
    *ry = dy - tv;
    return std::hypot(*rx, *ry);
  };

  double x = tu, y = tv;
  double rx = 0, ry = 0;
  double norm = residual(x, y, &rx, &ry);
  for (int iteration = 0; iteration < kMaxIterations && std::isfinite(norm); ++iteration) {
    if (norm <= tolerance) break;
    Dual du_x, dv_x;
    Distort(model, k, Dual{x, 1, 0}, Dual{y, 0, 1}, &du_x, &dv_x);
    const double det = du_x.du * dv_x.dv - du_x.dv * dv_x.du;
    if (!std::isfinite(det) || std::abs(det) < 1e-300) return false;
    const double step_x = (dv_x.dv * rx - du_x.dv * ry) / det;
    const double step_y = (du_x.du * ry - dv_x.du * rx) / det;
    // Halve the step until the residual decreases: plain Newton can overshoot where the
    // distortion polynomial is steep.
    double t = 1.0;
    bool improved = false;
    for (int halving = 0; halving < 40; ++halving, t *= 0.5) {
      double nrx = 0, nry = 0;
      const double nx = x - t * step_x;
      const double ny = y - t * step_y;
      const double new_norm = residual(nx, ny, &nrx, &nry);
      if (new_norm < norm) {
        x = nx, y = ny, rx = nrx, ry = nry, norm = new_norm;
        improved = true;
        break;
      }
    }
    if (!improved) break;  // at the floor of floating-point precision
  }
  if (!(norm <= acceptable)) return false;
  *u = x;
  *v = y;
  return true;
}

// Focal lengths and principal point of the perspective models.
struct Intrinsics {
  double fx, fy, cx, cy;
  const double* extra;
};

Intrinsics SplitParams(CameraModelId model, std::span<const double> p) {
  switch (model) {
    case CameraModelId::kSimplePinhole:
    case CameraModelId::kSimpleRadial:
    case CameraModelId::kRadial:
    case CameraModelId::kSimpleRadialFisheye:
    case CameraModelId::kRadialFisheye:
    case CameraModelId::kSimpleDivision:
    case CameraModelId::kSimpleFisheye:
      return {p[0], p[0], p[1], p[2], p.data() + 3};
    default:
      return {p[0], p[1], p[2], p[3], p.data() + 4};
  }
}

bool IsFisheye(CameraModelId model) {
  switch (model) {
    case CameraModelId::kOpenCVFisheye:
    case CameraModelId::kSimpleRadialFisheye:
    case CameraModelId::kRadialFisheye:
    case CameraModelId::kThinPrismFisheye:
    case CameraModelId::kRadTanThinPrismFisheye:
    case CameraModelId::kSimpleFisheye:
    case CameraModelId::kFisheye:
      return true;
    default:
      return false;
  }
}

// FOV model (Devernay & Faugeras): r_d = atan(2 r tan(w/2)) / w. The ratios r_d / r and its
// inverse, with their limits for w -> 0 (series to second order) and r -> 0.
double FovDistortFactor(double omega, double r) {
  if (std::abs(omega) < 1e-6) return 1.0 + omega * omega * (1.0 / 12.0 - r * r / 3.0);
  const double two_tan = 2.0 * std::tan(0.5 * omega);
  if (r < 1e-12) return two_tan / omega;
  return std::atan(r * two_tan) / (r * omega);
}

bool FovUndistortFactor(double omega, double rd, double* factor) {
  if (std::abs(omega) < 1e-6) {
    *factor = 1.0 + omega * omega * (rd * rd / 3.0 - 1.0 / 12.0);
    return true;
  }
  if (rd * std::abs(omega) >= 0.5 * std::numbers::pi) return false;  // beyond 90 degrees
  const double two_tan = 2.0 * std::tan(0.5 * omega);
  if (rd < 1e-12) {
    *factor = omega / two_tan;
    return true;
  }
  *factor = std::tan(rd * omega) / (rd * two_tan);
  return true;
}

bool AllFinite(std::span<const double> values) {
  return std::all_of(values.begin(), values.end(), [](double x) { return std::isfinite(x); });
}

}  // namespace

std::span<const CameraModelInfo> AllCameraModels() { return kModels; }

std::optional<CameraModelInfo> FindCameraModel(int32_t model_id) {
  if (const CameraModelInfo* info = Lookup(static_cast<CameraModelId>(model_id))) return *info;
  return std::nullopt;
}

std::optional<CameraModelInfo> FindCameraModel(std::string_view name) {
  for (const CameraModelInfo& info : kModels) {
    if (info.name == name) return info;
  }
  return std::nullopt;
}

std::string_view CameraModelName(CameraModelId model) {
  const CameraModelInfo* info = Lookup(model);
  return info ? info->name : std::string_view();
}

int CameraModelNumParams(CameraModelId model) {
  const CameraModelInfo* info = Lookup(model);
  return info ? info->num_params : -1;
}

bool ProjectToPixel(CameraModelId model, std::span<const double> params,
                    const std::array<double, 3>& point_in_camera, std::array<double, 2>* pixel) {
  const CameraModelInfo* info = Lookup(model);
  if (!info || params.size() != static_cast<size_t>(info->num_params)) return false;
  const auto [X, Y, Z] = point_in_camera;
  if (!std::isfinite(X) || !std::isfinite(Y) || !std::isfinite(Z)) return false;

  if (model == CameraModelId::kEquirectangular) {
    const double horizontal = std::hypot(X, Z);
    if (horizontal + std::abs(Y) < kEpsilon) return false;
    const double azimuth = std::atan2(X, Z);              // 0 straight ahead, +pi/2 towards +x
    const double elevation = std::atan2(-Y, horizontal);  // +pi/2 up (-y)
    (*pixel)[0] = (azimuth / (2 * std::numbers::pi) + 0.5) * params[0];
    (*pixel)[1] = (0.5 - elevation / std::numbers::pi) * params[1];
    return true;
  }

  if (Z < kEpsilon) return false;
  const Intrinsics in = SplitParams(model, params);
  double xd = 0, yd = 0;  // distorted coordinates on the plane that fx, fy, cx, cy map to pixels
  switch (model) {
    case CameraModelId::kSimpleDivision:
    case CameraModelId::kDivision: {
      // Fitzgibbon's division model: the distorted point p satisfies p / (1 + k|p|^2) = X/Z.
      // With p = s (X, Y): k |(X,Y)|^2 s^2 - Z s + 1 = 0; take the root that tends to 1/Z.
      const double k = in.extra[0];
      const double disc = Z * Z - 4.0 * k * (X * X + Y * Y);
      if (disc < 0) return false;
      const double s = 2.0 / (Z + std::sqrt(disc));
      xd = s * X;
      yd = s * Y;
      break;
    }
    case CameraModelId::kEUCM: {
      const double alpha = in.extra[0];
      const double beta = in.extra[1];
      const double rho2 = beta * (X * X + Y * Y) + Z * Z;
      if (rho2 < 0) return false;
      const double den = alpha * std::sqrt(rho2) + (1.0 - alpha) * Z;
      if (den < kEpsilon) return false;
      xd = X / den;
      yd = Y / den;
      break;
    }
    case CameraModelId::kFOV: {
      const double u = X / Z, v = Y / Z;
      const double s = FovDistortFactor(in.extra[0], std::hypot(u, v));
      xd = u * s;
      yd = v * s;
      break;
    }
    default: {
      double u = X / Z, v = Y / Z;
      if (IsFisheye(model)) {
        // Equidistant mapping: the plane coordinate is the angle to the axis.
        const double r = std::hypot(u, v);
        if (r > kEpsilon) {
          const double s = std::atan(r) / r;
          u *= s;
          v *= s;
        }
      }
      if (!Distort(model, in.extra, u, v, &xd, &yd)) {
        xd = u;  // models without distortion
        yd = v;
      }
      break;
    }
  }
  (*pixel)[0] = in.fx * xd + in.cx;
  (*pixel)[1] = in.fy * yd + in.cy;
  return std::isfinite((*pixel)[0]) && std::isfinite((*pixel)[1]);
}

bool PixelToNormalized(CameraModelId model, std::span<const double> params,
                       const std::array<double, 2>& pixel, std::array<double, 2>* normalized) {
  const CameraModelInfo* info = Lookup(model);
  if (!info || params.size() != static_cast<size_t>(info->num_params)) return false;
  if (!AllFinite(params) || !std::isfinite(pixel[0]) || !std::isfinite(pixel[1])) return false;

  if (model == CameraModelId::kEquirectangular) {
    const double azimuth = 2 * std::numbers::pi * (pixel[0] / params[0] - 0.5);
    const double elevation = std::numbers::pi * (0.5 - pixel[1] / params[1]);
    const double rx = std::cos(elevation) * std::sin(azimuth);
    const double ry = -std::sin(elevation);
    const double rz = std::cos(elevation) * std::cos(azimuth);
    if (rz <= kEpsilon) return false;  // not in front of the camera
    (*normalized)[0] = rx / rz;
    (*normalized)[1] = ry / rz;
    return true;
  }

  const Intrinsics in = SplitParams(model, params);
  if (in.fx == 0 || in.fy == 0) return false;
  const double xd = (pixel[0] - in.cx) / in.fx;
  const double yd = (pixel[1] - in.cy) / in.fy;
  double u = 0, v = 0;
  switch (model) {
    case CameraModelId::kSimpleDivision:
    case CameraModelId::kDivision: {
      const double den = 1.0 + in.extra[0] * (xd * xd + yd * yd);
      if (den < kEpsilon) return false;
      u = xd / den;
      v = yd / den;
      break;
    }
    case CameraModelId::kEUCM: {
      const double alpha = in.extra[0];
      const double beta = in.extra[1];
      const double r2 = xd * xd + yd * yd;
      const double radicand = 1.0 - (2.0 * alpha - 1.0) * beta * r2;
      if (radicand < 0) return false;
      const double mz =
          (1.0 - alpha * alpha * beta * r2) / (alpha * std::sqrt(radicand) + 1.0 - alpha);
      if (mz < kEpsilon) return false;
      u = xd / mz;
      v = yd / mz;
      break;
    }
    case CameraModelId::kFOV: {
      double s = 0;
      if (!FovUndistortFactor(in.extra[0], std::hypot(xd, yd), &s)) return false;
      u = xd * s;
      v = yd * s;
      break;
    }
    default: {
      if (!Distort(model, in.extra, xd, yd, &u, &v)) {
        u = xd;  // no distortion
        v = yd;
      } else if (!Undistort(model, in.extra, xd, yd, &u, &v)) {
        return false;
      }
      if (IsFisheye(model)) {
        const double theta = std::hypot(u, v);
        if (theta >= 0.5 * std::numbers::pi) return false;  // at or beyond 90 degrees
        if (theta > kEpsilon) {
          const double s = std::tan(theta) / theta;
          u *= s;
          v *= s;
        }
      }
      break;
    }
  }
  if (!std::isfinite(u) || !std::isfinite(v)) return false;
  (*normalized)[0] = u;
  (*normalized)[1] = v;
  return true;
}

double MeanFocalLength(CameraModelId model, std::span<const double> params) {
  const CameraModelInfo* info = Lookup(model);
  if (!info || params.size() != static_cast<size_t>(info->num_params)) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  if (model == CameraModelId::kEquirectangular) return params[0] / (2 * std::numbers::pi);
  const Intrinsics in = SplitParams(model, params);
  return 0.5 * (in.fx + in.fy);
}

}  // namespace cwloc
