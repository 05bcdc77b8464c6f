#pragma once

// The generated city as an in-memory scene: facade points (unique texture or instances of
// globally repeated motifs), mapping and query cameras with their features (views of points
// plus clutter), and which points a triangulating SfM would keep. Descriptors are not stored:
// Describe() renders any feature's descriptor on demand from seeds, so memory stays at a few
// tens of bytes per feature.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include "colmap/reconstruction.h"
#include "colmap/types.h"
#include "tools/synth/city_layout.h"
#include "tools/synth/sift_descriptors.h"

namespace cwloc::synth {

inline constexpr int kMaxRigCameras = 6;
inline constexpr double kRigRadius = 0.3;  // metres: the circle the rig's cameras sit on

struct SceneOptions {
  uint64_t seed = 1;
  LayoutOptions layout;
  int queries = 100;
  int features_per_image = 1500;
  double clutter_fraction = 0.33;  // share of each image's features that belong to no point
  double repetition = 0.3;         // share of facade points drawn from the motif pool
  int motifs = 256;                // size of the global motif pool
  double instance_noise = 0.3;     // how much two instances of one motif differ
  double keypoint_noise = 0.7;     // pixels, sigma per axis (truncated at 2.5 sigma)
  double point_noise = 0.01;       // metres, sigma per axis of the model's xyz at 20 m from
                                   // the nearest mapping camera (scaled with that distance,
                                   // as triangulation error is)
  double point_density = 0;        // facade points per m^2; 0: derived from features_per_image
  double max_distance = 60;        // metres
  double max_obliquity_deg = 70;   // between the viewing ray and the facade normal
  int min_query_points = 50;       // model points a query must see (redrawn otherwise)
  // 0: the queries are independent cameras; otherwise the frames of one walk down a street,
  // this many metres apart, in order (CityLayout::WalkCameras), each as it comes: a frame that
  // sees few model points is part of the walk.
  double path_step = 0;
  // 1: a query is one camera. 2..kMaxRigCameras: a query frame is a rig of this many cameras
  // (RigCameraPose), each an ordinary query image, so that rig localization can be tested.
  int rig_cameras = 1;
  colmap::Camera camera;  // shared by every image; camera_id 1
  PatchModel patch;
  ViewNoiseModel view_noise;
  int threads = 0;  // 0: all cores
};

// Camera `camera` of a rig of `cameras` in the rig frame (cam_from_rig, metres). Camera 0 is
// the reference sensor (the identity); camera c is camera 0 turned right by c * 360 / cameras
// degrees about its y (down) axis. All sit on a circle of kRigRadius looking outwards, camera 0
// at the rig origin, so that together they see all around as a street-level 360 rig does.
CameraPose RigCameraInRig(int camera, int cameras);

// That camera in the world when the rig frame (camera 0) is at `rig`.
CameraPose RigCameraPose(const CameraPose& rig, int camera, int cameras);

// Facade points per m^2 that fill an image's feature budget at typical distances.
double DefaultPointDensity(const SceneOptions& options);

// Expected model views (observations) per metre of facade, for sizing a city to a target.
double EstimatedViewsPerFacadeMetre(const SceneOptions& options);

inline constexpr uint32_t kNoPoint = std::numeric_limits<uint32_t>::max();
inline constexpr int32_t kUniqueTexture = -1;

struct ScenePoint {
  Eigen::Vector3d xyz;  // true position
  uint32_t facade = 0;
  int32_t motif = kUniqueTexture;
  float size = 0;   // metric scale of the feature (SIFT sigma), metres
  float angle = 0;  // its dominant gradient's direction on the facade, radians
};

// One keypoint of an image: a view of a point (with detection noise) or clutter.
struct SceneFeature {
  float x = 0, y = 0;         // pixels, COLMAP convention
  float scale = 0;            // pixels
  float orientation = 0;      // radians
  uint32_t point = kNoPoint;  // index into CityScene::points, kNoPoint for clutter
};

struct SceneImage {
  image_t image_id = 0;
  std::string name;
  bool query = false;
  CameraPose pose;
  std::vector<SceneFeature> features;
};

struct SceneCounts {
  size_t mapping_images = 0;
  size_t queries = 0;  // query images: frames x rig cameras
  size_t facades = 0;
  size_t scene_points = 0;  // all facade points, seen or not
  size_t model_points = 0;  // seen by >= 2 mapping images
  size_t views = 0;         // model observations
  size_t features = 0;      // all keypoints, queries included
  size_t clutter_features = 0;
  size_t mapping_features = 0;
  size_t mapping_clutter = 0;
  size_t single_view_features = 0;  // mapping features of points that did not make the model
  size_t motif_model_points = 0;    // model points that are motif instances
  size_t motif_views = 0;
  size_t distinct_motifs = 0;  // motifs with at least one model point
  size_t query_model_observations = 0;
  size_t min_query_model_points = 0;
};

class CityScene {
 public:
  using Progress = std::function<void(std::string_view stage, double fraction)>;

