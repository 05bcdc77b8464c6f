// cameras.txt, images.txt, points3D.txt (+ rigs.txt, frames.txt) as COLMAP writes them
// (src/colmap/scene/reconstruction_io_text.cc): '#' comment headers, one record per line
// (two for images), values separated by single spaces, doubles with 17 significant digits.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <memory>
#include <system_error>

#include "base/atomic_file.h"
#include "base/bounded_file.h"
#include "base/error.h"
#include "colmap/reconstruction_io.h"

namespace cwloc::colmap {
namespace fs = std::filesystem;

namespace {

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

std::string_view Trim(std::string_view s) {
  while (!s.empty() && IsSpace(s.front())) s.remove_prefix(1);
  while (!s.empty() && IsSpace(s.back())) s.remove_suffix(1);
  return s;
}

// Reads lines through a growing buffer (up to 1 MiB to start, the file's size when smaller; one
// images.txt line holds all points2D of an image and may be longer).
class LineReader {
 public:
  explicit LineReader(fs::path path) : path_(std::move(path)) {
    CheckInputFile(path_, kColmapModelFile);  // before open(), which waits on a pipe
    fd_ = ::open(path_.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) {
      throw InputError(path_.string() + ": cannot open: " + std::generic_category().message(errno));
    }
    struct stat st {};
    if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
      ::close(fd_);
      throw InputError(path_.string() + ": not a regular file");
    }
    capacity_ = static_cast<size_t>(std::clamp<off_t>(st.st_size + 1, 64, off_t{1} << 20));
    buffer_ = std::make_unique_for_overwrite<char[]>(capacity_);
  }
  ~LineReader() { ::close(fd_); }
  LineReader(const LineReader&) = delete;
  LineReader& operator=(const LineReader&) = delete;

  // The next line without its '\n'; false at the end of the file.
  bool Next(std::string_view* line) {
    size_t scanned = begin_;
    for (;;) {
      const char* nl =
          static_cast<const char*>(std::memchr(buffer_.get() + scanned, '\n', end_ - scanned));
      if (nl) {
        const size_t stop = static_cast<size_t>(nl - buffer_.get());
        *line = std::string_view(buffer_.get() + begin_, stop - begin_);
        begin_ = stop + 1;
        ++line_number_;
        return true;
      }
      scanned = end_;
      if (eof_) {
        if (begin_ == end_) return false;
        *line = std::string_view(buffer_.get() + begin_, end_ - begin_);
        begin_ = end_;
        ++line_number_;
        return true;
      }
      // Keep the partial line, make room, read more.
      scanned -= begin_;
      std::memmove(buffer_.get(), buffer_.get() + begin_, end_ - begin_);
      end_ -= begin_;
      begin_ = 0;
      if (end_ == capacity_) {  // one line fills the buffer: grow it
        auto bigger = std::make_unique_for_overwrite<char[]>(capacity_ * 2);
        std::memcpy(bigger.get(), buffer_.get(), end_);
        buffer_ = std::move(bigger);
        capacity_ *= 2;
      }
      const ssize_t got = ::read(fd_, buffer_.get() + end_, capacity_ - end_);
      if (got < 0) {
        if (errno == EINTR) continue;
        throw InputError(path_.string() + ": read error after line " +
                         std::to_string(line_number_) + ": " +
                         std::generic_category().message(errno));
      }
      if (got == 0) eof_ = true;
      end_ += static_cast<size_t>(got);
    }
  }

  const fs::path& path() const { return path_; }
  size_t line_number() const { return line_number_; }

 private:
  fs::path path_;
  int fd_ = -1;
  size_t capacity_ = 0;
  std::unique_ptr<char[]> buffer_;
  size_t begin_ = 0, end_ = 0;
  bool eof_ = false;
  size_t line_number_ = 0;
};

// Next data line: skips blank lines and '#' comments.
bool NextRecordLine(LineReader& reader, std::string_view* line) {
  while (reader.Next(line)) {
    *line = Trim(*line);
    if (!line->empty() && line->front() != '#') return true;
  }
  return false;
}

// Splits one line into tokens and parses them; errors name file, line, record and field.
class LineParser {
 public:
  LineParser(const LineReader& reader, std::string_view line, const char* kind)
      : reader_(reader), rest_(line), kind_(kind) {}

