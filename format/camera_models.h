#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

namespace cwloc {

// COLMAP's camera models, with COLMAP's numeric ids (these ids are what cameras.bin and
// database.db store). Parameter order follows COLMAP's src/colmap/sensor/models.h.
enum class CameraModelId : int32_t {
  kSimplePinhole = 0,          // f, cx, cy
  kPinhole = 1,                // fx, fy, cx, cy
  kSimpleRadial = 2,           // f, cx, cy, k
  kRadial = 3,                 // f, cx, cy, k1, k2
  kOpenCV = 4,                 // fx, fy, cx, cy, k1, k2, p1, p2
  kOpenCVFisheye = 5,          // fx, fy, cx, cy, k1, k2, k3, k4
  kFullOpenCV = 6,             // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, k5, k6
  kFOV = 7,                    // fx, fy, cx, cy, omega
  kSimpleRadialFisheye = 8,    // f, cx, cy, k
  kRadialFisheye = 9,          // f, cx, cy, k1, k2
  kThinPrismFisheye = 10,      // fx, fy, cx, cy, k1, k2, p1, p2, k3, k4, sx1, sy1
  kRadTanThinPrismFisheye = 11,// fx, fy, cx, cy, k0..k5, p0, p1, s0..s3
};

struct CameraModelInfo {
  CameraModelId id;
  std::string_view name;  // COLMAP's spelling, e.g. "SIMPLE_RADIAL"
  int num_params;
  bool can_project;       // projection/unprojection implemented for this model
};

// Every model COLMAP defines, in id order.
std::span<const CameraModelInfo> AllCameraModels();

// Lookups return nullopt for an unknown id or name (callers turn that into an InputError
// naming their file).
std::optional<CameraModelInfo> FindCameraModel(int32_t model_id);
std::optional<CameraModelInfo> FindCameraModel(std::string_view name);

// Pixel coordinates follow COLMAP: origin at the top-left corner of the top-left pixel.
// `params` must hold num_params values. Projection takes a point in camera coordinates
// (z forward); returns false when the point is behind the camera or the model cannot project.
bool ProjectToPixel(CameraModelId model, std::span<const double> params,
                    const std::array<double, 3>& point_in_camera, std::array<double, 2>* pixel);

// Inverse of the distortion: pixel -> normalized image plane coordinates (x/z, y/z).
// Returns false when the iterative undistortion does not converge or the model cannot project.
bool PixelToNormalized(CameraModelId model, std::span<const double> params,
                       const std::array<double, 2>& pixel, std::array<double, 2>* normalized);

// Mean focal length in pixels (the f of P3P), from the model's focal parameter(s).
double MeanFocalLength(CameraModelId model, std::span<const double> params);

}  // namespace cwloc
