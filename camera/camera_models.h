#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace cwloc {

// COLMAP's camera models, with COLMAP's numeric ids (these ids are what cameras.bin and
// database.db store). Parameter order follows COLMAP's src/colmap/sensor/models.h.
// Ids 0-10 exist since COLMAP 3.x (Debian's 3.8 knows these), 11 since 3.11, 12-15 since
// 4.0 and 16-17 since 4.1.
enum class CameraModelId : int32_t {
  kSimplePinhole = 0,            // f, cx, cy
  kPinhole = 1,                  // fx, fy, cx, cy
  kSimpleRadial = 2,             // f, cx, cy, k
  kRadial = 3,                   // f, cx, cy, k1, k2
  kOpenCV = 4,                   // fx, fy, cx, cy, k1, k2, p1, p2
  kOpenCVFisheye = 5,            // fx, fy, cx, cy, k1, k2, k3, k4
  kFullOpenCV = 6,               // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6
  kFOV = 7,                      // fx, fy, cx, cy, omega
  kSimpleRadialFisheye = 8,      // f, cx, cy, k
  kRadialFisheye = 9,            // f, cx, cy, k1, k2
  kThinPrismFisheye = 10,        // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1
  kRadTanThinPrismFisheye = 11,  // fx, fy, cx, cy, k0..k5, p0, p1, s0..s3
  kSimpleDivision = 12,          // f, cx, cy, k
  kDivision = 13,                // fx, fy, cx, cy, k
  kSimpleFisheye = 14,           // f, cx, cy (equidistant, no distortion)
  kFisheye = 15,                 // fx, fy, cx, cy (equidistant, no distortion)
  kEUCM = 16,                    // fx, fy, cx, cy, alpha, beta
  kEquirectangular = 17,         // w, h (full-sphere panorama; no focal length)
};

struct CameraModelInfo {
  CameraModelId id;
  std::string_view name;  // COLMAP's spelling, e.g. "SIMPLE_RADIAL"
  int num_params;
  bool can_project;  // projection/unprojection implemented for this model
};

// Every model COLMAP defines, in id order.
std::span<const CameraModelInfo> AllCameraModels();

// Lookups return nullopt for an unknown id or name (callers turn that into an InputError
// naming their file). Names are matched exactly (COLMAP's upper-case spelling).
std::optional<CameraModelInfo> FindCameraModel(int32_t model_id);
std::optional<CameraModelInfo> FindCameraModel(std::string_view name);

// Name and parameter count of a valid id ("" and -1 for a value outside the enum).
std::string_view CameraModelName(CameraModelId model);
int CameraModelNumParams(CameraModelId model);

// Pixel coordinates follow COLMAP: origin at the top-left corner of the top-left pixel.
// `params` must hold num_params values (otherwise both functions return false).
// Projection takes a point in camera coordinates (z forward); returns false when the point
// is behind the camera (z <= 0) or outside the model's valid domain. EQUIRECTANGULAR
// projects any non-zero direction, including those behind the camera.
bool ProjectToPixel(CameraModelId model, std::span<const double> params,
                    const std::array<double, 3>& point_in_camera, std::array<double, 2>* pixel);

// Inverse of the distortion: pixel -> normalized image plane coordinates (x/z, y/z).
// Models without a closed-form inverse use Newton iterations with a convergence check; returns
// false when they do not converge, or when the pixel's ray is not in front of the camera.
bool PixelToNormalized(CameraModelId model, std::span<const double> params,
                       const std::array<double, 2>& pixel, std::array<double, 2>* normalized);

// Mean focal length in pixels (the f of P3P), from the model's focal parameter(s).
// EQUIRECTANGULAR has none; it returns the angular resolution w / (2 pi) in pixels per
// radian. NaN when `params` has the wrong size.
double MeanFocalLength(CameraModelId model, std::span<const double> params);

}  // namespace cwloc
