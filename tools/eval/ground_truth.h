#pragma once

#include <filesystem>
#include <string>
#include <vector>

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

// Opens a text file and returns its lines without trailing '\r'; InputError if it cannot be read.
std::vector<std::string> ReadLines(const std::filesystem::path& path);

// "FILE:LINE: message" for an InputError.
std::string Where(const std::filesystem::path& path, int line);

}  // namespace cwloc::eval
