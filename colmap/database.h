#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "base/atomic_file.h"
#include "colmap/reconstruction.h"

struct sqlite3;
struct sqlite3_stmt;

namespace cwloc::colmap {
namespace internal {
struct MatrixRow;
struct MatrixTable;
}  // namespace internal

// COLMAP's FeatureKeypoint: position plus the affine shape. Rows with 2 columns (x, y) get an
// identity shape, rows with 4 (x, y, scale, orientation) get the similarity COLMAP derives.
struct Keypoint {
  float x = 0, y = 0;
  float a11 = 1, a12 = 0, a21 = 0, a22 = 1;
  float Scale() const;
  float Orientation() const;
  bool operator==(const Keypoint&) const = default;
};

struct DatabaseImage {
  image_t image_id = 0;
  std::string name;
  camera_t camera_id = 0;
  bool operator==(const DatabaseImage&) const = default;
};

inline constexpr int kDescriptorDim = 128;

// N x 128 uint8 SIFT descriptors, row-major (COLMAP's FeatureDescriptors).
struct Descriptors {
  uint32_t rows = 0;
  std::vector<uint8_t> data;
  const uint8_t* Row(uint32_t i) const { return data.data() + size_t{i} * kDescriptorDim; }
};

// x0, y0, x1, y1, ...: the keypoints' positions as a query holds them.
std::vector<float> KeypointPositions(const std::vector<Keypoint>& keypoints);

// Keypoints and descriptors of one image; ReadFeatures checks that they have the same rows.
struct ImageFeatures {
  std::vector<Keypoint> keypoints;
  Descriptors descriptors;
};

// Reads a COLMAP database.db (COLMAP 3.6 to 4.x schemas) strictly read-only: the file is
// opened with SQLITE_OPEN_READONLY and never modified, and no -wal/-shm/-journal file is
// created. The schema and every blob size are checked; a mismatch throws InputError naming
// the file, the table, the image and the size expected. Only SIFT descriptors (N x 128
// uint8) are accepted. Not thread-safe (prepared statements are reused): use one reader
// per thread. Do not run colmap on the same database while reading it. A path that is not a
// regular file (a device, a pipe) is refused before SQLite opens it (kColmapDatabaseFile).
class DatabaseReader {
 public:
  explicit DatabaseReader(const std::filesystem::path& path);
  ~DatabaseReader();
  DatabaseReader(const DatabaseReader&) = delete;
  DatabaseReader& operator=(const DatabaseReader&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // PRAGMA user_version: 3800 for COLMAP 3.8, 3900 for 3.9 to 3.13, 4xx0000 for 4.x.
  int user_version() const { return user_version_; }
  // The newer schema (COLMAP >= 4.0) tags descriptors with their extractor type.
  bool has_descriptor_type() const { return has_descriptor_type_; }

  std::vector<Camera> ReadAllCameras() const;  // ordered by camera_id
  // COLMAP <= 3.9 flags each camera with prior_focal_length: 1 when its focal length is a
  // prior (from EXIF; COLMAP's mapper still refines it), 0 when it is the feature extractor's
  // guess 1.2 * max(width, height). Newer schemas may have no such column.
  bool has_prior_focal_length() const { return has_prior_focal_length_; }
  // camera_id -> prior_focal_length != 0 (as COLMAP reads it) for every camera; empty without
  // the column. A non-integer value throws InputError.
  std::map<camera_t, bool> ReadPriorFocalLengths() const;
  std::vector<DatabaseImage> ReadAllImages() const;  // ordered by image_id
  std::optional<DatabaseImage> FindImage(const std::string& name) const;
  std::vector<Keypoint> ReadKeypoints(image_t image_id) const;  // empty when the image has none
  Descriptors ReadDescriptors(image_t image_id) const;          // rows == 0 when none
  // Both of the above; throws when the row counts differ.
  ImageFeatures ReadFeatures(image_t image_id) const;
  // Row counts without reading the blobs (the blob sizes are still checked); 0 when none.
  uint32_t NumKeypoints(image_t image_id) const;
  uint32_t NumDescriptors(image_t image_id) const;

 private:
  struct Statements;
  // The constructor's stages once the connection is open; `file` names the database.
  // PRAGMA query_only, the read transaction of the reader's life, and user_version_.
  void BeginReading(const std::string& file);
  // COLMAP's tables and columns are there; sets has_descriptor_type_, has_prior_focal_length_.
  void CheckTables(const std::string& file);
  void PrepareStatements(const std::string& file);
  std::string ImageLabel(image_t image_id) const;  // "image 3 'a.jpg'" for messages
  // Steps `stmt`, a query of `table` for one image, and reads and checks the matrix row it
  // returns (only its size with `sizes_only`); false when the image has no row.
  bool ReadMatrixRow(sqlite3_stmt* stmt, image_t image_id, const internal::MatrixTable& table,
                     bool sizes_only, internal::MatrixRow* row) const;

  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
  std::unique_ptr<Statements> stmts_;
  int user_version_ = 0;
  bool has_descriptor_type_ = false;
  bool has_prior_focal_length_ = false;
};

// Creates a new database in COLMAP 3.8's schema (the one Debian's colmap reads and
// upgrades), with user_version 3800. Writes go into one transaction committed by Commit();
// SQLite builds the file at an AtomicFile's temporary path, which Commit() renames into
// place, so a failure never leaves a partial database. Cameras are written with
// prior_focal_length = 0. Bad arguments throw std::invalid_argument, SQLite failures
// std::runtime_error, file-system failures InputError (one too), all naming the file.
class DatabaseWriter {
 public:
  // Replaces an existing file (and its stale -journal/-wal/-shm) on Commit().
  explicit DatabaseWriter(const std::filesystem::path& path);
  ~DatabaseWriter();  // without Commit(), removes the temporary file
  DatabaseWriter(const DatabaseWriter&) = delete;
  DatabaseWriter& operator=(const DatabaseWriter&) = delete;

  void WriteCamera(const Camera& camera);       // keeps camera.camera_id
  void WriteImage(const DatabaseImage& image);  // keeps image.image_id
  // Keypoints are stored with 6 columns (x, y, a11, a12, a21, a22) as COLMAP >= 3.x does.
  void WriteKeypoints(image_t image_id, const std::vector<Keypoint>& keypoints);
  void WriteDescriptors(image_t image_id, const Descriptors& descriptors);
  // Commits, closes, fsyncs and renames into place. The writer cannot be used afterwards.
  void Commit();

  const std::filesystem::path& path() const { return file_.path(); }

 private:
  struct Statements;
  void Close() noexcept;

  AtomicFile file_;  // created before SQLite opens its temp_path()
  sqlite3* db_ = nullptr;
  std::unique_ptr<Statements> stmts_;
};

}  // namespace cwloc::colmap
