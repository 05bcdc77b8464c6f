#include "tools/eval/ground_truth.h"

#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <unordered_map>

#include "base/bounded_file.h"
#include "base/error.h"

namespace cwloc::eval {
namespace {

bool ParseDouble(const std::string& token, double* value) {
  const char* end = token.data() + token.size();
  const auto [ptr, ec] = std::from_chars(token.data(), end, *value);
  return ec == std::errc() && ptr == end && std::isfinite(*value);
}

std::string Trim(const std::string& s) {
  const size_t begin = s.find_first_not_of(" \t");
  if (begin == std::string::npos) return "";
  return s.substr(begin, s.find_last_not_of(" \t") - begin + 1);
}

}  // namespace

std::string Where(const std::filesystem::path& path, int line) {
  return path.string() + ":" + std::to_string(line) + ": ";
}

std::vector<std::string> ReadLines(const std::filesystem::path& path) {
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec))
    throw InputError(path.string() + ": is a directory, expected a file");
  CheckInputFile(path, kEvalInputFile);
  std::ifstream file(path);
  if (!file) throw InputError(path.string() + ": cannot open (" + std::strerror(errno) + ")");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(file, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    lines.push_back(std::move(line));
  }
  if (file.bad()) throw InputError(path.string() + ": read error");
  return lines;
}

std::vector<NamedPose> ReadPosesFile(const std::filesystem::path& path) {
  const std::vector<std::string> lines = ReadLines(path);
  std::vector<NamedPose> poses;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const int line_number = int(i) + 1;
    std::istringstream tokens(line);
    NamedPose entry;
    entry.line = line_number;
    double v[7];
    bool ok = bool(tokens >> entry.name);
    for (int k = 0; k < 7 && ok; ++k) {
      std::string token;
      ok = (tokens >> token) && ParseDouble(token, &v[k]);
    }
    if (!ok) throw InputError(Where(path, line_number) + "expected NAME QW QX QY QZ TX TY TZ");
    const Eigen::Quaterniond q(v[0], v[1], v[2], v[3]);
    if (q.norm() < 1e-12)
      throw InputError(Where(path, line_number) + "quaternion QW QX QY QZ is zero");
    entry.pose.qvec = q.normalized();
    entry.pose.tvec = Eigen::Vector3d(v[4], v[5], v[6]);
    poses.push_back(std::move(entry));
  }
  return poses;
}

std::vector<NamedPose> ReadGroundTruth(const std::filesystem::path& path) {
  std::vector<NamedPose> poses = ReadPosesFile(path);
  if (poses.empty())
    throw InputError(path.string() +
                     ": no ground-truth queries (expected NAME QW QX QY QZ TX TY TZ lines)");
  std::unordered_map<std::string, int> first_line;
  for (const NamedPose& p : poses) {
    const auto [it, inserted] = first_line.emplace(p.name, p.line);
    if (!inserted) {
      throw InputError(Where(path, p.line) + "duplicate query " + p.name + " (first on line " +
                       std::to_string(it->second) + ")");
    }
  }
  return poses;
}

std::vector<NamedGeodetic> ReadGeoGroundTruth(const std::filesystem::path& path) {
  static constexpr const char* kFields[] = {"LAT", "LON", "HEIGHT"};
  const std::vector<std::string> lines = ReadLines(path);
  std::vector<NamedGeodetic> positions;
  std::unordered_map<std::string, int> first_line;
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string line = Trim(lines[i]);
    if (line.empty() || line[0] == '#') continue;
    const int line_number = int(i) + 1;
    std::istringstream stream(line);
    std::vector<std::string> tokens;
    for (std::string token; stream >> token;) tokens.push_back(std::move(token));
    if (tokens.size() != 4) {
      throw InputError(Where(path, line_number) + "expected NAME LAT LON HEIGHT, got " +
                       std::to_string(tokens.size()) + " value(s)");
    }
    double v[3];
    for (int k = 0; k < 3; ++k) {
      if (!ParseDouble(tokens[k + 1], &v[k])) {
        throw InputError(Where(path, line_number) + kFields[k] + " '" + tokens[k + 1] +
                         "' is not a finite number");
      }
    }
    NamedGeodetic entry{tokens[0], {v[0], v[1], v[2]}, line_number};
    // "FILE:LINE: latitude 91 is outside [-90, 90]"
    ValidateGeodetic(entry.position, path.string() + ":" + std::to_string(line_number));
    const auto [it, inserted] = first_line.emplace(entry.name, line_number);
    if (!inserted) {
      throw InputError(Where(path, line_number) + "duplicate query " + entry.name +
                       " (first on line " + std::to_string(it->second) + ")");
    }
    positions.push_back(std::move(entry));
  }
  if (positions.empty())
    throw InputError(path.string() + ": no positions (expected NAME LAT LON HEIGHT lines)");
  return positions;
}

std::unordered_map<std::string, Geodetic> TruePositionsOfQueries(
    const std::vector<NamedPose>& ground_truth, const std::vector<NamedGeodetic>& positions,
    const std::filesystem::path& path) {
  std::unordered_map<std::string, Geodetic> by_name;
  for (const NamedGeodetic& p : positions) by_name.emplace(p.name, p.position);
  for (const NamedPose& query : ground_truth) {
    if (!by_name.contains(query.name)) {
      throw InputError(path.string() + ": no position for ground-truth query " + query.name +
                       " (line " + std::to_string(query.line) + " of the --gt file)");
    }
  }
  return by_name;
}

double ReadScale(const std::filesystem::path& path) {
  const std::vector<std::string> lines = ReadLines(path);
  for (size_t i = 0; i < lines.size(); ++i) {
    std::istringstream tokens(Trim(lines[i]));
    std::string key, value, extra;
    if (!(tokens >> key) || key != "scale") continue;
    double scale = 0;
    if (!(tokens >> value) || !ParseDouble(value, &scale) || scale <= 0 || (tokens >> extra)) {
      throw InputError(Where(path, int(i) + 1) + "expected 'scale S' with a number S > 0");
    }
    return scale;
  }
  throw InputError(path.string() + ": no 'scale S' line");
}

}  // namespace cwloc::eval
