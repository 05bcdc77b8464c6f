#include "tools/synth/scene_writer.h"

#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <condition_variable>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <mutex>
#include <thread>

#include "base/atomic_file.h"
#include "base/error.h"
#include "base/parallel_for.h"
#include "base/stopwatch.h"
#include "camera/camera_models.h"
#include "colmap/database.h"
#include "colmap/reconstruction_io.h"

namespace cwloc::synth {
namespace fs = std::filesystem;
namespace {

constexpr uint64_t kColorStream = 200;

std::string Format(const char* format, double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), format, value);
  return buffer;
}

// Shortest text that reads back to the same double.
std::string Exact(double value) {
  char buffer[32];
  for (int precision = 6; precision <= 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, value);
    if (std::strtod(buffer, nullptr) == value) break;
  }
  return buffer;
}

// Appends " field" (piecewise: GCC 12 warns falsely about " " + std::string).
void AppendField(std::string* line, const std::string& field) {
  *line += ' ';
  *line += field;
}

std::string CameraText(const colmap::Camera& camera) {
  const auto info = FindCameraModel(int32_t(camera.model_id));
  std::string text = std::string(info ? info->name : "UNKNOWN") + " " +
                     std::to_string(camera.width) + " " + std::to_string(camera.height);
  for (double p : camera.params) AppendField(&text, Exact(p));
  return text;
}

void WriteTextFile(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  out.close();
  if (!out) throw InputError("cannot write '" + path.string() + "'");
}

bool IsNonEmptyDirectory(const fs::path& path) {
  std::error_code ec;
  return fs::is_directory(path, ec) && !fs::is_empty(path, ec);
}

// README.txt's section on the query rig; empty without one.
std::string RigReadmeText(const SceneOptions& o) {
  if (o.rig_cameras < 2) return "";
  const std::string n = std::to_string(o.rig_cameras);
  std::string t = "\nQUERY RIG (--rig-cameras " + n + ")\n";
  t += "  Every query is one frame of a rig of " + n +
       " cameras (all with the shared camera's intrinsics), for rig localization:\n";
  t += "  camC/query_NNNNN.jpg is camera C of frame NNNNN, and the query files list a frame's "
       "cameras together.\n";
  t += "  cam0 is the reference sensor (the rig frame); camera c is cam0 turned right by c x " +
       Format("%.6g", 360.0 / o.rig_cameras) + " deg about its\n";
  t += "  down (y) axis, all on a " + Format("%.3g", kRigRadius) +
       " m circle looking outwards. A frame was accepted when its cameras together see\n";
  t += "  enough model points, so single cameras may see none. rig_config.json: each camera's "
       "cam_from_rig in the\n";
  t += "  model frame, in the format of COLMAP 3.12's rig_configurator.\n";
  return t;
}

// COLMAP 3.12's rig_config.json, cam_from_rig in the model frame: the model frame is a
// similarity of the world, and camera frames in it are scaled alike (ModelFrame::CamFromModel),
// so rotations stay and translations scale.
std::string RigConfigText(const SceneOptions& o, const ModelFrame& frame) {
  auto number = [](double value) { return Format("%.17g", value + 0.0); };  // no "-0"
  std::string t = "[\n  {\n    \"cameras\": [\n";
  t += "      {\n        \"image_prefix\": \"cam0/\",\n        \"ref_sensor\": true\n      }";
  for (int c = 1; c < o.rig_cameras; ++c) {
    const CameraPose in_rig = RigCameraInRig(c, o.rig_cameras);
    Eigen::Quaterniond q(in_rig.cam_from_world_rotation);
    if (q.w() < 0) q.coeffs() *= -1;
    const Eigen::Vector3d x = -frame.scale * (in_rig.cam_from_world_rotation * in_rig.centre);
    t += ",\n      {\n        \"image_prefix\": \"cam" + std::to_string(c) + "/\",\n";
    t += "        \"cam_from_rig_rotation\": [" + number(q.w()) + ", " + number(q.x()) + ", " +
         number(q.y()) + ", " + number(q.z()) + "],\n";
    t += "        \"cam_from_rig_translation\": [" + number(x.x()) + ", " + number(x.y()) + ", " +
         number(x.z()) + "]\n      }";
  }
  t += "\n    ]\n  }\n]\n";
  return t;
}

