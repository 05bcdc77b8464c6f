// cameras.bin, images.bin, points3D.bin (+ rigs.bin, frames.bin) exactly as COLMAP writes
// them (src/colmap/scene/reconstruction_io_binary.cc): no header, a uint64 record count per
// file, then packed little-endian records. Decoding is byte-wise, so any host works.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cerrno>
#include <memory>
#include <system_error>

#include "base/atomic_file.h"
#include "base/bounded_file.h"
#include "base/error.h"
#include "colmap/reconstruction_io.h"

namespace cwloc::colmap {
namespace fs = std::filesystem;

namespace {

// Smallest possible record sizes, to reject a count that the rest of the file cannot hold
// before anything is allocated for it.
constexpr uint64_t kMinCameraBytes = 4 + 4 + 8 + 8 + 2 * 8;  // EQUIRECTANGULAR has 2 params
constexpr uint64_t kMinImageBytes = 4 + 7 * 8 + 4 + 1 + 8;   // empty name, no points2D
constexpr uint64_t kPoint2DBytes = 8 + 8 + 8;
constexpr uint64_t kMinPoint3DBytes = 8 + 3 * 8 + 3 + 8 + 8;
constexpr uint64_t kTrackElementBytes = 4 + 4;
constexpr uint64_t kMinRigBytes = 4 + 4;
constexpr uint64_t kRefSensorBytes = 4 + 4;
constexpr uint64_t kMinSensorBytes = 4 + 4 + 1;
constexpr uint64_t kMinFrameBytes = 4 + 4 + 7 * 8 + 4;
constexpr uint64_t kDataIdBytes = 4 + 4 + 8;

inline uint32_t LoadU32(const uint8_t* p) {
  return uint32_t{p[0]} | uint32_t{p[1]} << 8 | uint32_t{p[2]} << 16 | uint32_t{p[3]} << 24;
}
inline uint64_t LoadU64(const uint8_t* p) {
  return uint64_t{LoadU32(p)} | uint64_t{LoadU32(p + 4)} << 32;
}
inline double LoadF64(const uint8_t* p) { return std::bit_cast<double>(LoadU64(p)); }

inline void StoreU32(char* p, uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<char>(v >> (8 * i));
}
inline void StoreU64(char* p, uint64_t v) {
  for (int i = 0; i < 8; ++i) p[i] = static_cast<char>(v >> (8 * i));
}
inline void StoreF64(char* p, double v) { StoreU64(p, std::bit_cast<uint64_t>(v)); }

// Reads a file through a 1 MiB window. Every read is bounds-checked against the file size and
// failures name the file, the record being read, the field and the byte offset.
class BinaryReader {
 public:
  static constexpr size_t kWindow = size_t{1} << 20;

  explicit BinaryReader(fs::path path) : path_(std::move(path)) {
    CheckInputFile(path_, kColmapModelFile);  // before open(), which waits on a pipe
    fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) Fail("cannot open: " + std::generic_category().message(errno), false);
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      Fail("not a regular file", false);
    }
    file_size_ = static_cast<uint64_t>(st.st_size);
    // A small file gets a small buffer: a take longer than the file fails anyway.
    window_ = static_cast<size_t>(std::clamp<uint64_t>(file_size_, 64, kWindow));
    buffer_ = std::make_unique_for_overwrite<uint8_t[]>(window_);
    pos_ = end_ = buffer_.get();
  }
  ~BinaryReader() { ::close(fd_); }
  BinaryReader(const BinaryReader&) = delete;
  BinaryReader& operator=(const BinaryReader&) = delete;

  const fs::path& path() const { return path_; }
  uint64_t Offset() const { return buffer_offset_ + static_cast<uint64_t>(pos_ - buffer_.get()); }
  uint64_t Remaining() const { return file_size_ - Offset(); }

  // Names the record that the next reads belong to, e.g. ("image", 12) -> "image 12".
  void SetRecord(const char* kind, uint64_t id) {
    record_kind_ = kind;
    record_id_ = id;
    record_has_id_ = true;
    record_is_index_ = false;
  }
  // Before the record's id is known: ("image", 3) -> "image record #3".
  void SetRecordIndex(const char* kind, uint64_t index) {
    SetRecord(kind, index);
    record_is_index_ = true;
  }