  void SetId(uint64_t id) { id_ = std::to_string(id); }

  bool AtEnd() {
    SkipSpace();
    return rest_.empty();
  }
  std::string_view Rest() { return Trim(rest_); }

  std::string_view Token(const char* field) {
    SkipSpace();
    if (rest_.empty()) Fail(std::string(field) + ": missing (the line ends early)");
    size_t n = 0;
    while (n < rest_.size() && !IsSpace(rest_[n])) ++n;
    const std::string_view token = rest_.substr(0, n);
    rest_.remove_prefix(n);
    return token;
  }

  template <typename T>
  T Unsigned(const char* field, const char* what) {
    const std::string_view token = Token(field);
    T value{};
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    if (ec != std::errc() || ptr != token.data() + token.size()) Expected(field, what, token);
    return value;
  }
  uint32_t U32(const char* field) {
    return Unsigned<uint32_t>(field, "an unsigned 32-bit integer");
  }
  uint64_t U64(const char* field) {
    return Unsigned<uint64_t>(field, "an unsigned 64-bit integer");
  }
  double F64(const char* field) {
    std::string_view token = Token(field);
    const std::string_view original = token;
    if (token.size() > 1 && token.front() == '+') token.remove_prefix(1);
    double value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    // ERANGE: a denormal or overflowing literal; from_chars leaves `value` unset then.
    if (ec != std::errc() || ptr != token.data() + token.size()) {
      Expected(field, "a number", original);
    }
    return value;
  }
  Rigid3d Pose(const char* field) {
    Rigid3d pose;
    for (double& v : pose.rotation) v = F64(field);
    for (double& v : pose.translation) v = F64(field);
    return pose;
  }
  SensorId Sensor(const char* field) {
    const std::string_view type = Token(field);
    SensorId sensor;
    if (type == "CAMERA") {
      sensor.type = SensorType::kCamera;
    } else if (type == "IMU") {
      sensor.type = SensorType::kImu;
    } else {
      Expected(field, "CAMERA or IMU", type);
    }
    sensor.id = U32(field);
    return sensor;
  }
  void ExpectEnd() {
    if (!AtEnd()) {
      Fail("unexpected extra values '" + Shorten(Rest()) + "' at the end of the line");
    }
  }

  [[noreturn]] void Expected(const char* field, const char* what, std::string_view token) const {
    Fail(std::string(field) + ": expected " + what + ", found '" + Shorten(token) + "'");
  }
  [[noreturn]] void Fail(const std::string& what) const {
    std::string message =
        reader_.path().string() + ":" + std::to_string(reader_.line_number()) + ": " + kind_;
    if (!id_.empty()) message += " " + id_;
    throw InputError(message + ": " + what);
  }

 private:
  static std::string Shorten(std::string_view s) {
    return s.size() <= 40 ? std::string(s) : std::string(s.substr(0, 40)) + "...";
  }
  void SkipSpace() {
    while (!rest_.empty() && IsSpace(rest_.front())) rest_.remove_prefix(1);
  }

