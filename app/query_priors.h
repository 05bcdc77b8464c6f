#pragma once

// A query's priors as the CLI and the API take them (docs/cli.md, docs/geo.md):
// --prior-position "LAT LON [HEIGHT] RADIUS_M", --prior-gravity "GX GY GZ", a --priors file,
// and the photo's EXIF GPS.

#include <array>
#include <filesystem>
#include <optional>
#include <string>
#include <unordered_map>

#include "localizer/query.h"

namespace cwloc {

// "LAT LON [HEIGHT] RADIUS_M"; throws InputError naming `what` and the problem.
PositionPrior ParsePositionPrior(const std::string& text, const std::string& what);

// "GX GY GZ": the direction gravity pulls in the camera frame; any non-zero length.
std::array<double, 3> ParseGravityPrior(const std::string& text, const std::string& what);

struct QueryPriors {
  std::optional<PositionPrior> position;
  std::optional<std::array<double, 3>> gravity;
};

// A priors file: per line `NAME position LAT LON HEIGHT RADIUS_M` (HEIGHT '-' when unknown)
// or `NAME gravity GX GY GZ`; '#' comments and blank lines skipped. Keyed by query name.
// Throws InputError naming the file, the line and the problem; a file that is not a regular one
// or is over kPriorsFile's limit (base/bounded_file.h) is refused before it is read.
std::unordered_map<std::string, QueryPriors> ReadPriorsFile(const std::filesystem::path& path);

// --exif-gps-radius: a phone's fix in a street canyon is often 10-30 m off.
inline constexpr double kDefaultExifGpsRadiusM = 50.0;

// The photo's EXIF GPS as a horizontal position prior of radius_m; nullopt without a fix.
std::optional<PositionPrior> ExifPositionPrior(const Query& query, double radius_m);

}  // namespace cwloc