  // `n` contiguous bytes (n <= kWindow), or an error naming `field`.
  const uint8_t* Take(size_t n, const char* field) {
    if (static_cast<size_t>(end_ - pos_) < n) Refill(n, field);
    const uint8_t* p = pos_;
    pos_ += n;
    return p;
  }
  uint8_t U8(const char* field) { return *Take(1, field); }
  uint32_t U32(const char* field) { return LoadU32(Take(4, field)); }
  int32_t I32(const char* field) { return static_cast<int32_t>(U32(field)); }
  uint64_t U64(const char* field) { return LoadU64(Take(8, field)); }
  double F64(const char* field) { return LoadF64(Take(8, field)); }

  // A count followed by `count` items of at least `min_item_bytes` plus `extra_bytes` more.
  uint64_t Count(const char* field, uint64_t min_item_bytes, uint64_t extra_bytes = 0) {
    const uint64_t count = U64(field);
    CheckCount(field, count, min_item_bytes, extra_bytes);
    return count;
  }
  void CheckCount(const char* field, uint64_t count, uint64_t min_item_bytes,
                  uint64_t extra_bytes = 0) {
    const uint64_t remaining = Remaining();
    if (extra_bytes > remaining || count > (remaining - extra_bytes) / min_item_bytes) {
      Fail(std::string(field) + " = " + std::to_string(count) + " does not fit in the " +
           std::to_string(remaining) + " bytes left at byte " + std::to_string(Offset()) +
           " (each needs at least " + std::to_string(min_item_bytes) + ")");
    }
  }

  // A '\0'-terminated string (COLMAP's image name).
  std::string String(const char* field) {
    std::string s;
    for (;;) {
      if (pos_ == end_) Refill(1, field);
      const auto* nul = static_cast<const uint8_t*>(std::memchr(pos_, 0, end_ - pos_));
      const uint8_t* stop = nul ? nul : end_;
      s.append(reinterpret_cast<const char*>(pos_), stop - pos_);
      pos_ = stop;
      if (nul) {
        ++pos_;
        return s;
      }
    }
  }

  void ExpectEnd(const char* after) {
    if (Remaining() != 0) {
      record_kind_ = nullptr;
      Fail(std::to_string(Remaining()) + " unexpected bytes after the last " + after + " (byte " +
           std::to_string(Offset()) + " of " + std::to_string(file_size_) + ")");
    }
  }

  [[noreturn]] void Fail(const std::string& what, bool with_record = true) const {
    std::string message = path_.string() + ": ";
    if (with_record && record_kind_) {
      message += record_kind_;
      if (record_has_id_) {
        message += record_is_index_ ? " record #" : " ";
        message += std::to_string(record_id_);
      }
      message += ": ";
    }
    throw InputError(message + what);
  }

 private:
  void Refill(size_t n, const char* field) {
    const size_t have = static_cast<size_t>(end_ - pos_);
    buffer_offset_ += static_cast<uint64_t>(pos_ - buffer_.get());
    std::memmove(buffer_.get(), pos_, have);
    pos_ = buffer_.get();
    end_ = pos_ + have;
    while (static_cast<size_t>(end_ - pos_) < n) {
      const ssize_t got =
          ::read(fd_, const_cast<uint8_t*>(end_), window_ - static_cast<size_t>(end_ - pos_));
      if (got < 0) {
        if (errno == EINTR) continue;
        Fail(std::string("read error in ") + field + ": " + std::generic_category().message(errno));
      }
      if (got == 0) {
        Fail(std::string("unexpected end of file reading ") + field + " at byte " +
             std::to_string(Offset()) + " (file is " + std::to_string(file_size_) + " bytes)");
      }
      end_ += got;
    }
  }

  fs::path path_;
  int fd_ = -1;
  uint64_t file_size_ = 0;
  size_t window_ = 0;  // buffer_'s size
  std::unique_ptr<uint8_t[]> buffer_;
  const uint8_t* pos_ = nullptr;
  const uint8_t* end_ = nullptr;
  uint64_t buffer_offset_ = 0;          // file offset of buffer_[0]
  const char* record_kind_ = "header";  // the leading count
  uint64_t record_id_ = 0;
  bool record_has_id_ = false;
  bool record_is_index_ = false;
};