std::string ReadmeText(const CityScene& scene, const WriteOptions& options) {
  const SceneOptions& o = scene.options();
  const SceneCounts& c = scene.counts();
  const LayoutOptions& l = o.layout;
  std::string t;
  t += "Generated city scene (cwloc-synth): COLMAP model + database + held-out queries with exact "
       "ground truth\n";
  t += "==========================================================================================="
       "==============\n\n";
  t += "HOW IT WAS MADE\n";
  t += "  Command: " + options.command_line + "\n";
  t += "  Seed " + std::to_string(o.seed) +
       ". The output is byte-identical for the same seed and knobs\n";
  t += "  (whatever --threads), except this command line and the timings in stats.json.\n\n";
  t += "  A grid of " + std::to_string(l.blocks_x) + " x " + std::to_string(l.blocks_y) +
       " blocks separated by streets; every block side is split into buildings whose facades\n";
  t += "  carry feature points: unique texture, and a share (" + Format("%.3g", o.repetition) +
       ") of instances of " + std::to_string(o.motifs) + " motifs repeated all over the city\n";
  t += "  (rows of a few instances per facade; instance noise " + Format("%.3g", o.instance_noise) +
       "). Mapping cameras walk along every block side\n";
  t += "  (one view across the street every " + Format("%.3g", l.camera_spacing) +
       " m, an oblique one every second station); queries stand at random places\n";
  t += "  in the streets. A view sees the facade points in its frustum that are not occluded by a "
       "block,\n";
  t += "  within " + Format("%.3g", o.max_distance) + " m and " +
       Format("%.3g", o.max_obliquity_deg) +
       " deg of obliquity, detected with a probability that falls with obliquity;\n";
  t += "  each image keeps its " + std::to_string(o.features_per_image) +
       " x (1 - clutter) strongest features and adds clutter (share " +
       Format("%.3g", o.clutter_fraction) + ") that belongs to no point.\n";
  t += "  Keypoints carry " + Format("%.3g", o.keypoint_noise) +
       " px Gaussian noise (truncated at 2.5 sigma); model xyz carry " +
       Format("%.3g", o.point_noise) +
       " m noise at 20 m from the nearest camera (scaled with distance).\n";
  t += "  Descriptors are SIFT-like (COLMAP's uint8 L1-root convention), rendered from a patch "
       "model\n";
  t += "  seen through each view's affine distortion; see docs/synth.md in the cwloc sources.\n\n";
  t += "COUNTS\n";
  t += "  mapping images:      " + std::to_string(c.mapping_images) + "\n";
  t += "  queries:             " + std::to_string(c.queries);
  if (o.rig_cameras > 1) {
    t += " (" + std::to_string(o.queries) + " frames of a " + std::to_string(o.rig_cameras) +
         "-camera rig)";
  }
  t += "\n";
  t += "  model 3D points:     " + std::to_string(c.model_points) + " (of " +
       std::to_string(c.scene_points) + " facade points)\n";
  t += "  model views:         " + std::to_string(c.views) + "\n";
  t += "  features (all):      " + std::to_string(c.features) + ", clutter " +
       std::to_string(c.clutter_features) + "\n";
  t += "  camera (shared, id 1): " + CameraText(o.camera) + "\n\n";
  t += "FILES\n";
  t += "  database.db                 COLMAP 3.8 database: cameras, images, keypoints (6 columns), "
       "descriptors\n";
  t += "                              for ALL images, queries included; no matches. Image ids "
       "match the model.\n";
  t += "  mapping_model/bin (/txt)    the model to localize against: mapping images only. Every "
       "keypoint of an\n";
  t += "                              image is a POINTS2D entry in database row order; clutter and "
       "points seen\n";
  t += "                              by a single image have POINT3D_ID -1.\n";
  t += "  query_list.txt              query image names, one per line\n";
  t += "  queries_gt.txt              NAME QW QX QY QZ TX TY TZ CAMERA_MODEL W H PARAMS (exact "
       "poses)\n";
  t += "  queries_with_intrinsics.txt NAME CAMERA_MODEL W H PARAMS\n";
  t += "  queries_gt_points.txt       NAME then the model POINT3D_IDs the query sees (location "
       "recognition GT)\n";
  t +=
      "  queries_gt_matches.txt      NAME then POINT2D_IDX:POINT3D_ID pairs (true 2D-3D matches)\n";
  if (o.rig_cameras > 1) {
    t += "  rig_config.json             COLMAP 3.12 rig config of the query rig (see QUERY RIG)\n";
  }
  if (!options.geo.origin) {
    t += "  scale_to_metres.txt         identity similarity: the city is built in metres\n";
    t += "  stats.json                  counts, timings, peak memory\n";
    return t + RigReadmeText(o);
  }
  const GeoOptions& geo = options.geo;
  t += "  scale_to_metres.txt         similarity model -> ENU metres at the city centre (--geo)\n";
  t += "  georef.txt                  NAME LAT LON HEIGHT: every mapping image's noisy GPS "
       "position\n";
  t += "  georef_outliers.txt         the mapping images whose GPS position is an outlier\n";
  t += "  queries_geo.txt             NAME LAT LON HEIGHT: the queries' true camera centres\n";
  t += "  query_priors.txt            NAME position LAT LON HEIGHT RADIUS_M and NAME gravity GX GY "
       "GZ per query\n";
  t += "  stats.json                  counts, timings, peak memory\n\n";
  char origin[96];
  std::snprintf(origin, sizeof(origin), "%.12f, %.12f, %.3f m", geo.origin->latitude_deg,
                geo.origin->longitude_deg, geo.origin->height_m);
  t += "ON THE GLOBE (--geo)\n";
  t += "  The city centre on the ground lies at WGS84 " + std::string(origin) +
       " above the ellipsoid;\n";
  t += "  the east-north-up frame there is the world frame (x east, y north, z up) moved to "
       "that centre.\n";
  t += "  The model (mapping_model, queries_gt.txt) is in an arbitrary SfM-like frame, a seeded "
       "similarity of it;\n";
  t += "  scale_to_metres.txt maps it back to ENU metres. GPS noise " +
       Format("%.3g", geo.gps_noise) + " m per axis, outlier share " +
       Format("%.3g", geo.gps_outliers) + ";\n";
  t += "  query priors " + Format("%.3g", geo.prior_position_error) +
       " m off horizontally (radius " + Format("%.3g", geo.prior_radius) + " m), gravity " +
       Format("%.3g", geo.prior_gravity_error_deg) + " deg off.\n";
  return t + RigReadmeText(o);
}

