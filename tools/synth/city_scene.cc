#include "tools/synth/city_scene.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <span>

#include "base/parallel_for.h"
#include "camera/camera_models.h"

namespace cwloc::synth {
namespace {

// Stream tags: every random stream is seeded from (seed, tag, ids) so that no two uses share
// numbers and nothing depends on thread scheduling.
enum SceneStream : uint64_t {
  kPointsStream = 100,
  kMotifShapeStream,
  kObserveStream,
  kQueryObserveStream,
  kFeaturesStream,
  kPointNoiseStream,
  kPointPatchStream,
  kMotifPatchStream,
  kInstanceStream,
  kClutterPatchStream,
  kViewNoiseStream,
  kRigObserveStream,
};

constexpr double kMinKeypointScale = 1.3;  // pixels; smaller blobs are not detected
constexpr double kMaxKeypointScale = 80;
constexpr double kReferenceDistance =
    12;  // metres; the distance a feature's canonical look is from
constexpr double kKeypointScaleError = 0.13;  // log2, sigma; the descriptor sees the same error
constexpr double kMinDepth = 0.3;
constexpr int kMaxQueryDraws = 64;

// Random draws each in their own statement, in the order GCC made them (arguments right to
// left): the order of arguments and of operands is unspecified, and clang's differs.

// Feature sizes: a Pareto tail (alpha = 2) above 1.9 cm, as SIFT scales on facades look.
double DrawFeatureSize(Rng& rng) { return std::min(0.5, 0.019 / std::sqrt(1 - rng.Uniform())); }

// Facade features are mostly aligned with horizontal and vertical edges.
double DrawFeatureAngle(Rng& rng) {
  if (rng.Uniform() < 0.5) return rng.Uniform(-std::numbers::pi, std::numbers::pi);
  const double edge = double(rng.Below(4)) * std::numbers::pi / 2;
  return edge + 0.15 * rng.Gaussian();
}

double TruncatedGaussian(Rng& rng, double sigma) {
  return sigma * std::clamp(rng.Gaussian(), -2.5, 2.5);
}

}  // namespace

struct CityScene::Observation {
  uint32_t point;
  float x, y, scale, orientation;
  float score;  // detector response: larger and more frontal features win the budget
};

CameraPose RigCameraInRig(int camera, int cameras) {
  // R turns about y so that the camera's view direction in the rig frame, R^T e_z =
  // (sin yaw, 0, cos yaw), goes right (+x) for a positive yaw.
  const double yaw = 2 * std::numbers::pi * double(camera) / double(cameras);
  const double c = std::cos(yaw), s = std::sin(yaw);
  CameraPose pose;
  pose.cam_from_world_rotation << c, 0, -s, 0, 1, 0, s, 0, c;
  pose.centre = kRigRadius * Eigen::Vector3d(s, 0, c - 1);
  return pose;
}

CameraPose RigCameraPose(const CameraPose& rig, int camera, int cameras) {
  if (camera == 0) return rig;  // bit for bit: a one-camera rig changes nothing
  const CameraPose in_rig = RigCameraInRig(camera, cameras);
  CameraPose pose = rig;
  pose.cam_from_world_rotation = in_rig.cam_from_world_rotation * rig.cam_from_world_rotation;
  pose.centre = rig.centre + rig.cam_from_world_rotation.transpose() * in_rig.centre;
  return pose;
}

double DefaultPointDensity(const SceneOptions& options) {
  // About 140 m^2 of facade lies in a typical view within the detectable range; more points
  // than the budget keeps most images full after occlusion, detection and scale losses.
  const double budget = options.features_per_image * (1 - options.clutter_fraction);
  return std::max(0.05, 2.4 * budget / 140);
}

double EstimatedViewsPerFacadeMetre(const SceneOptions& options) {
  // 1.5 cameras per station (across + every second oblique); an image fills ~80% of its
  // budget on average and ~90% of its points make the model (seen twice). Measured on
  // generated cities of 0.2M to 10M views.
  const double cameras_per_metre = 1.5 / options.layout.camera_spacing;
  const double budget = options.features_per_image * (1 - options.clutter_fraction);
  return cameras_per_metre * budget * 0.73;
}

CityScene::CityScene(const SceneOptions& options)
    : options_(options),
      layout_(options.layout, options.seed),
      sift_(options.patch, options.view_noise),
      focal_(MeanFocalLength(options.camera.model_id, options.camera.params)) {}

CityScene CityScene::Generate(const SceneOptions& options, const Progress& progress) {
  auto report = [&](std::string_view stage, double fraction) {
    if (progress) progress(stage, fraction);
  };
  CityScene scene(options);
  report("facade points", 0);
  scene.MakePoints();

  // Mapping images: observe in parallel, one slot per image.
  std::vector<CameraPose> poses = scene.layout_.PlaceMappingCameras(options.seed);
  const size_t budget =
      size_t(std::lround(options.features_per_image * (1 - options.clutter_fraction)));
  ImageObservations observations(poses.size());
  std::atomic<size_t> done{0};
  ParallelFor(poses.size(), options.threads, [&](size_t i) {
    observations[i] =
        scene.Observe(poses[i], Rng::Seed(options.seed, kObserveStream, i + 1), budget);
    const size_t d = ++done;
    if (d % 64 == 0) report("mapping views", double(d) / double(poses.size()));
  });
  const std::vector<uint32_t> view_count =
      scene.KeepRegisteredImages(std::max<size_t>(30, budget / 6), &poses, &observations);
  const size_t num_model_points = scene.NumberModelPoints(poses, observations, view_count);

  report("queries", 0);
  std::vector<CameraPose> query_poses;
  ImageObservations query_observations;
  scene.DrawQueries(budget, &query_poses, &query_observations);

  scene.NameImages(poses, query_poses);
  report("features", 0);
  const size_t num_mapping = poses.size();
  ParallelFor(scene.images_.size(), options.threads, [&](size_t i) {
    auto& obs = i < num_mapping ? observations[i] : query_observations[i - num_mapping];
    scene.MakeFeatures(&scene.images_[i], std::move(obs));
  });
  scene.Count(view_count, num_model_points);
  report("done", 1);
  return scene;
}

std::vector<uint32_t> CityScene::KeepRegisteredImages(size_t min_model_views,
                                                      std::vector<CameraPose>* poses,
                                                      ImageObservations* observations) const {
  // Sequential, so it does not depend on threads.
  std::vector<uint32_t> view_count(points_.size(), 0);
  for (const auto& obs : *observations) {
    for (const Observation& o : obs) ++view_count[o.point];
  }
  std::vector<bool> registered(poses->size(), true);
  for (bool changed = true; changed;) {
    changed = false;
    for (size_t i = 0; i < poses->size(); ++i) {
      if (!registered[i]) continue;
      const std::vector<Observation>& image = (*observations)[i];
      const size_t model_views =
          size_t(std::count_if(image.begin(), image.end(),
                               [&](const Observation& o) { return view_count[o.point] >= 2; }));
      if (model_views >= min_model_views) continue;
      registered[i] = false;
      changed = true;
      for (const Observation& o : image) --view_count[o.point];
    }
  }
  size_t kept = 0;
  for (size_t i = 0; i < poses->size(); ++i) {
    if (!registered[i]) continue;
    if (kept != i) {
      (*poses)[kept] = (*poses)[i];
      (*observations)[kept] = std::move((*observations)[i]);
    }
    ++kept;
  }
  poses->resize(kept);
  observations->resize(kept);
  return view_count;
}

size_t CityScene::NumberModelPoints(const std::vector<CameraPose>& poses,
                                    const ImageObservations& observations,
                                    const std::vector<uint32_t>& view_count) {
  nearest_view_distance_.assign(points_.size(), std::numeric_limits<float>::max());
  for (size_t i = 0; i < poses.size(); ++i) {
    for (const Observation& o : observations[i]) {
      float& nearest = nearest_view_distance_[o.point];
      nearest = std::min(nearest, float((points_[o.point].xyz - poses[i].centre).norm()));
    }
  }
  point3D_ids_.assign(points_.size(), kInvalidPoint3DId);
  point3D_t next_id = 1;
  for (size_t p = 0; p < points_.size(); ++p) {
    if (view_count[p] >= 2) point3D_ids_[p] = next_id++;
  }
  return size_t(next_id - 1);
}

void CityScene::DrawQueries(size_t budget, std::vector<CameraPose>* query_poses,
                            ImageObservations* query_observations) const {
  const size_t num_frames = size_t(std::max(0, options_.queries));
  const size_t rig = size_t(std::max(1, options_.rig_cameras));
  const size_t num_queries = num_frames * rig;
  query_poses->assign(num_queries, CameraPose());
  query_observations->assign(num_queries, {});
  const bool walk = options_.path_step > 0;
  std::vector<CameraPose> walk_poses;
  if (walk) walk_poses = layout_.WalkCameras(options_.seed, num_frames, options_.path_step);
  ParallelFor(num_frames, options_.threads, [&](size_t q) {
    std::vector<CameraPose> frame_poses(rig);
    std::vector<std::vector<Observation>> frame_obs(rig);
    size_t best = 0;
    for (int draw = 0; draw < kMaxQueryDraws; ++draw) {
      const CameraPose rig_pose =
          walk ? walk_poses[q] : layout_.DrawQueryCamera(options_.seed, q * kMaxQueryDraws + draw);
      size_t in_model = 0;
      for (size_t c = 0; c < rig; ++c) {
        // Camera 0 keeps the single camera's stream: without a rig nothing changes.
        const uint64_t observe_seed =
            c == 0 ? Rng::Seed(options_.seed, kQueryObserveStream, q, uint64_t(draw))
                   : Rng::Seed(options_.seed, kRigObserveStream, q * kMaxRigCameras + c,
                               uint64_t(draw));
        frame_poses[c] = RigCameraPose(rig_pose, int(c), int(rig));
        frame_obs[c] = Observe(frame_poses[c], observe_seed, budget);
        for (const Observation& o : frame_obs[c])
          in_model += point3D_ids_[o.point] != kInvalidPoint3DId;
      }
      if (draw == 0 || in_model > best) {
        best = in_model;
        for (size_t c = 0; c < rig; ++c) {
          (*query_poses)[q * rig + c] = frame_poses[c];
          (*query_observations)[q * rig + c] = std::move(frame_obs[c]);
        }
      }
      if (walk || in_model >= size_t(options_.min_query_points)) break;
    }
  });
}

void CityScene::NameImages(const std::vector<CameraPose>& poses,
                           const std::vector<CameraPose>& query_poses) {
  const size_t num_mapping = poses.size();
  const size_t rig = size_t(std::max(1, options_.rig_cameras));
  num_mapping_images_ = num_mapping;
  images_.resize(num_mapping + query_poses.size());
  for (size_t i = 0; i < images_.size(); ++i) {
    SceneImage& image = images_[i];
    image.image_id = image_t(i + 1);
    image.query = i >= num_mapping;
    char name[64];
    if (!image.query) {
      std::snprintf(name, sizeof(name), "map_%06zu.jpg", i + 1);
    } else if (rig == 1) {
      std::snprintf(name, sizeof(name), "query_%05zu.jpg", i - num_mapping + 1);
    } else {
      // COLMAP's rig layout: a folder per camera, the images of one frame share the file name.
      const size_t k = i - num_mapping;
      std::snprintf(name, sizeof(name), "cam%zu/query_%05zu.jpg", k % rig, k / rig + 1);
    }
    image.name = name;
    image.pose = image.query ? query_poses[i - num_mapping] : poses[i];
  }
}

void CityScene::Count(const std::vector<uint32_t>& view_count, size_t num_model_points) {
  SceneCounts& c = counts_;
  c.mapping_images = num_mapping_images_;
  c.queries = images_.size() - num_mapping_images_;
  c.facades = layout_.facades().size();
  c.scene_points = points_.size();
  c.model_points = num_model_points;
  std::vector<bool> motif_used(size_t(std::max(0, options_.motifs)), false);
  for (size_t p = 0; p < points_.size(); ++p) {
    if (point3D_ids_[p] == kInvalidPoint3DId) continue;
    const int32_t motif = points_[p].motif;
    if (motif == kUniqueTexture) continue;
    ++c.motif_model_points;
    c.motif_views += view_count[p];
    motif_used[size_t(motif)] = true;
  }
  c.distinct_motifs = size_t(std::count(motif_used.begin(), motif_used.end(), true));
  c.min_query_model_points = c.queries > 0 ? std::numeric_limits<size_t>::max() : 0;
  for (const SceneImage& image : images_) {
    size_t in_model = 0;
    for (const SceneFeature& f : image.features) {
      ++c.features;
      if (f.point == kNoPoint) {
        ++c.clutter_features;
        if (!image.query) ++c.mapping_clutter;
        continue;
      }
      const bool model = point3D_ids_[f.point] != kInvalidPoint3DId;
      in_model += model;
      if (!image.query) c.single_view_features += !model;
    }
    if (image.query) {
      c.query_model_observations += in_model;
      c.min_query_model_points = std::min(c.min_query_model_points, in_model);
    } else {
      c.mapping_features += image.features.size();
      c.views += in_model;
    }
  }
}

void CityScene::MakePoints() {
  const auto& facades = layout_.facades();
  const double density =
      options_.point_density > 0 ? options_.point_density : DefaultPointDensity(options_);
  const bool repeat = options_.repetition > 0 && options_.motifs > 0;
  std::vector<std::vector<ScenePoint>> per_facade(facades.size());
  ParallelFor(facades.size(), options_.threads, [&](size_t id) {
    const Facade& f = facades[id];
    Rng rng(Rng::Seed(options_.seed, kPointsStream, id));
    const size_t n = size_t(density * f.width * f.height + rng.Uniform());
    std::vector<ScenePoint>& out = per_facade[id];
    out.reserve(n);
    auto add = [&](double u, double v, int32_t motif, double size, double angle) {
      ScenePoint p;
      // A little relief: ornaments and recesses are not on the wall plane.
      p.xyz = f.Point(std::clamp(u, 0.0, f.width), std::clamp(v, 0.0, f.height),
                      std::clamp(0.03 * rng.Gaussian(), -0.08, 0.08));
      p.facade = uint32_t(id);
      p.motif = motif;
      p.size = float(size);
      p.angle = float(angle);
      out.push_back(p);
    };
    // Repeated motifs come in rows (windows, signs): a few instances of one motif per facade,
    // while the same motif recurs on facades all over the city.
    const size_t quota = repeat ? size_t(std::lround(options_.repetition * double(n))) : 0;
    while (out.size() < quota) {
      const int32_t motif = int32_t(rng.Below(uint64_t(options_.motifs)));
      Rng shape(Rng::Seed(options_.seed, kMotifShapeStream, uint64_t(motif)));
      const double size = DrawFeatureSize(shape);
      const double angle = DrawFeatureAngle(shape);
      size_t count = 1;
      while (count < 6 && rng.Uniform() < 0.6) ++count;
      count = std::min(count, quota - out.size());
      const double v = rng.Uniform(0.5, std::max(0.6, f.height - 0.5));
      const double step = rng.Uniform(1.5, 4.0);
      const double u0 = rng.Uniform(0, f.width);
      for (size_t k = 0; k < count; ++k) {
        const double u = std::fmod(u0 + double(k) * step, f.width);
        const double instance_angle = angle + 0.03 * rng.Gaussian();
        const double instance_size = size * std::exp(0.05 * rng.Gaussian());
        add(u, v, motif, instance_size, instance_angle);
      }
    }
    while (out.size() < n) {
      const double u = rng.Uniform(0, f.width), v = rng.Uniform(0, f.height);
      const double size = DrawFeatureSize(rng);
      add(u, v, kUniqueTexture, size, DrawFeatureAngle(rng));
    }
  });
  size_t total = 0;
  for (const auto& v : per_facade) total += v.size();
  points_.reserve(total);
  facade_points_.reserve(facades.size() + 1);
  for (auto& v : per_facade) {
    facade_points_.push_back(uint32_t(points_.size()));
    points_.insert(points_.end(), v.begin(), v.end());
    std::vector<ScenePoint>().swap(v);
  }
  facade_points_.push_back(uint32_t(points_.size()));
}

std::vector<CityScene::Observation> CityScene::Observe(const CameraPose& pose, uint64_t image_seed,
                                                       size_t budget) const {
  Rng rng(image_seed);
  const Eigen::Matrix3d& R = pose.cam_from_world_rotation;
  const Eigen::Vector3d& C = pose.centre;
  const Eigen::Vector2d C2 = C.head<2>();
  const colmap::Camera& camera = options_.camera;
  const double width = double(camera.width), height = double(camera.height);
  // Conservative view cone in normalized coordinates (distortion moves the border a little).
  const double half_x = 1.15 * 0.5 * width / focal_, half_y = 1.15 * 0.5 * height / focal_;
  const double cos_max = std::cos(options_.max_obliquity_deg * std::numbers::pi / 180);
  const double cos_full = std::cos(40 * std::numbers::pi / 180);
  const double max_distance2 = options_.max_distance * options_.max_distance;

  std::vector<uint32_t> facades;
  layout_.FacadesNear(C2, options_.max_distance, &facades);
  std::vector<Observation> out;
  for (const uint32_t facade_id : facades) {
    const Facade& f = layout_.facades()[facade_id];
    if ((C2 - f.origin).dot(f.normal) < 0.5) continue;  // behind or inside the wall
    // Skip facades entirely outside one side of the view cone.
    Eigen::Vector3d corners[4] = {f.Point(0, 0), f.Point(f.width, 0), f.Point(0, f.height),
                                  f.Point(f.width, f.height)};
    std::array<int, 5> outside{};
    for (auto& corner : corners) {
      const Eigen::Vector3d x = R * (corner - C);
      outside[0] += x.z() < kMinDepth;
      outside[1] += x.x() < -half_x * x.z();
      outside[2] += x.x() > half_x * x.z();
      outside[3] += x.y() < -half_y * x.z();
      outside[4] += x.y() > half_y * x.z();
    }
    if (std::find(outside.begin(), outside.end(), 4) != outside.end()) continue;
    const Eigen::Vector3d normal(f.normal.x(), f.normal.y(), 0);
    for (uint32_t p = facade_points_[facade_id]; p < facade_points_[facade_id + 1]; ++p) {
      const ScenePoint& point = points_[p];
      const Eigen::Vector3d d = point.xyz - C;
      const double dist2 = d.squaredNorm();
      if (dist2 > max_distance2) continue;
      const Eigen::Vector3d x = R * d;
      if (x.z() < kMinDepth) continue;
      if (std::abs(x.x()) > half_x * x.z() || std::abs(x.y()) > half_y * x.z()) continue;
      const double dist = std::sqrt(dist2);
      const double cos_obliquity = -d.dot(normal) / dist;
      if (cos_obliquity < cos_max) continue;
      const double scale = point.size * focal_ / x.z();
      if (scale < kMinKeypointScale || scale > kMaxKeypointScale) continue;
      std::array<double, 2> pixel;
      if (!ProjectToPixel(camera.model_id, camera.params, {x.x(), x.y(), x.z()}, &pixel)) continue;
      if (pixel[0] < 1 || pixel[0] > width - 1 || pixel[1] < 1 || pixel[1] > height - 1) continue;
      // Detection gets less likely as the view gets oblique.
      const double detect = 0.95 * std::min(1.0, (cos_obliquity - cos_max) / (cos_full - cos_max));
      if (rng.Uniform() >= detect) continue;
      if (layout_.SegmentBlocked(C2, point.xyz.head<2>(), f.block)) continue;
      // Keypoint orientation: the image direction of the feature's dominant gradient.
      const Eigen::Vector3d axis3(std::cos(point.angle) * f.direction.x(),
                                  std::cos(point.angle) * f.direction.y(), std::sin(point.angle));
      const Eigen::Vector3d a = R * axis3;
      const double orientation =
          std::atan2(a.y() * x.z() - x.y() * a.z(), a.x() * x.z() - x.x() * a.z()) +
          0.05 * rng.Gaussian();
      Observation o;
      o.point = p;
      o.x = float(pixel[0] + TruncatedGaussian(rng, options_.keypoint_noise));
      o.y = float(pixel[1] + TruncatedGaussian(rng, options_.keypoint_noise));
      o.x = std::clamp(o.x, 0.5f, float(width - 0.5));
      o.y = std::clamp(o.y, 0.5f, float(height - 0.5));
      o.scale = float(scale * std::exp2(kKeypointScaleError * rng.Gaussian()));
      o.orientation = float(std::remainder(orientation, 2 * std::numbers::pi));
      o.score = float(scale * cos_obliquity * std::exp(0.25 * rng.Gaussian()));
      out.push_back(o);
    }
  }
  // Keep the strongest responses, as a detector with a feature limit does.
  if (out.size() > budget) {
    auto stronger = [](const Observation& a, const Observation& b) {
      return a.score != b.score ? a.score > b.score : a.point < b.point;
    };
    std::nth_element(out.begin(), out.begin() + std::ptrdiff_t(budget), out.end(), stronger);
    out.resize(budget);
  }
  std::sort(out.begin(), out.end(),
            [](const Observation& a, const Observation& b) { return a.point < b.point; });
  return out;
}

void CityScene::MakeFeatures(SceneImage* image, std::vector<Observation>&& observations) const {
  Rng rng(Rng::Seed(options_.seed, kFeaturesStream, image->image_id));
  const double c = options_.clutter_fraction;
  const size_t clutter = size_t(std::lround(double(observations.size()) * c / (1 - c)));
  auto& features = image->features;
  features.reserve(observations.size() + clutter);
  for (const Observation& o : observations) {
    features.push_back({o.x, o.y, o.scale, o.orientation, o.point});
  }
  std::vector<Observation>().swap(observations);
  const double width = double(options_.camera.width), height = double(options_.camera.height);
  for (size_t k = 0; k < clutter; ++k) {
    SceneFeature f;
    f.x = float(rng.Uniform(0.5, width - 0.5));
    f.y = float(rng.Uniform(0.5, height - 0.5));
    f.scale = float(std::min(kMaxKeypointScale, kMinKeypointScale / std::sqrt(1 - rng.Uniform())));
    f.orientation = float(rng.Uniform(-std::numbers::pi, std::numbers::pi));
    features.push_back(f);
  }
  // Shuffle so that neither clutter nor any point order can be read off the row index.
  for (size_t i = features.size(); i > 1; --i) std::swap(features[i - 1], features[rng.Below(i)]);
}

Eigen::Vector3d CityScene::ModelXyz(uint32_t point) const {
  Rng rng(Rng::Seed(options_.seed, kPointNoiseStream, point));
  constexpr double kNoiseReferenceDistance = 20;
  const double s = options_.point_noise *
                   std::min<double>(nearest_view_distance_[point], options_.max_distance) /
                   kNoiseReferenceDistance;
  const double dx = s * rng.Gaussian(), dy = s * rng.Gaussian(), dz = s * rng.Gaussian();
  return points_[point].xyz + Eigen::Vector3d(dx, dy, dz);
}

colmap::Rigid3d CityScene::CamFromWorld(const SceneImage& image) const {
  Eigen::Quaterniond q(image.pose.cam_from_world_rotation);
  q.normalize();
  if (q.w() < 0) q.coeffs() *= -1;
  const Eigen::Vector3d t = -(image.pose.cam_from_world_rotation * image.pose.centre);
  colmap::Rigid3d rigid;
  rigid.rotation = {q.w(), q.x(), q.y(), q.z()};
  rigid.translation = {t.x(), t.y(), t.z()};
  return rigid;
}

void CityScene::Describe(const SceneImage& image, size_t feature_index, uint8_t* out) const {
  const SceneFeature& f = image.features[feature_index];
  const uint64_t seed = options_.seed;
  Rng view_rng(Rng::Seed(seed, kViewNoiseStream, image.image_id, feature_index));
  Appearance appearance;
  ViewChange view;
  if (f.point == kNoPoint) {
    appearance.patch_seed = Rng::Seed(seed, kClutterPatchStream, image.image_id, feature_index);
  } else {
    const ScenePoint& p = points_[f.point];
    if (p.motif != kUniqueTexture) {
      appearance.patch_seed = Rng::Seed(seed, kMotifPatchStream, uint64_t(p.motif));
      appearance.instance_seed = Rng::Seed(seed, kInstanceStream, f.point);
      appearance.instance_noise = options_.instance_noise;
    } else {
      appearance.patch_seed = Rng::Seed(seed, kPointPatchStream, f.point);
    }
    // The viewing ray in the feature's own frame on the facade.
    const Facade& facade = layout_.facades()[p.facade];
    const Eigen::Vector3d to_camera = image.pose.centre - p.xyz;
    const double dist = to_camera.norm();
    const double u = to_camera.head<2>().dot(facade.direction) / dist, w = to_camera.z() / dist;
    const double ca = std::cos(p.angle), sa = std::sin(p.angle);
    view.u = u * ca + w * sa;
    view.v = -u * sa + w * ca;
    // The keypoint's scale error (its scale over the projected size) also shifts the window
    // the descriptor is computed over, and the scale the patch is seen at.
    const double depth = (image.pose.cam_from_world_rotation.row(2) * -to_camera)(0);
    view.log2_detection_error = std::log2(f.scale / (p.size * focal_ / depth));
    view.log2_scale = std::log2(kReferenceDistance / depth) + view.log2_detection_error;
  }
  SiftVector descriptor;
  sift_.Describe(appearance, view, view_rng, &descriptor);
  QuantizeDescriptor(descriptor, out);
}

bool CityScene::Project(const CameraPose& pose, const Eigen::Vector3d& xyz,
                        Eigen::Vector2d* pixel) const {
  const Eigen::Vector3d x = pose.cam_from_world_rotation * (xyz - pose.centre);
  if (x.z() <= 0) return false;
  std::array<double, 2> px;
  if (!ProjectToPixel(options_.camera.model_id, options_.camera.params, {x.x(), x.y(), x.z()},
                      &px)) {
    return false;
  }
  *pixel = {px[0], px[1]};
  return true;
}

}  // namespace cwloc::synth