Rigid3d ReadPose(BinaryReader& in, const char* field) {
  Rigid3d pose;
  const uint8_t* p = in.Take(7 * 8, field);
  for (int i = 0; i < 4; ++i) pose.rotation[i] = LoadF64(p + 8 * i);
  for (int i = 0; i < 3; ++i) pose.translation[i] = LoadF64(p + 32 + 8 * i);
  return pose;
}

SensorId ReadSensor(BinaryReader& in, const char* field) {
  const int32_t type = in.I32(field);
  if (type != 0 && type != 1) {
    in.Fail(std::string(field) + " has sensor type " + std::to_string(type) +
            " (expected 0 = CAMERA or 1 = IMU)");
  }
  return {static_cast<SensorType>(type), in.U32(field)};
}

void ReadCameras(const fs::path& path, Reconstruction* rec) {
  BinaryReader in(path);
  const uint64_t count = in.Count("num_cameras", kMinCameraBytes);
  for (uint64_t i = 0; i < count; ++i) {
    in.SetRecordIndex("camera", i);
    Camera camera;
    camera.camera_id = in.U32("camera_id");
    in.SetRecord("camera", camera.camera_id);
    const int32_t model_id = in.I32("model_id");
    const auto model = FindCameraModel(model_id);
    if (!model) {
      in.Fail("unknown camera model id " + std::to_string(model_id) + " (expected 0.." +
              std::to_string(AllCameraModels().size() - 1) + ")");
    }
    camera.model_id = model->id;
    camera.width = in.U64("width");
    camera.height = in.U64("height");
    const uint8_t* p = in.Take(8 * static_cast<size_t>(model->num_params), "params");
    camera.params.resize(static_cast<size_t>(model->num_params));
    for (size_t j = 0; j < camera.params.size(); ++j) camera.params[j] = LoadF64(p + 8 * j);
    if (!rec->cameras.emplace(camera.camera_id, std::move(camera)).second) {
      in.Fail("duplicate camera_id");
    }
  }
  in.ExpectEnd("camera");
}

void ReadImages(const fs::path& path, Reconstruction* rec) {
  BinaryReader in(path);
  const uint64_t count = in.Count("num_reg_images", kMinImageBytes);
  for (uint64_t i = 0; i < count; ++i) {
    in.SetRecordIndex("image", i);
    Image image;
    image.image_id = in.U32("image_id");
    in.SetRecord("image", image.image_id);
    image.cam_from_world = ReadPose(in, "cam_from_world");
    image.camera_id = in.U32("camera_id");
    image.name = in.String("name");
    const uint64_t num_points2D = in.Count("num_points2D", kPoint2DBytes);
    image.points2D.resize(num_points2D);
    constexpr size_t kBatch = BinaryReader::kWindow / kPoint2DBytes;
    for (size_t done = 0; done < num_points2D;) {
      const size_t n = std::min<size_t>(kBatch, num_points2D - done);
      const uint8_t* p = in.Take(n * kPoint2DBytes, "points2D");
      for (size_t j = 0; j < n; ++j, p += kPoint2DBytes) {
        Point2D& point = image.points2D[done + j];
        point.x = LoadF64(p);
        point.y = LoadF64(p + 8);
        point.point3D_id = LoadU64(p + 16);
      }
      done += n;
    }
    const image_t id = image.image_id;
    const size_t before = rec->images.size();
    rec->images.emplace_hint(rec->images.end(), id, std::move(image));  // O(1) when sorted
    if (rec->images.size() == before) in.Fail("duplicate image_id");
  }
  in.ExpectEnd("image");
}

void ReadPoints3D(const fs::path& path, Reconstruction* rec) {
  BinaryReader in(path);
  const uint64_t count = in.Count("num_points3D", kMinPoint3DBytes);
  for (uint64_t i = 0; i < count; ++i) {
    in.SetRecordIndex("point3D", i);
    Point3D point;
    point.point3D_id = in.U64("point3D_id");
    in.SetRecord("point3D", point.point3D_id);
    const uint8_t* p = in.Take(3 * 8 + 3 + 8, "xyz, color, error");
    for (int j = 0; j < 3; ++j) point.xyz[j] = LoadF64(p + 8 * j);
    for (int j = 0; j < 3; ++j) point.color[j] = p[24 + j];
    point.error = LoadF64(p + 27);
    const uint64_t length = in.Count("track_length", kTrackElementBytes);
    point.track.resize(length);
    constexpr size_t kBatch = BinaryReader::kWindow / kTrackElementBytes;
    for (size_t done = 0; done < length;) {
      const size_t n = std::min<size_t>(kBatch, length - done);
      const uint8_t* q = in.Take(n * kTrackElementBytes, "track");
      for (size_t j = 0; j < n; ++j, q += kTrackElementBytes) {
        point.track[done + j] = {LoadU32(q), LoadU32(q + 4)};
      }
      done += n;
    }
    const point3D_t id = point.point3D_id;
    const size_t before = rec->points3D.size();
    rec->points3D.emplace_hint(rec->points3D.end(), id, std::move(point));
    if (rec->points3D.size() == before) in.Fail("duplicate point3D_id");
  }
  in.ExpectEnd("point3D");
}