// Renders descriptors on worker threads while the calling thread writes the database in
// image order: a bounded window of finished images keeps memory flat.
void WriteDatabase(const CityScene& scene, const fs::path& path, int threads,
                   const CityScene::Progress& progress) {
  colmap::DatabaseWriter db(path);
  colmap::Camera camera = scene.options().camera;
  camera.camera_id = 1;
  db.WriteCamera(camera);
  const auto& images = scene.images();
  for (const SceneImage& image : images) db.WriteImage({image.image_id, image.name, 1});

  if (threads <= 0) threads = int(std::max(1u, std::thread::hardware_concurrency()));
  const size_t n = images.size();
  const size_t window = size_t(4 * threads + 4);
  struct Slot {
    std::vector<colmap::Keypoint> keypoints;
    colmap::Descriptors descriptors;
    bool ready = false;
  };
  std::vector<Slot> slots(window);
  std::mutex mutex;
  std::condition_variable cv;
  size_t next = 0, written = 0;
  bool stop = false;
  std::exception_ptr error;

  auto worker = [&] {
    for (;;) {
      size_t i;
      {
        std::unique_lock lock(mutex);
        cv.wait(lock, [&] { return stop || next >= n || next < written + window; });
        if (stop || next >= n) return;
        i = next++;
      }
      try {
        const SceneImage& image = images[i];
        Slot& slot = slots[i % window];
        const size_t rows = image.features.size();
        slot.keypoints.resize(rows);
        slot.descriptors.rows = uint32_t(rows);
        slot.descriptors.data.resize(rows * colmap::kDescriptorDim);
        for (size_t k = 0; k < rows; ++k) {
          const SceneFeature& f = image.features[k];
          // COLMAP's FeatureKeypoint(x, y, scale, orientation).
          const float c = f.scale * std::cos(f.orientation), s = f.scale * std::sin(f.orientation);
          slot.keypoints[k] = {f.x, f.y, c, -s, s, c};
          scene.Describe(image, k, slot.descriptors.data.data() + k * colmap::kDescriptorDim);
        }
        std::lock_guard lock(mutex);
        slot.ready = true;
      } catch (...) {
        std::lock_guard lock(mutex);
        if (!error) error = std::current_exception();
        stop = true;
      }
      cv.notify_all();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  try {
    for (size_t i = 0; i < n; ++i) {
      Slot& slot = slots[i % window];
      {
        std::unique_lock lock(mutex);
        cv.wait(lock, [&] { return slot.ready || stop; });
        if (stop) break;
      }
      db.WriteKeypoints(images[i].image_id, slot.keypoints);
      db.WriteDescriptors(images[i].image_id, slot.descriptors);
      {
        std::lock_guard lock(mutex);
        slot.ready = false;
        written = i + 1;
      }
      cv.notify_all();
      if (progress && (i % 16 == 0 || i + 1 == n)) progress("database", double(i + 1) / double(n));
    }
  } catch (...) {
    std::lock_guard lock(mutex);
    if (!error) error = std::current_exception();
    stop = true;
  }
  {
    std::lock_guard lock(mutex);
    stop = true;
  }
  cv.notify_all();
  for (auto& t : pool) t.join();
  if (error) std::rethrow_exception(error);
  db.Commit();
}

void WriteQueryFiles(const CityScene& scene, const ModelFrame& frame, const fs::path& dir) {
  const std::string camera = CameraText(scene.options().camera);
  std::string list, gt, intrinsics, points, matches;
  gt +=
      "# Ground-truth query poses (exact: the generator placed these cameras; same frame as "
      "mapping_model).\n";
  gt += "# COLMAP convention: world-to-camera, X_cam = R(q) * X_world + t, q = (qw qx qy qz).\n";
  gt +=
      "# Camera centre C = -R^T t. Pixel coords: COLMAP convention (origin at top-left corner of "
      "top-left pixel).\n";
  gt += "# NAME QW QX QY QZ TX TY TZ CAMERA_MODEL WIDTH HEIGHT PARAMS...\n";
  points += "# Model 3D points each query sees: the ground truth for location recognition.\n";
  points +=
      "# One line per query: NAME POINT3D_ID... (ids of mapping_model, ascending; none when it "
      "sees no model point)\n";
  matches +=
      "# True 2D-3D matches of each query: its keypoint rows (database.db) that are views of model "
      "points.\n";
  matches += "# One line per query: NAME POINT2D_IDX:POINT3D_ID... (ascending POINT2D_IDX)\n";
  for (const SceneImage& image : scene.images()) {
    if (!image.query) continue;
    list += image.name + "\n";
    const colmap::Rigid3d pose = frame.CamFromModel(scene, image);
    gt += image.name;
    for (double q : pose.rotation) AppendField(&gt, Exact(q));
    for (double v : pose.translation) AppendField(&gt, Exact(v));
    AppendField(&gt, camera);
    gt += '\n';
    intrinsics += image.name + " " + camera + "\n";
    std::vector<point3D_t> seen;
    matches += image.name;
    for (size_t k = 0; k < image.features.size(); ++k) {
      const uint32_t p = image.features[k].point;
      if (p == kNoPoint || scene.Point3DId(p) == kInvalidPoint3DId) continue;
      seen.push_back(scene.Point3DId(p));
      AppendField(&matches, std::to_string(k));
      matches += ':';
      matches += std::to_string(scene.Point3DId(p));
    }
    matches += "\n";
    std::sort(seen.begin(), seen.end());
    seen.erase(std::unique(seen.begin(), seen.end()), seen.end());
    points += image.name;
    for (point3D_t id : seen) AppendField(&points, std::to_string(id));
    points += "\n";
  }
  WriteTextFile(dir / "query_list.txt", list);
  WriteTextFile(dir / "queries_gt.txt", gt);
  WriteTextFile(dir / "queries_with_intrinsics.txt", intrinsics);
  WriteTextFile(dir / "queries_gt_points.txt", points);
  WriteTextFile(dir / "queries_gt_matches.txt", matches);
  if (!frame.identity) return;  // --geo writes the model -> ENU similarity instead
  WriteTextFile(
      dir / "scale_to_metres.txt",
      "# Similarity model->metric frame (metres): identity, the generated city is built in metres\n"
      "# X_gt = s * R * X_model + t\n"
      "scale 1\n"
      "R 1 0 0 0 1 0 0 0 1\n"
      "t 0 0 0\n");
}

}  // namespace

colmap::Reconstruction BuildReconstruction(const CityScene& scene, int threads,
                                           const ModelFrame& frame) {
  colmap::Reconstruction rec;
  colmap::Camera camera = scene.options().camera;
  camera.camera_id = 1;
  rec.cameras.emplace(1, camera);

  // Tracks in image order, then point order: point3D ids are 1..M.
  std::vector<std::vector<colmap::TrackElement>> tracks(scene.counts().model_points);
  const auto& images = scene.images();
  for (size_t i = 0; i < scene.num_mapping_images(); ++i) {
    const SceneImage& image = images[i];
    colmap::Image& out = rec.images[image.image_id];
    out.image_id = image.image_id;
    out.camera_id = 1;
    out.name = image.name;
    out.cam_from_world = frame.CamFromModel(scene, image);
    out.points2D.resize(image.features.size());
    for (size_t k = 0; k < image.features.size(); ++k) {
      const SceneFeature& f = image.features[k];
      colmap::Point2D& p = out.points2D[k];
      p.x = f.x;
      p.y = f.y;
      if (f.point != kNoPoint) {
        p.point3D_id = scene.Point3DId(f.point);
        if (p.point3D_id != kInvalidPoint3DId) {
          tracks[p.point3D_id - 1].push_back({image.image_id, point2D_t(k)});
        }
      }
    }
  }
  // Positions (with SfM-like noise), colours and the mean reprojection error of each track.
  std::vector<uint32_t> point_of_id(tracks.size());
  for (uint32_t p = 0; p < scene.points().size(); ++p) {
    const point3D_t id = scene.Point3DId(p);
    if (id != kInvalidPoint3DId) point_of_id[id - 1] = p;
  }
  std::vector<colmap::Point3D> points(tracks.size());
  ParallelFor((tracks.size() + 4095) / 4096, threads, [&](size_t chunk) {
    for (size_t j = chunk * 4096; j < std::min(tracks.size(), (chunk + 1) * 4096); ++j) {
      const uint32_t p = point_of_id[j];
      colmap::Point3D& out = points[j];
      out.point3D_id = j + 1;
      const Eigen::Vector3d xyz = scene.ModelXyz(p);
      const Eigen::Vector3d model_xyz = frame.ModelFromWorld(xyz);
      out.xyz = {model_xyz.x(), model_xyz.y(), model_xyz.z()};
      const auto& facade = scene.layout().facades()[scene.points()[p].facade];
      Rng rng(Rng::Seed(scene.options().seed, kColorStream, p));
      for (int ch = 0; ch < 3; ++ch) {
        out.color[ch] = uint8_t(std::clamp(facade.color[ch] + 20 * rng.Gaussian(), 0.0, 255.0));
      }
      double error = 0;
      for (const colmap::TrackElement& e : tracks[j]) {
        const SceneImage& image = images[e.image_id - 1];
        const SceneFeature& f = image.features[e.point2D_idx];
        Eigen::Vector2d pixel;
        if (scene.Project(image.pose, xyz, &pixel))
          error += (pixel - Eigen::Vector2d(f.x, f.y)).norm();
      }
      out.error = tracks[j].empty() ? 0 : error / double(tracks[j].size());
      out.track = std::move(tracks[j]);
    }
  });
  std::vector<std::vector<colmap::TrackElement>>().swap(tracks);
  for (auto& point : points)
    rec.points3D.emplace_hint(rec.points3D.end(), point.point3D_id, std::move(point));
  return rec;
}

SceneWriter::SceneWriter(const fs::path& output_dir, bool overwrite)
    : output_dir_(output_dir), overwrite_(overwrite) {
  if (output_dir.empty()) throw InputError("--output: an output directory is required");
  std::error_code ec;
  const fs::file_status status = fs::status(output_dir, ec);
  if (fs::exists(status) && !fs::is_directory(status)) {
    throw InputError("output path '" + output_dir.string() + "' exists and is not a directory");
  }
  if (!overwrite && IsNonEmptyDirectory(output_dir)) {
    throw InputError("output directory '" + output_dir.string() +
                     "' exists and is not empty (use --overwrite to replace it)");
  }
  fs::path absolute = fs::absolute(output_dir, ec);
  if (ec) absolute = output_dir;
  absolute = absolute.lexically_normal();
  if (!absolute.has_filename()) absolute = absolute.parent_path();
  output_dir_ = absolute;
  const fs::path parent = absolute.parent_path();
  fs::create_directories(parent, ec);
  if (ec) {
    throw InputError("cannot create output directory '" + parent.string() + "': " + ec.message());
  }
  // A killed writer's folder carries its pid: the next writer of this output removes it.
  RemoveDeadWritersTemporaries(absolute);
  std::string pattern =
      (parent / (absolute.filename().string() + ".tmp-" + std::to_string(::getpid()) + "-XXXXXX"))
          .string();
  if (::mkdtemp(pattern.data()) == nullptr) {
    throw InputError("cannot create output directory '" + output_dir.string() +
                     "': " + std::strerror(errno));
  }
  temp_dir_ = pattern;
  // mkdtemp makes the directory private; the output should get the usual permissions.
  const mode_t mask = ::umask(0);
  ::umask(mask);
  ::chmod(temp_dir_.c_str(), 0777 & ~mask);
}

SceneWriter::~SceneWriter() {
  if (committed_ || temp_dir_.empty()) return;
  std::error_code ec;
  fs::remove_all(temp_dir_, ec);
}

WriteTimings SceneWriter::Write(const CityScene& scene, const WriteOptions& options,
                                const CityScene::Progress& progress) {
  WriteTimings timings;
  Stopwatch stage;
  const ModelFrame frame = MakeModelFrame(scene, options.geo);
  {
    if (progress) progress("model", 0);
    const colmap::Reconstruction rec = BuildReconstruction(scene, options.threads, frame);
    for (const char* format : {"bin", "txt"}) {
      if (format[0] == 't' && !options.text) continue;
      const fs::path dir = temp_dir_ / "mapping_model" / format;
      std::error_code ec;
      fs::create_directories(dir, ec);
      if (ec) throw InputError("cannot create '" + dir.string() + "': " + ec.message());
      colmap::WriteReconstruction(
          rec, dir, format[0] == 'b' ? colmap::ModelFormat::kBinary : colmap::ModelFormat::kText);
    }
  }
  timings.model_seconds = stage.Seconds();
  stage.Restart();
  WriteDatabase(scene, temp_dir_ / "database.db", options.threads, progress);
  timings.database_seconds = stage.Seconds();
  stage.Restart();
  WriteQueryFiles(scene, frame, temp_dir_);
  if (scene.options().rig_cameras > 1)
    WriteTextFile(temp_dir_ / "rig_config.json", RigConfigText(scene.options(), frame));
  if (options.geo.origin) {
    const GeoFiles geo = MakeGeoFiles(scene, options.geo, frame);
    WriteTextFile(temp_dir_ / "georef.txt", geo.georef);
    WriteTextFile(temp_dir_ / "georef_outliers.txt", geo.georef_outliers);
    WriteTextFile(temp_dir_ / "queries_geo.txt", geo.queries_geo);
    WriteTextFile(temp_dir_ / "query_priors.txt", geo.query_priors);
    WriteTextFile(temp_dir_ / "scale_to_metres.txt", geo.scale_to_metres);
  }
  WriteTextFile(temp_dir_ / "README.txt", ReadmeText(scene, options));
  timings.files_seconds = stage.Seconds();
  return timings;
}

void SceneWriter::Commit(const std::string& stats_json) {
  WriteTextFile(temp_dir_ / "stats.json", stats_json);
  std::error_code ec;
  fs::path old;
  if (IsNonEmptyDirectory(output_dir_)) {
    if (!overwrite_) {
      throw InputError("output directory '" + output_dir_.string() +
                       "' appeared while generating and is not empty");
    }
    // One atomic swap: the destination holds the old scene or the new one at every moment; the
    // old one, now under the temporary name, is removed next (or by the next writer after a kill).
    if (::renameat2(AT_FDCWD, temp_dir_.c_str(), AT_FDCWD, output_dir_.c_str(), RENAME_EXCHANGE) ==
        0) {
      committed_ = true;
      fs::remove_all(temp_dir_, ec);
      return;
    }
    // File systems without RENAME_EXCHANGE: move the old scene aside first.
    std::string pattern = output_dir_.string() + ".old-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      throw InputError("cannot replace '" + output_dir_.string() + "': " + std::strerror(errno));
    }
    old = pattern;
    fs::rename(output_dir_, old, ec);
    if (ec) throw InputError("cannot replace '" + output_dir_.string() + "': " + ec.message());
  }
  fs::rename(temp_dir_, output_dir_, ec);
  if (ec) {
    if (!old.empty()) fs::rename(old, output_dir_, ec);
    throw InputError("cannot move the output into '" + output_dir_.string() + "': " + ec.message());
  }
  committed_ = true;
  if (!old.empty()) fs::remove_all(old, ec);
}

}  // namespace cwloc::synth
