#pragma once

#include <array>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "camera/camera_models.h"
#include "colmap/types.h"

namespace cwloc::colmap {

// A rigid transform: x_b = R(q) x_a + t for `b_from_a`. Quaternion (w, x, y, z) as COLMAP.
struct Rigid3d {
  std::array<double, 4> rotation{1, 0, 0, 0};
  std::array<double, 3> translation{0, 0, 0};
  bool operator==(const Rigid3d&) const = default;
};

// c_from_a = c_from_b * b_from_a, as COLMAP's Rigid3d product. The quaternion is used as
// stored (COLMAP keeps them normalized); the readers compute rig-layout image poses with it.
Rigid3d operator*(const Rigid3d& c_from_b, const Rigid3d& b_from_a);
Rigid3d Inverse(const Rigid3d& b_from_a);  // a_from_b
std::array<double, 3> operator*(const Rigid3d& b_from_a, const std::array<double, 3>& x_in_a);

struct Camera {
  camera_t camera_id = 0;
  CameraModelId model_id = CameraModelId::kSimplePinhole;
  uint64_t width = 0;
  uint64_t height = 0;
  std::vector<double> params;
  bool operator==(const Camera&) const = default;
};

struct Point2D {
  double x = 0;
  double y = 0;
  point3D_t point3D_id = kInvalidPoint3DId;
  bool operator==(const Point2D&) const = default;
};

struct Image {
  image_t image_id = 0;
  camera_t camera_id = 0;
  std::string name;
  Rigid3d cam_from_world;  // always filled; derived from rig and frame in the rig layout
  std::vector<Point2D> points2D;
  bool operator==(const Image&) const = default;
};

struct TrackElement {
  image_t image_id = 0;
  point2D_t point2D_idx = 0;
  bool operator==(const TrackElement&) const = default;
};

struct Point3D {
  point3D_t point3D_id = 0;
  std::array<double, 3> xyz{};
  std::array<uint8_t, 3> color{};
  double error = -1;
  std::vector<TrackElement> track;
  bool operator==(const Point3D&) const = default;
};

// Rig layout (COLMAP >= 3.12: rigs.bin / frames.bin). Sensor types as COLMAP's SensorType.
enum class SensorType : int32_t { kInvalid = -1, kCamera = 0, kImu = 1 };

struct SensorId {
  SensorType type = SensorType::kCamera;
  uint32_t id = 0;
  bool operator==(const SensorId&) const = default;
};

struct RigSensor {
  SensorId sensor;
  std::optional<Rigid3d> sensor_from_rig;  // unset when the calibration is unknown
  bool operator==(const RigSensor&) const = default;
};

struct Rig {
  rig_t rig_id = 0;
  SensorId ref_sensor;             // its sensor_from_rig is identity; type kInvalid when
                                   // the rig has no sensors at all
  std::vector<RigSensor> sensors;  // the non-reference sensors, in file order
  bool operator==(const Rig&) const = default;
};

struct FrameDataId {
  SensorId sensor;
  uint64_t data_id = 0;  // an image_id for camera sensors
  bool operator==(const FrameDataId&) const = default;
};

struct Frame {
  frame_t frame_id = 0;
  rig_t rig_id = 0;
  Rigid3d rig_from_world;
  std::vector<FrameDataId> data_ids;  // in file order
  bool operator==(const Frame&) const = default;
};

// A COLMAP sparse model. Containers are keyed by id so that writing is deterministic.
// `rigs` and `frames` are empty for a model in the classic layout (COLMAP <= 3.11).
// Invariants the readers guarantee: every image's camera exists; each point2D with a
// point3D_id appears exactly once in that point's track and each track element points back
// to it; in the rig layout each image is in one frame and its cam_from_world equals
// sensor_from_rig * frame.rig_from_world.
struct Reconstruction {
  std::map<camera_t, Camera> cameras;
  std::map<image_t, Image> images;
  std::map<point3D_t, Point3D> points3D;
  std::map<rig_t, Rig> rigs;
  std::map<frame_t, Frame> frames;
  bool operator==(const Reconstruction&) const = default;

  size_t NumObservations() const;  // sum of track lengths
};

}  // namespace cwloc::colmap