void ReadRigs(const fs::path& path, Reconstruction* rec) {
  BinaryReader in(path);
  const uint64_t count = in.Count("num_rigs", kMinRigBytes);
  for (uint64_t i = 0; i < count; ++i) {
    in.SetRecordIndex("rig", i);
    Rig rig;
    rig.rig_id = in.U32("rig_id");
    in.SetRecord("rig", rig.rig_id);
    const uint32_t num_sensors = in.U32("num_sensors");
    if (num_sensors == 0) {
      rig.ref_sensor = {SensorType::kInvalid, UINT32_MAX};
    } else {
      in.CheckCount("num_sensors", num_sensors - 1, kMinSensorBytes, kRefSensorBytes);
      rig.ref_sensor = ReadSensor(in, "ref_sensor");
      rig.sensors.resize(num_sensors - 1);
      for (RigSensor& sensor : rig.sensors) {
        sensor.sensor = ReadSensor(in, "sensor");
        const uint8_t has_pose = in.U8("has_pose");
        if (has_pose > 1) {
          in.Fail("has_pose of sensor " + std::to_string(sensor.sensor.id) + " is " +
                  std::to_string(has_pose) + " (expected 0 or 1)");
        }
        if (has_pose) sensor.sensor_from_rig = ReadPose(in, "sensor_from_rig");
      }
    }
    if (!rec->rigs.emplace(rig.rig_id, std::move(rig)).second) in.Fail("duplicate rig_id");
  }
  in.ExpectEnd("rig");
}

void ReadFrames(const fs::path& path, Reconstruction* rec) {
  BinaryReader in(path);
  const uint64_t count = in.Count("num_frames", kMinFrameBytes);
  for (uint64_t i = 0; i < count; ++i) {
    in.SetRecordIndex("frame", i);
    Frame frame;
    frame.frame_id = in.U32("frame_id");
    in.SetRecord("frame", frame.frame_id);
    frame.rig_id = in.U32("rig_id");
    frame.rig_from_world = ReadPose(in, "rig_from_world");
    const uint32_t num_data_ids = in.U32("num_data_ids");
    in.CheckCount("num_data_ids", num_data_ids, kDataIdBytes);
    frame.data_ids.resize(num_data_ids);
    for (FrameDataId& data : frame.data_ids) {
      data.sensor = ReadSensor(in, "data_id");
      data.data_id = in.U64("data_id");
    }
    if (!rec->frames.emplace(frame.frame_id, std::move(frame)).second) {
      in.Fail("duplicate frame_id");
    }
  }
  in.ExpectEnd("frame");
}

// Binary writing through AtomicFileWriter's buffer.
class BinaryWriter {
 public:
  explicit BinaryWriter(const fs::path& path) : out_(path) {}
  void U8(uint8_t v) {
    char* p = out_.Ensure(1);
    *p = static_cast<char>(v);
    out_.Advance(p + 1);
  }
  void U32(uint32_t v) {
    char* p = out_.Ensure(4);
    StoreU32(p, v);
    out_.Advance(p + 4);
  }
  void I32(int32_t v) { U32(static_cast<uint32_t>(v)); }
  void U64(uint64_t v) {
    char* p = out_.Ensure(8);
    StoreU64(p, v);
    out_.Advance(p + 8);
  }
  void F64(double v) { U64(std::bit_cast<uint64_t>(v)); }
  void Pose(const Rigid3d& pose) {
    for (double v : pose.rotation) F64(v);
    for (double v : pose.translation) F64(v);
  }
  void Sensor(const SensorId& sensor) {
    I32(static_cast<int32_t>(sensor.type));
    U32(sensor.id);
  }
  void String(const std::string& s) { out_.Append(s.c_str(), s.size() + 1); }  // with '\0'
  AtomicFileWriter& out() { return out_; }
  void Commit() { out_.Commit(); }