  const LineReader& reader_;
  std::string_view rest_;
  const char* kind_;
  std::string id_;
};

void ReadCameras(const fs::path& path, Reconstruction* rec) {
  LineReader reader(path);
  std::string_view line;
  while (NextRecordLine(reader, &line)) {
    LineParser in(reader, line, "camera");
    Camera camera;
    camera.camera_id = in.U32("CAMERA_ID");
    in.SetId(camera.camera_id);
    const std::string_view name = in.Token("MODEL");
    const auto model = FindCameraModel(name);
    if (!model) in.Expected("MODEL", "a COLMAP camera model name", name);
    camera.model_id = model->id;
    camera.width = in.U64("WIDTH");
    camera.height = in.U64("HEIGHT");
    while (!in.AtEnd()) camera.params.push_back(in.F64("PARAMS"));
    if (camera.params.size() != static_cast<size_t>(model->num_params)) {
      in.Fail("PARAMS: model " + std::string(model->name) + " expects " +
              std::to_string(model->num_params) + " parameters, found " +
              std::to_string(camera.params.size()));
    }
    if (!rec->cameras.emplace(camera.camera_id, std::move(camera)).second) {
      in.Fail("duplicate CAMERA_ID");
    }
  }
}

void ReadImages(const fs::path& path, Reconstruction* rec) {
  LineReader reader(path);
  std::string_view line;
  while (NextRecordLine(reader, &line)) {
    Image image;
    {
      LineParser in(reader, line, "image");
      image.image_id = in.U32("IMAGE_ID");
      in.SetId(image.image_id);
      image.cam_from_world = in.Pose("QW, QX, QY, QZ, TX, TY, TZ");
      image.camera_id = in.U32("CAMERA_ID");
      // The rest of the line, so that names with spaces survive (COLMAP would cut them).
      image.name = std::string(in.Rest());
      // The second line is always the points2D line, even when empty.
      if (!reader.Next(&line)) in.Fail("POINTS2D: missing (the file ends after the image line)");
    }
    LineParser in(reader, Trim(line), "image");
    in.SetId(image.image_id);
    while (!in.AtEnd()) {
      Point2D point;
      point.x = in.F64("POINTS2D X");
      point.y = in.F64("POINTS2D Y");
      const std::string_view id = in.Token("POINTS2D POINT3D_ID");
      if (id != "-1") {
        const auto [ptr, ec] = std::from_chars(id.data(), id.data() + id.size(), point.point3D_id);
        if (ec != std::errc() || ptr != id.data() + id.size()) {
          in.Expected("POINTS2D POINT3D_ID", "-1 or an unsigned 64-bit integer", id);
        }
      }
      image.points2D.push_back(point);
    }
    const image_t id = image.image_id;
    const size_t before = rec->images.size();
    rec->images.emplace_hint(rec->images.end(), id, std::move(image));
    if (rec->images.size() == before) in.Fail("duplicate IMAGE_ID");
  }
}

void ReadPoints3D(const fs::path& path, Reconstruction* rec) {
  LineReader reader(path);
  std::string_view line;
  while (NextRecordLine(reader, &line)) {
    LineParser in(reader, line, "point3D");
    Point3D point;
    point.point3D_id = in.U64("POINT3D_ID");
    in.SetId(point.point3D_id);
    for (double& v : point.xyz) v = in.F64("X, Y, Z");
    for (uint8_t& c : point.color) {
      const uint32_t value = in.U32("R, G, B");
      if (value > 255) in.Fail("R, G, B: " + std::to_string(value) + " is not in 0..255");
      c = static_cast<uint8_t>(value);
    }
    point.error = in.F64("ERROR");
    while (!in.AtEnd()) {
      TrackElement el;
      el.image_id = in.U32("TRACK IMAGE_ID");
      el.point2D_idx = in.U32("TRACK POINT2D_IDX");
      point.track.push_back(el);
    }
    const point3D_t id = point.point3D_id;
    const size_t before = rec->points3D.size();
    rec->points3D.emplace_hint(rec->points3D.end(), id, std::move(point));
    if (rec->points3D.size() == before) in.Fail("duplicate POINT3D_ID");
  }
}

void ReadRigs(const fs::path& path, Reconstruction* rec) {
  LineReader reader(path);
  std::string_view line;
  while (NextRecordLine(reader, &line)) {
    LineParser in(reader, line, "rig");
    Rig rig;
    rig.rig_id = in.U32("RIG_ID");
    in.SetId(rig.rig_id);
    const uint32_t num_sensors = in.U32("NUM_SENSORS");
    if (num_sensors == 0) {
      rig.ref_sensor = {SensorType::kInvalid, UINT32_MAX};
    } else {
      rig.ref_sensor = in.Sensor("REF_SENSOR");
      // No reserve from the count: the line itself bounds how many sensors can follow.
      for (uint32_t i = 1; i < num_sensors; ++i) {
        RigSensor sensor;
        sensor.sensor = in.Sensor("SENSORS");
        const uint32_t has_pose = in.U32("HAS_POSE");
        if (has_pose > 1) in.Fail("HAS_POSE: expected 0 or 1, found " + std::to_string(has_pose));
        if (has_pose) sensor.sensor_from_rig = in.Pose("SENSOR_FROM_RIG");
        rig.sensors.push_back(sensor);
      }
    }
    in.ExpectEnd();
    if (!rec->rigs.emplace(rig.rig_id, std::move(rig)).second) in.Fail("duplicate RIG_ID");
  }
}

void ReadFrames(const fs::path& path, Reconstruction* rec) {
  LineReader reader(path);
  std::string_view line;
  while (NextRecordLine(reader, &line)) {
    LineParser in(reader, line, "frame");
    Frame frame;
    frame.frame_id = in.U32("FRAME_ID");
    in.SetId(frame.frame_id);
    frame.rig_id = in.U32("RIG_ID");
    frame.rig_from_world = in.Pose("RIG_FROM_WORLD");
    const uint32_t num_data_ids = in.U32("NUM_DATA_IDS");
    for (uint32_t i = 0; i < num_data_ids; ++i) {
      FrameDataId data;
      data.sensor = in.Sensor("DATA_IDS");
      data.data_id = in.U64("DATA_IDS");
      frame.data_ids.push_back(data);
    }
    in.ExpectEnd();
    if (!rec->frames.emplace(frame.frame_id, std::move(frame)).second) {
      in.Fail("duplicate FRAME_ID");
    }
  }
}

// Text output through AtomicFileWriter's buffer, numbers formatted in place.
class TextWriter {
 public:
  explicit TextWriter(const fs::path& path) : out_(path) {}
  TextWriter& operator<<(std::string_view s) {
    out_.Append(s);
    return *this;
  }
  TextWriter& operator<<(char c) {
    char* p = out_.Ensure(1);
    *p = c;
    out_.Advance(p + 1);
    return *this;
  }
  TextWriter& operator<<(uint64_t v) {
    char* p = out_.Ensure(24);
    out_.Advance(std::to_chars(p, p + 24, v).ptr);
    return *this;
  }
  TextWriter& operator<<(uint32_t v) { return *this << uint64_t{v}; }
  // %.17g, as COLMAP's streams with precision(17): every double round-trips exactly.
  TextWriter& operator<<(double v) {
    char* p = out_.Ensure(32);
    out_.Advance(std::to_chars(p, p + 32, v, std::chars_format::general, 17).ptr);
    return *this;
  }
  TextWriter& operator<<(const Rigid3d& pose) {
    const auto& q = pose.rotation;
    const auto& t = pose.translation;
    return *this << q[0] << ' ' << q[1] << ' ' << q[2] << ' ' << q[3] << ' ' << t[0] << ' ' << t[1]
                 << ' ' << t[2];
  }
  TextWriter& operator<<(const SensorId& sensor) {
    return *this << (sensor.type == SensorType::kCamera ? "CAMERA" : "IMU") << ' ' << sensor.id;
  }
  void Commit() { out_.Commit(); }

