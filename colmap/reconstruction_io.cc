#include "colmap/reconstruction_io.h"

#include <algorithm>
#include <future>
#include <system_error>
#include <unordered_map>

#include "base/error.h"
#include "base/prefetch.h"

namespace cwloc::colmap {
namespace fs = std::filesystem;

namespace {

std::string FileName(const fs::path& path) { return path.filename().string(); }

std::string SensorName(const SensorId& sensor) {
  switch (sensor.type) {
    case SensorType::kCamera:
      return "CAMERA " + std::to_string(sensor.id);
    case SensorType::kImu:
      return "IMU " + std::to_string(sensor.id);
    default:
      return "INVALID " + std::to_string(sensor.id);
  }
}

// Image lookup by id for the track checks: a dense table when ids are compact (COLMAP
// numbers images from 1), a hash map otherwise.
class ImageTable {
 public:
  explicit ImageTable(std::map<image_t, Image>& images) {
    const image_t max_id = images.empty() ? 0 : images.rbegin()->first;
    if (max_id <= 4 * images.size() + 1024) {
      dense_.assign(static_cast<size_t>(max_id) + 1, nullptr);
      for (auto& [id, image] : images) dense_[id] = &image;
    } else {
      sparse_.reserve(images.size());
      for (auto& [id, image] : images) sparse_.emplace(id, &image);
    }
  }
  Image* Find(image_t id) const {
    if (!dense_.empty() || sparse_.empty()) return id < dense_.size() ? dense_[id] : nullptr;
    const auto it = sparse_.find(id);
    return it == sparse_.end() ? nullptr : it->second;
  }

