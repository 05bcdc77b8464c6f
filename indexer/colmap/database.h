#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "indexer/colmap/reconstruction.h"

struct sqlite3;

namespace cwloc::colmap {

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

// Reads a COLMAP database.db (COLMAP 3.6 to 3.12 schemas) strictly read-only: the file is
// opened with SQLITE_OPEN_READONLY and never modified. The schema and every blob size are
// checked; a mismatch throws InputError naming the file, the table, the image and the size
// expected.
class DatabaseReader {
 public:
  explicit DatabaseReader(const std::filesystem::path& path);
  ~DatabaseReader();
  DatabaseReader(const DatabaseReader&) = delete;
  DatabaseReader& operator=(const DatabaseReader&) = delete;

  const std::filesystem::path& path() const { return path_; }

  std::vector<Camera> ReadAllCameras() const;
  std::vector<DatabaseImage> ReadAllImages() const;
  std::optional<DatabaseImage> FindImage(const std::string& name) const;
  std::vector<Keypoint> ReadKeypoints(image_t image_id) const;    // empty when the image has none
  Descriptors ReadDescriptors(image_t image_id) const;             // rows == 0 when none

 private:
  std::filesystem::path path_;
  sqlite3* db_ = nullptr;
};

// Creates a new database in COLMAP 3.8's schema (the one Debian's colmap reads and
// upgrades). Writes go into one transaction committed by Commit(); the file is built under
// a temporary name and renamed into place, so a failure never leaves a partial database.
class DatabaseWriter {
 public:
  explicit DatabaseWriter(const std::filesystem::path& path);  // replaces an existing file on Commit
  ~DatabaseWriter();  // without Commit(), removes the temporary file
  DatabaseWriter(const DatabaseWriter&) = delete;
  DatabaseWriter& operator=(const DatabaseWriter&) = delete;

  void WriteCamera(const Camera& camera);  // keeps camera.camera_id
  void WriteImage(const DatabaseImage& image);  // keeps image.image_id
  // Keypoints are stored with 6 columns (x, y, a11, a12, a21, a22) as COLMAP >= 3.x does.
  void WriteKeypoints(image_t image_id, const std::vector<Keypoint>& keypoints);
  void WriteDescriptors(image_t image_id, const Descriptors& descriptors);
  void Commit();

 private:
  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  sqlite3* db_ = nullptr;
  bool committed_ = false;
};

}  // namespace cwloc::colmap
