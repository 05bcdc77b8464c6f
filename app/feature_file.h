#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "localizer/query.h"

namespace cwloc {

// Reads COLMAP's text feature format into query.keypoints / query.descriptors:
//   NUM_FEATURES 128
//   X Y SCALE ORIENTATION D_1 ... D_128      (one line per feature, D_i integers 0..255)
// Throws InputError naming the file, the line and the problem; a file that is not a regular one
// or is over kFeatureFile's limit (base/bounded_file.h) is refused before it is read.
void ReadFeatureFile(const std::filesystem::path& path, Query* query);

// The same text in memory (a request's body); `source` names it in errors.
void ParseFeatureText(std::string_view text, const std::string& source, Query* query);

// The binary layout for clients that extract on the device (docs/serve.md), little-endian:
// the 4 bytes "CWLF", uint32 version 1, uint32 N, N x (float32 X, float32 Y) in COLMAP's
// pixel convention, then N x 128 uint8 descriptors. Throws InputError naming `source`.
inline constexpr char kFeatureBinaryMagic[4] = {'C', 'W', 'L', 'F'};
void ParseFeatureBinary(std::span<const uint8_t> bytes, const std::string& source, Query* query);

}  // namespace cwloc