 private:
  std::vector<Image*> dense_;
  std::unordered_map<image_t, Image*> sparse_;
};

void CheckRigsAndFrames(const detail::ModelFiles& files, Reconstruction* rec,
                        std::unordered_map<image_t, const Frame*>* frame_of_image,
                        std::unordered_map<image_t, SensorId>* sensor_of_image) {
  const std::string prefix_rigs = files.rigs.string() + ": rig ";
  for (const auto& [rig_id, rig] : rec->rigs) {
    std::vector<SensorId> seen;
    // clang 14 cannot capture a structured binding by reference.
    auto check = [&, rig_id = rig_id](const SensorId& sensor) {
      if (sensor.type == SensorType::kCamera && !rec->cameras.count(sensor.id)) {
        throw InputError(prefix_rigs + std::to_string(rig_id) + ": sensor " + SensorName(sensor) +
                         " is not in " + FileName(files.cameras));
      }
      if (std::find(seen.begin(), seen.end(), sensor) != seen.end()) {
        throw InputError(prefix_rigs + std::to_string(rig_id) + ": sensor " + SensorName(sensor) +
                         " is listed twice");
      }
      seen.push_back(sensor);
    };
    if (rig.ref_sensor.type != SensorType::kInvalid) check(rig.ref_sensor);
    for (const RigSensor& sensor : rig.sensors) check(sensor.sensor);
  }

  for (const auto& [frame_id, frame] : rec->frames) {
    const std::string where = files.frames.string() + ": frame " + std::to_string(frame_id);
    const auto rig_it = rec->rigs.find(frame.rig_id);
    if (rig_it == rec->rigs.end()) {
      throw InputError(where + ": rig_id " + std::to_string(frame.rig_id) + " is not in " +
                       FileName(files.rigs));
    }
    const Rig& rig = rig_it->second;
    for (const FrameDataId& data : frame.data_ids) {
      if (data.sensor.type != SensorType::kCamera) continue;  // IMU data: not used by COLMAP yet
      const bool in_rig = rig.ref_sensor == data.sensor ||
                          std::any_of(rig.sensors.begin(), rig.sensors.end(),
                                      [&](const RigSensor& s) { return s.sensor == data.sensor; });
      if (!in_rig) {
        throw InputError(where + ": data of sensor " + SensorName(data.sensor) +
                         " but that camera is not a sensor of rig " + std::to_string(rig.rig_id));
      }
      if (data.data_id > std::numeric_limits<image_t>::max()) {
        throw InputError(where + ": image data id " + std::to_string(data.data_id) +
                         " does not fit a 32-bit image_id");
      }
      const auto image_id = static_cast<image_t>(data.data_id);
      const auto [it, inserted] = frame_of_image->emplace(image_id, &frame);
      if (!inserted) {
        throw InputError(where + ": image " + std::to_string(image_id) + " is also in frame " +
                         std::to_string(it->second->frame_id));
      }
      sensor_of_image->emplace(image_id, data.sensor);
    }
  }
}

// COLMAP's cam_from_world for an image of a rig: sensor_from_rig * rig_from_world.
void SetImagePoseFromFrame(const detail::ModelFiles& files, const Reconstruction& rec,
                           const Frame& frame, const SensorId& listed_sensor, Image* image) {
  const std::string image_name = "image " + std::to_string(image->image_id);
  const SensorId sensor{SensorType::kCamera, image->camera_id};
  if (!(listed_sensor == sensor)) {
    throw InputError(files.frames.string() + ": frame " + std::to_string(frame.frame_id) +
                     " lists " + image_name + " as data of " + SensorName(listed_sensor) +
                     ", but " + image_name + " has camera_id " + std::to_string(image->camera_id) +
                     " in " + FileName(files.images));
  }
  const Rig& rig = rec.rigs.at(frame.rig_id);
  if (rig.ref_sensor == sensor) {
    image->cam_from_world = frame.rig_from_world;
    return;
  }
  for (const RigSensor& s : rig.sensors) {
    if (!(s.sensor == sensor)) continue;
    if (!s.sensor_from_rig) {
      throw InputError(files.rigs.string() + ": rig " + std::to_string(rig.rig_id) + ": sensor " +
                       SensorName(sensor) + " has no sensor_from_rig, needed for the pose of " +
                       image_name + " (frame " + std::to_string(frame.frame_id) + ")");
    }
    image->cam_from_world = *s.sensor_from_rig * frame.rig_from_world;
    return;
  }
  // Unreachable after CheckRigsAndFrames, which checks frames' camera data against rigs.
  throw InputError(files.frames.string() + ": frame " + std::to_string(frame.frame_id) + ": " +
                   SensorName(sensor) + " is not a sensor of rig " + std::to_string(rig.rig_id));
}

// Locates the point2D whose reference is not matched by a track (slow; error path only).
[[noreturn]] void ReportUnmatchedPoint2D(const detail::ModelFiles& files,
                                         const Reconstruction& rec) {
  for (const auto& [image_id, image] : rec.images) {
    for (size_t idx = 0; idx < image.points2D.size(); ++idx) {
      const point3D_t point_id = image.points2D[idx].point3D_id;
      if (point_id == kInvalidPoint3DId) continue;
      const std::string where = files.images.string() + ": image " + std::to_string(image_id) +
                                ": point2D " + std::to_string(idx) + " refers to point3D " +
                                std::to_string(point_id);
      const auto it = rec.points3D.find(point_id);
      if (it == rec.points3D.end()) {
        throw InputError(where + ", which is not in " + FileName(files.points3D));
      }
      const auto& track = it->second.track;
      const bool listed =
          std::any_of(track.begin(), track.end(), [&, image_id = image_id](const TrackElement& el) {
            return el.image_id == image_id && el.point2D_idx == idx;
          });
      if (!listed) throw InputError(where + ", whose track does not list it");
    }
  }
  throw InputError(files.images.string() + ": points2D and the tracks in " +
                   FileName(files.points3D) + " disagree");
}

[[noreturn]] void ReportBackReference(const detail::ModelFiles& files, const Reconstruction& rec,
                                      point3D_t point_id, size_t element) {
  const TrackElement& el = rec.points3D.at(point_id).track[element];
  const point3D_t back = rec.images.at(el.image_id).points2D[el.point2D_idx].point3D_id;
  throw InputError(files.points3D.string() + ": point3D " + std::to_string(point_id) +
                   ": track element " + std::to_string(element) + " is point2D " +
                   std::to_string(el.point2D_idx) + " of image " + std::to_string(el.image_id) +
                   ", whose point3D_id is " +
                   (back == kInvalidPoint3DId ? std::string("-1") : std::to_string(back)) + " in " +
                   FileName(files.images) + ", not " + std::to_string(point_id));
}

void CheckTracks(const detail::ModelFiles& files, Reconstruction* rec) {
  ImageTable table(rec->images);
  // The back-reference of each track element is a random read into some image's points2D.
  // They are checked in batches, prefetched when queued, so that the reads overlap instead of
  // each waiting for memory (3x faster on a model with 10 million observations).
  struct Pending {
    const Point2D* point2D;
    point3D_t point_id;
    size_t element;
  };
  constexpr size_t kBatch = 1024;
  std::vector<Pending> pending;
  pending.reserve(kBatch);
  auto check_pending = [&] {
    for (const Pending& p : pending) {
      if (p.point2D->point3D_id != p.point_id) {
        ReportBackReference(files, *rec, p.point_id, p.element);
      }
    }
    pending.clear();
  };

  std::vector<uint64_t> keys;
  size_t num_observations = 0;
  for (const auto& [point_id, point] : rec->points3D) {
    const auto where = [&, id = point_id]() {
      return files.points3D.string() + ": point3D " + std::to_string(id) + ": ";
    };
    for (size_t i = 0; i < point.track.size(); ++i) {
      const TrackElement& el = point.track[i];
      const Image* image = table.Find(el.image_id);
      if (!image) {
        check_pending();
        throw InputError(where() + "track element " + std::to_string(i) + " refers to image " +
                         std::to_string(el.image_id) + ", which is not in " +
                         FileName(files.images));
      }
      if (el.point2D_idx >= image->points2D.size()) {
        check_pending();
        throw InputError(where() + "track element " + std::to_string(i) + " has point2D_idx " +
                         std::to_string(el.point2D_idx) + " but image " +
                         std::to_string(el.image_id) + " has " +
                         std::to_string(image->points2D.size()) + " points2D");
      }
      const Point2D* point2D = &image->points2D[el.point2D_idx];
      Prefetch(point2D);
      pending.push_back({point2D, point_id, i});
      if (pending.size() == kBatch) check_pending();
    }
    if (point.track.size() > 1) {
      keys.clear();
      for (const TrackElement& el : point.track) {
        keys.push_back(uint64_t{el.image_id} << 32 | el.point2D_idx);
      }
      std::sort(keys.begin(), keys.end());
      const auto dup = std::adjacent_find(keys.begin(), keys.end());
      if (dup != keys.end()) {
        check_pending();
        throw InputError(where() + "track lists point2D " + std::to_string(*dup & 0xffffffffu) +
                         " of image " + std::to_string(*dup >> 32) + " twice");
      }
    }
    num_observations += point.track.size();
  }
  check_pending();

  // Each track element now names a distinct point2D that refers back to its point. If the
  // number of referencing points2D equals the number of track elements, that is a bijection
  // and every reference is valid, without a lookup per point2D.
  size_t num_references = 0;
  for (const auto& [image_id, image] : rec->images) {
    for (const Point2D& p : image.points2D) num_references += p.point3D_id != kInvalidPoint3DId;
  }
  if (num_references != num_observations) ReportUnmatchedPoint2D(files, *rec);
}

}  // namespace

namespace detail {

ModelFiles FilesOf(const fs::path& dir, ModelFormat format) {
  const std::string ext = format == ModelFormat::kBinary ? ".bin" : ".txt";
  ModelFiles files;
  files.cameras = dir / ("cameras" + ext);
  files.images = dir / ("images" + ext);
  files.points3D = dir / ("points3D" + ext);
  files.rigs = dir / ("rigs" + ext);
  files.frames = dir / ("frames" + ext);
  return files;
}

void FinishReconstruction(const ModelFiles& files, Reconstruction* rec) {
  std::unordered_map<image_t, const Frame*> frame_of_image;
  std::unordered_map<image_t, SensorId> sensor_of_image;
  if (files.has_rigs) CheckRigsAndFrames(files, rec, &frame_of_image, &sensor_of_image);

  for (auto& [image_id, image] : rec->images) {
    if (!rec->cameras.count(image.camera_id)) {
      throw InputError(files.images.string() + ": image " + std::to_string(image_id) +
                       ": camera_id " + std::to_string(image.camera_id) + " is not in " +
                       FileName(files.cameras));
    }
    if (!files.has_rigs) continue;
    const auto it = frame_of_image.find(image_id);
    if (it == frame_of_image.end()) {
      throw InputError(files.images.string() + ": image " + std::to_string(image_id) +
                       " is in no frame of " + FileName(files.frames));
    }
    SetImagePoseFromFrame(files, *rec, *it->second, sensor_of_image.at(image_id), &image);
  }
  CheckTracks(files, rec);
}

void RigsAndFramesToWrite(const Reconstruction& rec, std::map<rig_t, Rig>* rigs,
                          std::map<frame_t, Frame>* frames) {
  if (!rec.rigs.empty() || !rec.frames.empty()) {
    *rigs = rec.rigs;
    *frames = rec.frames;
    return;
  }
  rigs->clear();
  frames->clear();
  for (const auto& [camera_id, camera] : rec.cameras) {
    Rig rig;
    rig.rig_id = camera_id;
    rig.ref_sensor = {SensorType::kCamera, camera_id};
    rigs->emplace(camera_id, rig);
  }
  for (const auto& [image_id, image] : rec.images) {
    Frame frame;
    frame.frame_id = image_id;
    frame.rig_id = image.camera_id;
    frame.rig_from_world = image.cam_from_world;
    frame.data_ids.push_back({{SensorType::kCamera, image.camera_id}, image_id});
    frames->emplace(image_id, std::move(frame));
  }
}

}  // namespace detail

Reconstruction ReadReconstruction(const fs::path& dir, int threads) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(dir.string() + ": not a directory (expected a COLMAP sparse model)");
  }
  if (fs::exists(dir / "cameras.bin", ec)) return ReadReconstructionBinary(dir, threads);
  if (fs::exists(dir / "cameras.txt", ec)) return ReadReconstructionText(dir, threads);
  throw InputError(dir.string() +
                   ": no COLMAP model (expected cameras.bin, images.bin, points3D.bin or the "
                   "same .txt files)");
}

