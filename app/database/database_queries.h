#pragma once

#include <filesystem>
#include <map>
#include <mutex>
#include <string>

#include "colmap/database.h"
#include "localizer/query.h"

namespace cwloc {

// Query features and intrinsics from a COLMAP database (read-only). Only the query's own
// keypoints and descriptors are read, never the database's matches. Thread-safe.
//
// The database camera is what COLMAP's feature extractor wrote, never a refined calibration;
// its prior_focal_length flag (COLMAP <= 3.9) sets the query's calibration as COLMAP's
// registrator reads it:
//   0 -> Calibration::kUnknown: the focal length is the extractor's guess 1.2 * max(w, h);
//   1 -> Calibration::kFocalPrior: a prior (EXIF, or given to the extractor) that COLMAP still
//        refines with the distortion for a camera no registered image has refined;
//   no such column (newer schemas) -> Calibration::kFocalPrior as well.
class DatabaseQueries {
 public:
  explicit DatabaseQueries(const std::filesystem::path& path);

  // The image's features and its database camera; throws InputError naming the database and
  // the image when the name or its camera is unknown. The Localizer checks what was read.
  Query Load(const std::string& name) const;

 private:
  colmap::DatabaseReader reader_;
  std::map<camera_t, colmap::Camera> cameras_;
  std::map<camera_t, bool> prior_focal_lengths_;  // empty without the column
  mutable std::mutex mutex_;
};

}  // namespace cwloc
