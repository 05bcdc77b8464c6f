#include "app/feature_file.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
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
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open feature file");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw InputError(path.string() + ": cannot read feature file");
  ParseFeatureText(text, path.string(), query);
}

void ParseFeatureText(std::string_view text, const std::string& name, Query* query) {
  size_t line_number = 0;
  // The next line, without its newline; false at the end of the text.
  const auto next_line = [&](std::string_view* line) {
    if (text.empty()) return false;
    const size_t end = text.find('\n');
    *line = text.substr(0, end);
    text.remove_prefix(end == std::string_view::npos ? text.size() : end + 1);
    ++line_number;
    return true;
  };
  std::string_view line;
  if (!next_line(&line))
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
  // A feature's line has at least 264 characters: reserve no more than the text can hold.
  const uint64_t room = std::min<uint64_t>(count, text.size() / 264 + 1);
  query->keypoints.reserve(room * 2);
  query->descriptors.reserve(room * 128);
  for (uint64_t i = 0; i < count; ++i) {
    const std::string where = name + ":" + std::to_string(i + 2);
    if (!next_line(&line)) {
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

void ParseFeatureBinary(std::span<const uint8_t> bytes, const std::string& source, Query* query) {
  constexpr size_t kHeader = 12;
  if (bytes.size() < kHeader || std::memcmp(bytes.data(), kFeatureBinaryMagic, 4) != 0)
    throw InputError(source + ": not binary features (they start with 'CWLF')");
  const auto u32 = [&](size_t at) {
    return uint32_t{bytes[at]} | uint32_t{bytes[at + 1]} << 8 | uint32_t{bytes[at + 2]} << 16 |
           uint32_t{bytes[at + 3]} << 24;
  };
  if (u32(4) != 1)
    throw InputError(source + ": binary features of version " + std::to_string(u32(4)) +
                     ", expected 1");
  const uint64_t count = u32(8);
  const uint64_t expected = kHeader + count * (2 * sizeof(float) + 128);
  if (bytes.size() != expected) {
    throw InputError(source + ": " + std::to_string(count) + " binary features take " +
                     std::to_string(expected) + " bytes, got " + std::to_string(bytes.size()));
  }
  query->keypoints.resize(count * 2);
  for (uint64_t i = 0; i < count * 2; ++i) {
    const uint32_t bits = u32(kHeader + i * 4);
    float value;
    std::memcpy(&value, &bits, sizeof(value));
    if (!std::isfinite(value))
      throw InputError(source + ": feature " + std::to_string(i / 2) + " has a non-finite pixel");
    query->keypoints[i] = value;
  }
  const uint8_t* descriptors = bytes.data() + kHeader + count * 2 * sizeof(float);
  query->descriptors.assign(descriptors, descriptors + count * 128);
}

}  // namespace cwloc