  // Generates everything but descriptors. Deterministic for (options minus threads).
  static CityScene Generate(const SceneOptions& options, const Progress& progress = {});

  const SceneOptions& options() const { return options_; }
  const CityLayout& layout() const { return layout_; }
  const std::vector<ScenePoint>& points() const { return points_; }
  // Mapping images first (image ids 1..M), then queries (M+1..M+Q), a rig frame's cameras
  // in order before the next frame's.
  const std::vector<SceneImage>& images() const { return images_; }
  size_t num_mapping_images() const { return num_mapping_images_; }
  // Model point3D id of a scene point, or kInvalidPoint3DId when fewer than 2 mapping images
  // see it. Ids are 1.. in point order.
  point3D_t Point3DId(uint32_t point) const { return point3D_ids_[point]; }
  const SceneCounts& counts() const { return counts_; }

  // The model's position of a point: the true one plus SfM-like noise (options.point_noise,
  // scaled with the distance to the nearest mapping camera that sees it).
  Eigen::Vector3d ModelXyz(uint32_t point) const;
  // Rigid3d of an image's pose, COLMAP's quaternion (w, x, y, z) and translation.
  colmap::Rigid3d CamFromWorld(const SceneImage& image) const;
  // Renders the 128 uint8 descriptor of one feature.
  void Describe(const SceneImage& image, size_t feature_index, uint8_t* out) const;
  // Projects a world point with an image's pose; false when behind or outside the model.
  bool Project(const CameraPose& pose, const Eigen::Vector3d& xyz, Eigen::Vector2d* pixel) const;

 private:
  explicit CityScene(const SceneOptions& options);
  struct Observation;
  std::vector<Observation> Observe(const CameraPose& pose, uint64_t image_seed,
                                   size_t budget) const;
  using ImageObservations = std::vector<std::vector<Observation>>;  // per image
  void MakePoints();
  // SfM registers an image only when it sees enough triangulated points (seen by >= 2
  // images): drops the images below `min_model_views` until nothing changes, since dropping
  // one can starve the points of another. Returns each point's views in the images kept.
  std::vector<uint32_t> KeepRegisteredImages(size_t min_model_views, std::vector<CameraPose>* poses,
                                             ImageObservations* observations) const;
  // A point enters the model when at least two mapping images see it, as triangulation needs:
  // sets point3D_ids_ and nearest_view_distance_, returns the model's points.
  size_t NumberModelPoints(const std::vector<CameraPose>& poses,
                           const ImageObservations& observations,
                           const std::vector<uint32_t>& view_count);
  // Queries: redraws a pose until its frame sees enough model points (keeps the best draw
  // otherwise), or the walk's frames as they come. With a rig the cameras count together, so
  // that some of them may see nothing (the sky, down a street), as a real rig's do.
  void DrawQueries(size_t budget, std::vector<CameraPose>* query_poses,
                   ImageObservations* query_observations) const;
  // images_: the mapping images, then the queries, with their names and poses.
  void NameImages(const std::vector<CameraPose>& poses, const std::vector<CameraPose>& query_poses);
  void MakeFeatures(SceneImage* image, std::vector<Observation>&& observations) const;
  void Count(const std::vector<uint32_t>& view_count, size_t num_model_points);

  SceneOptions options_;
  CityLayout layout_;
  SiftGenerator sift_;
  double focal_ = 0;  // mean focal length, pixels
  std::vector<ScenePoint> points_;
  std::vector<uint32_t> facade_points_;  // points of facade f: [facade_points_[f], [f+1])
  std::vector<SceneImage> images_;
  size_t num_mapping_images_ = 0;
  std::vector<point3D_t> point3D_ids_;
  std::vector<float> nearest_view_distance_;  // per point, metres (mapping images only)
  SceneCounts counts_;
};

}  // namespace cwloc::synth
