#include "io/feature_file.h"

#include <charconv>
#include <cmath>
#include <fstream>
#include <string>
#include <string_view>

#include "base/bounded_file.h"
#include "base/error.h"

namespace cwloc {
namespace {

// Splits off the next whitespace-separated token of `line`.
std::string_view NextToken(std::string_view& line) {
  const size_t begin = line.find_first_not_of(" \t\r");
  if (begin == std::string_view::npos) {
    line = {};
    return {};
  }
  const size_t end = line.find_first_of(" \t\r", begin);
  const std::string_view token =
      line.substr(begin, end == std::string_view::npos ? line.size() - begin : end - begin);
  line.remove_prefix(end == std::string_view::npos ? line.size() : end);
  return token;
}

template <typename T>
bool ParseNumber(std::string_view token, T* value) {
  if (token.empty()) return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), *value);
  return error == std::errc() && end == token.data() + token.size();
}

}  // namespace

void ReadFeatureFile(const std::filesystem::path& path, Query* query) {
  CheckInputFile(path, kFeatureFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open feature file");
  const std::string name = path.string();
  std::string line;
  if (!std::getline(in, line))
    throw InputError(name + ": empty feature file; expected 'NUM_FEATURES 128'");
  std::string_view header = line;
  uint64_t count = 0;
  uint32_t dim = 0;
  if (!ParseNumber(NextToken(header), &count) || !ParseNumber(NextToken(header), &dim) ||
      !NextToken(header).empty()) {
    throw InputError(name + ":1: expected 'NUM_FEATURES 128'");
  }
  if (dim != 128)
    throw InputError(name + ":1: descriptors have " + std::to_string(dim) +
                     " dimensions, expected 128");
  if (count > 10'000'000)
    throw InputError(name + ":1: " + std::to_string(count) + " features is more than 10 million");
  query->keypoints.clear();
  query->descriptors.clear();
  query->keypoints.reserve(count * 2);
  query->descriptors.reserve(count * 128);
  for (uint64_t i = 0; i < count; ++i) {
    const std::string where = name + ":" + std::to_string(i + 2);
    if (!std::getline(in, line)) {
      throw InputError(where + ": file ends after " + std::to_string(i) + " of " +
                       std::to_string(count) + " features");
    }
    std::string_view rest = line;
    float values[4];
    for (float& value : values) {
      if (!ParseNumber(NextToken(rest), &value) || !std::isfinite(value)) {
        throw InputError(where + ": expected X Y SCALE ORIENTATION then 128 descriptor values");
      }
    }
    query->keypoints.push_back(values[0]);
    query->keypoints.push_back(values[1]);
    for (int d = 0; d < 128; ++d) {
      unsigned value;
      if (!ParseNumber(NextToken(rest), &value) || value > 255) {
        throw InputError(where + ": descriptor value " + std::to_string(d + 1) +
                         " is not an integer in 0..255");
      }
      query->descriptors.push_back(static_cast<uint8_t>(value));
    }
    if (!NextToken(rest).empty()) throw InputError(where + ": more than 128 descriptor values");
  }
}

}  // namespace cwloc