 private:
  AtomicFileWriter out_;
};

void WriteCameras(const Reconstruction& rec, const fs::path& path) {
  BinaryWriter out(path);
  out.U64(rec.cameras.size());
  for (const auto& [id, camera] : rec.cameras) {
    out.U32(id);
    out.I32(static_cast<int32_t>(camera.model_id));
    out.U64(camera.width);
    out.U64(camera.height);
    for (double v : camera.params) out.F64(v);
  }
  out.Commit();
}

void WriteImages(const Reconstruction& rec, const fs::path& path) {
  BinaryWriter out(path);
  out.U64(rec.images.size());
  for (const auto& [id, image] : rec.images) {
    out.U32(id);
    out.Pose(image.cam_from_world);
    out.U32(image.camera_id);
    out.String(image.name);
    out.U64(image.points2D.size());
    for (const Point2D& point : image.points2D) {
      char* p = out.out().Ensure(kPoint2DBytes);
      StoreF64(p, point.x);
      StoreF64(p + 8, point.y);
      StoreU64(p + 16, point.point3D_id);
      out.out().Advance(p + kPoint2DBytes);
    }
  }
  out.Commit();
}

void WritePoints3D(const Reconstruction& rec, const fs::path& path) {
  BinaryWriter out(path);
  out.U64(rec.points3D.size());
  for (const auto& [id, point] : rec.points3D) {
    out.U64(id);
    for (double v : point.xyz) out.F64(v);
    for (uint8_t c : point.color) out.U8(c);
    out.F64(point.error);
    out.U64(point.track.size());
    for (const TrackElement& el : point.track) {
      char* p = out.out().Ensure(kTrackElementBytes);
      StoreU32(p, el.image_id);
      StoreU32(p + 4, el.point2D_idx);
      out.out().Advance(p + kTrackElementBytes);
    }
  }
  out.Commit();
}

void WriteRigs(const std::map<rig_t, Rig>& rigs, const fs::path& path) {
  BinaryWriter out(path);
  out.U64(rigs.size());
  for (const auto& [id, rig] : rigs) {
    out.U32(id);
    const bool has_ref = rig.ref_sensor.type != SensorType::kInvalid;
    if (!has_ref && !rig.sensors.empty()) {
      throw std::invalid_argument("rig " + std::to_string(id) +
                                  " has sensors but no reference sensor");
    }
    out.U32(static_cast<uint32_t>(rig.sensors.size() + (has_ref ? 1 : 0)));
    if (has_ref) out.Sensor(rig.ref_sensor);
    for (const RigSensor& sensor : rig.sensors) {
      out.Sensor(sensor.sensor);
      out.U8(sensor.sensor_from_rig ? 1 : 0);
      if (sensor.sensor_from_rig) out.Pose(*sensor.sensor_from_rig);
    }
  }
  out.Commit();
}

void WriteFrames(const std::map<frame_t, Frame>& frames, const fs::path& path) {
  BinaryWriter out(path);
  out.U64(frames.size());
  for (const auto& [id, frame] : frames) {
    out.U32(id);
    out.U32(frame.rig_id);
    out.Pose(frame.rig_from_world);
    out.U32(static_cast<uint32_t>(frame.data_ids.size()));
    for (const FrameDataId& data : frame.data_ids) {
      out.Sensor(data.sensor);
      out.U64(data.data_id);
    }
  }
  out.Commit();
}

}  // namespace

Reconstruction ReadReconstructionBinary(const fs::path& dir, int threads) {
  return detail::ReadModel(dir, ModelFormat::kBinary, threads);
}

namespace detail {

const ModelFileCodec& BinaryCodec() {
  static const ModelFileCodec codec{ReadCameras,  ReadRigs,     ReadFrames,  ReadImages,
                                    ReadPoints3D, WriteCameras, WriteImages, WritePoints3D,
                                    WriteRigs,    WriteFrames};
  return codec;
}

}  // namespace detail
}  // namespace cwloc::colmap
