#pragma once

#include <filesystem>

#include "localizer/query.h"

namespace cwloc {

// Reads COLMAP's text feature format into query.keypoints / query.descriptors:
//   NUM_FEATURES 128
//   X Y SCALE ORIENTATION D_1 ... D_128      (one line per feature, D_i integers 0..255)
// Throws InputError naming the file, the line and the problem; a file that is not a regular one
// or is over kFeatureFile's limit (base/bounded_file.h) is refused before it is read.
void ReadFeatureFile(const std::filesystem::path& path, Query* query);

}  // namespace cwloc
