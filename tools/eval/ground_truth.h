#pragma once

#include <filesystem>
#include <string>
#include <unordered_map>
#include <vector>

#include "geo/georeference.h"
#include "tools/eval/pose_error.h"

namespace cwloc::eval {

// One line of a pose text file: NAME QW QX QY QZ TX TY TZ [anything else].
struct NamedPose {
  std::string name;
  Pose pose;
  int line = 0;  // 1-based line in its file, for messages
};

// Reads a pose text file (queries_gt.txt, or a localizer's poses output). '#' lines and blank
// lines are skipped; tokens after TZ (COLMAP camera, in queries_gt.txt) are ignored.
// Throws InputError "FILE:LINE: expected NAME QW QX QY QZ TX TY TZ" on a malformed line.
std::vector<NamedPose> ReadPosesFile(const std::filesystem::path& path);

// ReadPosesFile plus the checks ground truth needs: at least one query, no duplicate names.
std::vector<NamedPose> ReadGroundTruth(const std::filesystem::path& path);

// Reads the "scale S" line of scale_to_metres.txt (model units -> metres); other lines
// (R, t of the similarity) do not change distances and are ignored.
double ReadScale(const std::filesystem::path& path);

// One line of a --gt-geo file (cwloc-synth's queries_geo.txt): NAME LAT LON HEIGHT, a query's
// true camera centre in WGS84 degrees and metres above the ellipsoid.
struct NamedGeodetic {
  std::string name;
  Geodetic position;
  int line = 0;
};

// Reads a --gt-geo file. '#' lines and blank lines are skipped. Throws InputError naming the
// file and line for a line without exactly four values, a value that is not a finite number, a
// latitude outside [-90, 90] or longitude outside [-180, 360), a duplicate name, and for a file
// without positions.
std::vector<NamedGeodetic> ReadGeoGroundTruth(const std::filesystem::path& path);

// The true positions by name; throws InputError naming `path` when a ground-truth query has none
// (the two files describe different queries).
std::unordered_map<std::string, Geodetic> TruePositionsOfQueries(
    const std::vector<NamedPose>& ground_truth, const std::vector<NamedGeodetic>& positions,
    const std::filesystem::path& path);

// Opens a text file and returns its lines without trailing '\r'; InputError if it cannot be read.
std::vector<std::string> ReadLines(const std::filesystem::path& path);

// "FILE:LINE: message" for an InputError.
std::string Where(const std::filesystem::path& path, int line);

}  // namespace cwloc::eval
