#include "tests/colmap/synthetic_model.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <string>

#include "tests/test_util.h"

namespace cwloc::test {
namespace {

using colmap::Rigid3d;
using Vec3 = std::array<double, 3>;

double Uniform(double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(Rng());
}
int UniformInt(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(Rng()); }

// True when every summation order a program might use gives a squared norm of exactly 1.
bool IsExactlyUnit(const std::array<double, 4>& q) {
  const double a = q[0] * q[0], b = q[1] * q[1], c = q[2] * q[2], d = q[3] * q[3];
  return ((a + b) + c) + d == 1.0 && (a + c) + (b + d) == 1.0 && (a + b) + (c + d) == 1.0 &&
         a + (b + (c + d)) == 1.0;
}

std::array<double, 4> NormalizeExactly(std::array<double, 4> q) {
  const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
  for (double& v : q) v /= norm;
  return q;
}

// A random rotation close to `q` (angle up to `spread` radians) that is exactly unit.
std::array<double, 4> ExactRotationNear(const std::array<double, 4>& q, double spread) {
  for (;;) {
    std::normal_distribution<double> normal(0, spread / 2);
    const std::array<double, 4> d =
        NormalizeExactly({1, normal(Rng()), normal(Rng()), normal(Rng())});
    Rigid3d a, b;
    a.rotation = q;
    b.rotation = d;
    std::array<double, 4> r = NormalizeExactly((a * b).rotation);
    if (r[0] < 0) r = {-r[0], -r[1], -r[2], -r[3]};
    if (IsExactlyUnit(r)) return r;
  }
}

// Rotation whose camera z axis points from `center` to the origin.
std::array<double, 4> LookAtOrigin(const Vec3& center) {
  const double n = std::sqrt(center[0] * center[0] + center[1] * center[1] + center[2] * center[2]);
  const Vec3 z = {-center[0] / n, -center[1] / n, -center[2] / n};
  // Rotation taking (0,0,1) to z (world-from-camera), then inverted to camera-from-world.
  const Vec3 axis = {-z[1], z[0], 0};  // (0,0,1) x z
  const double s = std::sqrt(axis[0] * axis[0] + axis[1] * axis[1]);
  const double angle = std::atan2(s, z[2]);
  std::array<double, 4> world_from_cam = {1, 0, 0, 0};
  if (s > 1e-12) {
    const double h = std::sin(angle / 2) / s;
    world_from_cam = {std::cos(angle / 2), axis[0] * h, axis[1] * h, 0};
  }
  return {world_from_cam[0], -world_from_cam[1], -world_from_cam[2], -world_from_cam[3]};
}

// cam_from_world for a camera at `center` looking at the origin, slightly perturbed.
Rigid3d RandomPose(double distance) {
  const double azimuth = Uniform(0, 2 * std::numbers::pi);
  const double elevation = Uniform(-0.4, 0.4);
  const Vec3 center = {distance * std::cos(elevation) * std::sin(azimuth),
                       distance * std::sin(elevation),
                       distance * std::cos(elevation) * std::cos(azimuth)};
  Rigid3d cam_from_world;
  cam_from_world.rotation = ExactRotationNear(LookAtOrigin(center), 0.05);
  // t = -R c
  Rigid3d rotation_only;
  rotation_only.rotation = cam_from_world.rotation;
  const Vec3 rc = rotation_only * center;
  cam_from_world.translation = {-rc[0], -rc[1], -rc[2]};
  return cam_from_world;
}

}  // namespace

std::vector<CameraModelId> Colmap38CameraModels() {
  std::vector<CameraModelId> models;
  for (int id = 0; id <= 10; ++id) models.push_back(static_cast<CameraModelId>(id));
  return models;
}

std::vector<double> TypicalCameraParams(CameraModelId model, uint64_t width, uint64_t height) {
  const double w = static_cast<double>(width), h = static_cast<double>(height);
  const double f = 1.2 * std::max(w, h) * Uniform(0.9, 1.1);
  const double cx = w / 2 + Uniform(-5, 5), cy = h / 2 + Uniform(-5, 5);
  const double ff = 0.5 * f;  // fisheye lenses see wider
  switch (model) {
    case CameraModelId::kSimplePinhole:
      return {f, cx, cy};
    case CameraModelId::kPinhole:
      return {f, f * 1.01, cx, cy};
    case CameraModelId::kSimpleRadial:
      return {f, cx, cy, Uniform(-0.1, 0.1)};
    case CameraModelId::kRadial:
      return {f, cx, cy, Uniform(-0.1, 0.1), Uniform(-0.02, 0.02)};
    case CameraModelId::kOpenCV:
      return {f, f * 1.01, cx, cy, -0.05, 0.01, Uniform(-1e-3, 1e-3), Uniform(-1e-3, 1e-3)};
    case CameraModelId::kOpenCVFisheye:
      return {ff, ff, cx, cy, 0.03, -0.005, 0.001, -0.0002};
    case CameraModelId::kFullOpenCV:
      return {f, f, cx, cy, -0.05, 0.01, 1e-3, -1e-3, 1e-3, 0.01, 1e-3, 5e-4};
    case CameraModelId::kFOV:
      return {f, f, cx, cy, Uniform(0.5, 1.0)};
    case CameraModelId::kSimpleRadialFisheye:
      return {ff, cx, cy, Uniform(-0.05, 0.05)};
    case CameraModelId::kRadialFisheye:
      return {ff, cx, cy, 0.03, -0.005};
    case CameraModelId::kThinPrismFisheye:
      return {ff, ff, cx, cy, 0.03, -0.005, 1e-3, -1e-3, 5e-4, -1e-4, 1e-3, -8e-4};
    case CameraModelId::kRadTanThinPrismFisheye:
      return {ff,   ff,    cx,   cy,    0.03, -0.005, 1e-3, -2e-4,
              5e-5, -1e-5, 1e-3, -8e-4, 5e-4, -2e-4,  3e-4, -1e-4};
    case CameraModelId::kSimpleDivision:
      return {f, cx, cy, Uniform(-0.1, 0.1)};
    case CameraModelId::kDivision:
      return {f, f, cx, cy, Uniform(-0.1, 0.1)};
    case CameraModelId::kSimpleFisheye:
      return {ff, cx, cy};
    case CameraModelId::kFisheye:
      return {ff, ff * 1.01, cx, cy};
    case CameraModelId::kEUCM:
      return {ff, ff, cx, cy, 0.6, 1.1};
    case CameraModelId::kEquirectangular:
      return {w, h};
  }
  return {};
}

namespace {

using colmap::Camera;
using colmap::Frame;
using colmap::Image;
using colmap::Point2D;
using colmap::Point3D;
using colmap::Reconstruction;
using colmap::Rig;
using colmap::RigSensor;
using colmap::SensorType;

// The id after `previous`: the next one, or with `sparse` one a gap of up to 2 past it.
uint64_t NextId(uint64_t previous, bool sparse) {
  return previous + (sparse ? UniformInt(1, 3) : 1);
}

// The cameras, the options' models in turn; returns their ids.
std::vector<camera_t> AddCameras(const SyntheticModelOptions& options, Reconstruction* model) {
  std::vector<CameraModelId> models = options.camera_models;
  if (models.empty()) {
    for (const CameraModelInfo& info : AllCameraModels()) models.push_back(info.id);
  }
  constexpr std::array<std::array<uint64_t, 2>, 3> kSizes = {
      {{640, 480}, {1024, 768}, {1536, 1024}}};
  std::vector<camera_t> camera_ids;
  for (int i = 0; i < options.num_cameras; ++i) {
    colmap::Camera camera;
    camera.camera_id = static_cast<camera_t>(i + 1);
    camera.model_id = models[static_cast<size_t>(i) % models.size()];
    const auto& size = kSizes[static_cast<size_t>(i) % kSizes.size()];
    camera.width = size[0];
    camera.height = size[1];
    camera.params = TypicalCameraParams(camera.model_id, camera.width, camera.height);
    camera_ids.push_back(camera.camera_id);
    model->cameras.emplace(camera.camera_id, std::move(camera));
  }
  return camera_ids;
}

constexpr double kDistance = 8;  // of the cameras from the points' centre

// Adds an image of `camera_id` after image `*image_id`, which becomes its id.
image_t AddImage(camera_t camera_id, const Rigid3d& cam_from_world, bool sparse_ids,
                 image_t* image_id, Reconstruction* model) {
  *image_id = static_cast<image_t>(NextId(*image_id, sparse_ids));
  Image image;
  image.image_id = *image_id;
  image.camera_id = camera_id;
  image.name = "cam" + std::to_string(camera_id) + "/img_" + std::to_string(*image_id) + ".jpg";
  image.cam_from_world = cam_from_world;
  model->images.emplace(*image_id, std::move(image));
  return *image_id;
}

// Rigs of two cameras, the second 0.3 units to the side, turned a little; returns each rig's
// cameras.
std::vector<std::vector<camera_t>> AddRigs(const std::vector<camera_t>& camera_ids,
                                           Reconstruction* model) {
  std::vector<std::vector<camera_t>> rig_cameras;
  for (size_t i = 0; i < camera_ids.size(); i += 2) {
    Rig rig;
    rig.rig_id = static_cast<rig_t>(rig_cameras.size() + 1);
    rig.ref_sensor = {SensorType::kCamera, camera_ids[i]};
    std::vector<camera_t> cams = {camera_ids[i]};
    if (i + 1 < camera_ids.size()) {
      RigSensor sensor;
      sensor.sensor = {SensorType::kCamera, camera_ids[i + 1]};
      Rigid3d sensor_from_rig;
      sensor_from_rig.rotation = ExactRotationNear({1, 0, 0, 0}, 0.1);
      sensor_from_rig.translation = {-0.3, Uniform(-0.02, 0.02), Uniform(-0.02, 0.02)};
      sensor.sensor_from_rig = sensor_from_rig;
      rig.sensors.push_back(sensor);
      cams.push_back(camera_ids[i + 1]);
    }
    if (rig.rig_id == 1) rig.sensors.push_back({{SensorType::kImu, 1}, std::nullopt});
    rig_cameras.push_back(cams);
    model->rigs.emplace(rig.rig_id, std::move(rig));
  }
  return rig_cameras;
}

// The images of frames of the rigs in turn, posed as the readers compute them.
void AddRigFrames(const SyntheticModelOptions& options,
                  const std::vector<std::vector<camera_t>>& rig_cameras, Reconstruction* model) {
  image_t image_id = 0;
  frame_t frame_id = 0;
  for (size_t r = 0; static_cast<int>(model->images.size()) < options.num_images; ++r) {
    const Rig& rig = model->rigs.at(static_cast<rig_t>(r % rig_cameras.size() + 1));
    Frame frame;
    frame_id = static_cast<frame_t>(NextId(frame_id, options.sparse_ids));
    frame.frame_id = frame_id;
    frame.rig_id = rig.rig_id;
    frame.rig_from_world = RandomPose(kDistance);
    for (camera_t camera_id : rig_cameras[r % rig_cameras.size()]) {
      if (static_cast<int>(model->images.size()) == options.num_images) break;
      Rigid3d cam_from_world = frame.rig_from_world;
      for (const RigSensor& sensor : rig.sensors) {
        if (sensor.sensor.type == SensorType::kCamera && sensor.sensor.id == camera_id) {
          cam_from_world = *sensor.sensor_from_rig * frame.rig_from_world;
        }
      }
      const image_t id = AddImage(camera_id, cam_from_world, options.sparse_ids, &image_id, model);
      frame.data_ids.push_back({{SensorType::kCamera, camera_id}, id});
    }
    if (rig.rig_id == 1) frame.data_ids.push_back({{SensorType::kImu, 1}, frame_id});
    model->frames.emplace(frame_id, std::move(frame));
  }
}

// The 3D points; returns which images see which point (in the points' order).
std::map<image_t, std::vector<point3D_t>> AddPoints(const SyntheticModelOptions& options,
                                                    Reconstruction* model) {
  std::vector<image_t> image_ids;
  for (const auto& [id, image] : model->images) image_ids.push_back(id);
  std::map<image_t, std::vector<point3D_t>> observations;
  point3D_t point_id = 0;
  for (int i = 0; i < options.num_points3D; ++i) {
    point_id = NextId(point_id, options.sparse_ids);
    if (options.sparse_ids && i == options.num_points3D - 1) point_id += uint64_t{1} << 32;
    Point3D point;
    point.point3D_id = point_id;
    for (double& v : point.xyz) v = Uniform(-2, 2);
    for (uint8_t& c : point.color) c = static_cast<uint8_t>(UniformInt(0, 255));
    point.error = Uniform(0, 2);
    model->points3D.emplace(point_id, std::move(point));
    const int length = std::min<int>(UniformInt(options.min_track_length, options.max_track_length),
                                     static_cast<int>(image_ids.size()));
    std::vector<image_t> seen;
    std::sample(image_ids.begin(), image_ids.end(), std::back_inserter(seen), length, Rng());
    if (!seen.empty() && UniformInt(0, 19) == 0)
      seen.push_back(seen.front());  // twice in one image
    for (image_t id : seen) observations[id].push_back(point_id);
  }
  return observations;
}

// Each image's points2D in random order, the observations projected with noise and the
// unobserved ones anywhere, then the tracks from their final positions.
void AddPoints2D(const SyntheticModelOptions& options,
                 const std::map<image_t, std::vector<point3D_t>>& observations,
                 Reconstruction* model) {
  std::normal_distribution<double> noise(0, 0.3);
  for (auto& [id, image] : model->images) {
    const auto observed = observations.find(id);
    std::vector<point3D_t> entries;
    if (observed != observations.end()) entries = observed->second;
    entries.insert(entries.end(), static_cast<size_t>(options.num_unobserved_points2D),
                   kInvalidPoint3DId);
    std::shuffle(entries.begin(), entries.end(), Rng());
    const colmap::Camera& camera = model->cameras.at(image.camera_id);
    for (point3D_t entry : entries) {
      Point2D point2D;
      point2D.point3D_id = entry;
      std::array<double, 2> pixel{};
      const bool projected =
          entry != kInvalidPoint3DId &&
          ProjectToPixel(camera.model_id, camera.params,
                         image.cam_from_world * model->points3D.at(entry).xyz, &pixel);
      if (projected) {
        point2D.x = pixel[0] + noise(Rng());
        point2D.y = pixel[1] + noise(Rng());
      } else {
        point2D.x = Uniform(0, static_cast<double>(camera.width));
        point2D.y = Uniform(0, static_cast<double>(camera.height));
      }
      if (entry != kInvalidPoint3DId) {
        model->points3D.at(entry).track.push_back(
            {id, static_cast<point2D_t>(image.points2D.size())});
      }
      image.points2D.push_back(point2D);
    }
  }
  for (auto& [id, point] : model->points3D)
    std::shuffle(point.track.begin(), point.track.end(), Rng());
}

}  // namespace

colmap::Reconstruction SyntheticModel(const SyntheticModelOptions& options) {
  Reconstruction model;
  const std::vector<camera_t> camera_ids = AddCameras(options, &model);
  if (!options.with_rigs) {
    image_t image_id = 0;
    for (int i = 0; i < options.num_images; ++i) {
      AddImage(camera_ids[static_cast<size_t>(i) % camera_ids.size()], RandomPose(kDistance),
               options.sparse_ids, &image_id, &model);
    }
  } else {
    AddRigFrames(options, AddRigs(camera_ids, &model), &model);
  }
  AddPoints2D(options, AddPoints(options, &model), &model);
  return model;
}

}  // namespace cwloc::test
