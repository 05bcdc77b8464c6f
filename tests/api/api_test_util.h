#pragma once
// What the API tests share: the golden index in tests/data and error expectations.
#include <gtest/gtest.h>

#include <filesystem>
#include <sstream>
#include <string>

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

}  // namespace cwloc