 private:
  AtomicFileWriter out_;
};

void WriteCameras(const Reconstruction& rec, const fs::path& path) {
  TextWriter out(path);
  out << "# Camera list with one line of data per camera:\n"
      << "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      << "# Number of cameras: " << uint64_t{rec.cameras.size()} << '\n';
  for (const auto& [id, camera] : rec.cameras) {
    out << id << ' ' << CameraModelName(camera.model_id) << ' ' << camera.width << ' '
        << camera.height;
    for (double v : camera.params) out << ' ' << v;
    out << '\n';
  }
  out.Commit();
}

void WriteImages(const Reconstruction& rec, const fs::path& path) {
  TextWriter out(path);
  const double mean_observations =
      rec.images.empty() ? 0.0 : static_cast<double>(rec.NumObservations()) / rec.images.size();
  out << "# Image list with two lines of data per image:\n"
      << "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      << "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      << "# Number of images: " << uint64_t{rec.images.size()}
      << ", mean observations per image: " << mean_observations << '\n';
  for (const auto& [id, image] : rec.images) {
    // The name ends the line and is read back trimmed: it must not hold a line break or
    // start or end with white space.
    if (image.name.find_first_of("\n\r") != std::string::npos ||
        (!image.name.empty() && (IsSpace(image.name.front()) || IsSpace(image.name.back())))) {
      throw InputError(path.string() + ": image " + std::to_string(id) + ": name '" + image.name +
                       "' cannot be stored in a text model (line break or white "
                       "space at either end); write the binary format");
    }
    out << id << ' ' << image.cam_from_world << ' ' << image.camera_id << ' ' << image.name << '\n';
    for (size_t i = 0; i < image.points2D.size(); ++i) {
      const Point2D& point = image.points2D[i];
      if (i > 0) out << ' ';
      out << point.x << ' ' << point.y << ' ';
      if (point.point3D_id == kInvalidPoint3DId) {
        out << "-1";
      } else {
        out << point.point3D_id;
      }
    }
    out << '\n';
  }
  out.Commit();
}

void WritePoints3D(const Reconstruction& rec, const fs::path& path) {
  TextWriter out(path);
  const double mean_track_length =
      rec.points3D.empty() ? 0.0 : static_cast<double>(rec.NumObservations()) / rec.points3D.size();
  out << "# 3D point list with one line of data per point:\n"
      << "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      << "# Number of points: " << uint64_t{rec.points3D.size()}
      << ", mean track length: " << mean_track_length << '\n';
  for (const auto& [id, point] : rec.points3D) {
    out << id << ' ' << point.xyz[0] << ' ' << point.xyz[1] << ' ' << point.xyz[2] << ' '
        << uint32_t{point.color[0]} << ' ' << uint32_t{point.color[1]} << ' '
        << uint32_t{point.color[2]} << ' ' << point.error;
    // COLMAP leaves a trailing space after ERROR when the track is empty; so do we.
    if (point.track.empty()) out << ' ';
    for (const TrackElement& el : point.track) out << ' ' << el.image_id << ' ' << el.point2D_idx;
    out << '\n';
  }
  out.Commit();
}

void WriteRigs(const std::map<rig_t, Rig>& rigs, const fs::path& path) {
  TextWriter out(path);
  out << "# Rig calib list with one line of data per calib:\n"
      << "#   RIG_ID, NUM_SENSORS, REF_SENSOR_TYPE, REF_SENSOR_ID, SENSORS[] as (SENSOR_TYPE, "
         "SENSOR_ID, HAS_POSE, [QW, QX, QY, QZ, TX, TY, TZ])\n"
      << "# Number of rigs: " << uint64_t{rigs.size()} << '\n';
  for (const auto& [id, rig] : rigs) {
    const bool has_ref = rig.ref_sensor.type != SensorType::kInvalid;
    if (!has_ref && !rig.sensors.empty()) {
      throw std::invalid_argument("rig " + std::to_string(id) +
                                  " has sensors but no reference sensor");
    }
    out << id << ' ' << uint64_t{rig.sensors.size() + (has_ref ? 1 : 0)};
    if (has_ref) out << ' ' << rig.ref_sensor;
    for (const RigSensor& sensor : rig.sensors) {
      out << ' ' << sensor.sensor << ' ' << (sensor.sensor_from_rig ? '1' : '0');
      if (sensor.sensor_from_rig) out << ' ' << *sensor.sensor_from_rig;
    }
    out << '\n';
  }
  out.Commit();
}

void WriteFrames(const std::map<frame_t, Frame>& frames, const fs::path& path) {
  TextWriter out(path);
  out << "# Frame list with one line of data per frame:\n"
      << "#   FRAME_ID, RIG_ID, RIG_FROM_WORLD[QW, QX, QY, QZ, TX, TY, TZ], NUM_DATA_IDS, "
         "DATA_IDS[] as (SENSOR_TYPE, SENSOR_ID, DATA_ID)\n"
      << "# Number of frames: " << uint64_t{frames.size()} << '\n';
  for (const auto& [id, frame] : frames) {
    out << id << ' ' << frame.rig_id << ' ' << frame.rig_from_world << ' '
        << uint64_t{frame.data_ids.size()};
    for (const FrameDataId& data : frame.data_ids) out << ' ' << data.sensor << ' ' << data.data_id;
    out << '\n';
  }
  out.Commit();
}

}  // namespace

Reconstruction ReadReconstructionText(const fs::path& dir, int threads) {
  return detail::ReadModel(dir, ModelFormat::kText, threads);
}

namespace detail {

const ModelFileCodec& TextCodec() {
  static const ModelFileCodec codec{ReadCameras,  ReadRigs,     ReadFrames,  ReadImages,
                                    ReadPoints3D, WriteCameras, WriteImages, WritePoints3D,
                                    WriteRigs,    WriteFrames};
  return codec;
}

}  // namespace detail
}  // namespace cwloc::colmap
