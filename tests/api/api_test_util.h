#pragma once
// What the API tests share: the golden index in tests/data and error expectations.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "cwloc/cwloc.h"
#include "cwloc/cwloc.hpp"
#include "tests/test_util.h"

namespace cwloc {

inline std::filesystem::path GoldenIndex() { return test::GoldenDir() / "index-1.0.cwl"; }
inline std::filesystem::path QueryDir() { return test::GoldenDir() / "index-1.0-queries"; }
// The same city on the globe (format 1.1, tests/data/README.md): results have geo poses.
inline std::filesystem::path GeoIndex() { return test::GoldenDir() / "index-1.1.cwl"; }
inline std::filesystem::path GeoQueryDir() { return test::GoldenDir() / "index-1.1-queries"; }

// "MODEL W H P1 P2 ..." as the ground-truth file writes it.
inline api::Camera ParseCamera(const std::string& spec) {
  std::istringstream in(spec);
  api::Camera camera;
  in >> camera.model >> camera.width >> camera.height;
  for (double p; in >> p;) camera.params.push_back(p);
  return camera;
}

// Features in COLMAP's text format from `dir`: NAME.txt.
inline api::Features ReadQueryFeatures(const std::filesystem::path& dir, const std::string& name) {
  return api::ReadFeatureFile((dir / (name + ".txt")).string());
}

// Checks that fn throws api::Error with this code and message.
template <typename Fn>
void ExpectError(Fn fn, api::ErrorCode code, const std::string& message) {
  try {
    fn();
    ADD_FAILURE() << "no error; expected: " << message;
  } catch (const api::Error& e) {
    EXPECT_EQ(e.code(), code) << e.what();
    EXPECT_EQ(std::string(e.what()), message);
  }
}

// A C result's fields by path (cwloc_result_value and its siblings); each fails the test when
// the path names no such value.
inline double CValue(const cwloc_result* result, const char* path) {
  double value = -1;
  EXPECT_EQ(cwloc_result_value(result, path, &value), CWLOC_OK)
      << path << ": " << cwloc_last_error();
  return value;
}
inline std::string CText(const cwloc_result* result, const char* path) {
  const char* text = nullptr;
  EXPECT_EQ(cwloc_result_text(result, path, &text), CWLOC_OK) << path << ": " << cwloc_last_error();
  return text != nullptr ? text : "(null)";
}
inline std::vector<double> CValues(const cwloc_result* result, const char* path) {
  size_t count = 0;
  EXPECT_EQ(cwloc_result_values(result, path, nullptr, 0, &count), CWLOC_OK)
      << path << ": " << cwloc_last_error();
  std::vector<double> values(count);
  EXPECT_EQ(cwloc_result_values(result, path, values.data(), values.size(), &count), CWLOC_OK);
  return values;
}
inline size_t CSize(const cwloc_result* result, const char* path) {
  size_t size = 0;
  EXPECT_EQ(cwloc_result_size(result, path, &size), CWLOC_OK) << path << ": " << cwloc_last_error();
  return size;
}
// The same numbers as a list of doubles, to compare with a C field.
template <typename T>
std::vector<double> Doubles(const T& values) {
  return std::vector<double>(values.begin(), values.end());
}

}  // namespace cwloc