void WriteReconstruction(const Reconstruction& reconstruction, const fs::path& dir,
                         ModelFormat format, ModelLayout layout) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(dir.string() + ": not a directory (create it before writing a model)");
  }
  if (layout == ModelLayout::kClassic) {
    const detail::ModelFiles files = detail::FilesOf(dir, format);
    for (const fs::path& stale : {files.rigs, files.frames}) {
      fs::remove(stale, ec);
      if (ec) throw InputError(stale.string() + ": cannot remove stale file: " + ec.message());
    }
  }
  detail::WriteModel(reconstruction, dir, format, layout);
}

namespace detail {
namespace {

const ModelFileCodec& CodecOf(ModelFormat format) {
  return format == ModelFormat::kBinary ? BinaryCodec() : TextCodec();
}

}  // namespace

Reconstruction ReadModel(const fs::path& dir, ModelFormat format, int threads) {
  const ModelFileCodec& codec = CodecOf(format);
  ModelFiles files = FilesOf(dir, format);
  std::error_code ec;
  const bool has_rigs = fs::exists(files.rigs, ec);
  const bool has_frames = fs::exists(files.frames, ec);
  if (has_rigs != has_frames) {
    const std::string rigs = files.rigs.filename().string(),
                      frames = files.frames.filename().string();
    throw InputError(dir.string() + ": has " +
                     (has_rigs ? rigs + " but no " + frames : frames + " but no " + rigs) +
                     " (a COLMAP >= 3.12 model needs both)");
  }
  files.has_rigs = has_rigs;
  Reconstruction rec;
  codec.read_cameras(files.cameras, &rec);
  if (files.has_rigs) {
    codec.read_rigs(files.rigs, &rec);
    codec.read_frames(files.frames, &rec);
  }
  if (threads > 1) {
    // The two fill separate maps. A 10.8M-view city's binary model: 0.67 -> 0.39 s (medians of
    // 5, each thread's allocations in its own jemalloc arena).
    std::future<void> points =
        std::async(std::launch::async, [&] { codec.read_points3D(files.points3D, &rec); });
    try {
      codec.read_images(files.images, &rec);
    } catch (...) {
      points.wait();
      throw;
    }
    points.get();
  } else {
    codec.read_images(files.images, &rec);
    codec.read_points3D(files.points3D, &rec);
  }
  FinishReconstruction(files, &rec);
  return rec;
}

void WriteModel(const Reconstruction& rec, const fs::path& dir, ModelFormat format,
                ModelLayout layout) {
  const ModelFileCodec& codec = CodecOf(format);
  const ModelFiles files = FilesOf(dir, format);
  if (layout == ModelLayout::kRigs) {
    std::map<rig_t, Rig> rigs;
    std::map<frame_t, Frame> frames;
    RigsAndFramesToWrite(rec, &rigs, &frames);
    codec.write_rigs(rigs, files.rigs);
    codec.write_cameras(rec, files.cameras);
    codec.write_frames(frames, files.frames);
  } else {
    codec.write_cameras(rec, files.cameras);
  }
  codec.write_images(rec, files.images);
  codec.write_points3D(rec, files.points3D);
}

}  // namespace detail

}  // namespace cwloc::colmap
