#pragma once

#include <filesystem>
#include <map>
#include <mutex>
#include <string>

#include "format/colmap/database.h"
#include "localizer/query.h"

namespace cwloc {

// Query features and intrinsics from a COLMAP database (read-only). Only the query's own
// keypoints and descriptors are read, never the database's matches. Thread-safe.
class DatabaseQueries {
 public:
  explicit DatabaseQueries(const std::filesystem::path& path);

  // The image's features and its database camera; throws InputError naming the database and
  // the image when the name or its camera is unknown. The Localizer checks what was read.
  Query Load(const std::string& name) const;

 private:
  colmap::DatabaseReader reader_;
  std::map<camera_t, colmap::Camera> cameras_;
  mutable std::mutex mutex_;
};

}  // namespace cwloc
