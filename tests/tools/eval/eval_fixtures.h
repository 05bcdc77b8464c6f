#pragma once

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numbers>
#include <string>
#include <vector>

#include "tools/eval/pose_error.h"

namespace cwloc::eval::test {

inline double Radians(double degrees) { return degrees * std::numbers::pi / 180.0; }

// A pose with rotation R and camera centre C (t = -R C).
inline Pose PoseFromCenter(const Eigen::Quaterniond& q, const Eigen::Vector3d& center) {
  Pose pose;
  pose.qvec = q.normalized();
  pose.tvec = -(pose.qvec.toRotationMatrix() * center);
  return pose;
}

// Five ground-truth queries and a run with hand-picked errors on the first four (the fifth is
// absent): position 0.1, 0.3, 1, 6 and rotation 1, 3, 8, 20 degrees.
struct Scenario {
  std::vector<std::string> names = {"q0.jpg", "q1.jpg", "q2.jpg", "q3.jpg", "q4.jpg"};
  std::vector<Pose> truth;
  std::vector<Pose> estimates;  // first four queries
  std::vector<double> position_errors = {0.1, 0.3, 1.0, 6.0};
  std::vector<double> rotation_errors = {1.0, 3.0, 8.0, 20.0};
  std::vector<double> total_ms = {10, 20, 30, 40};

  Scenario() {
    for (int i = 0; i < 5; ++i) {
      const Eigen::Quaterniond q(
          Eigen::AngleAxisd(0.3 * i + 0.1, Eigen::Vector3d(1, 2, 3 - i).normalized()));
      truth.push_back(PoseFromCenter(q, Eigen::Vector3d(i, -2.0 * i, 0.5 + i)));
    }
    for (int i = 0; i < 4; ++i) {
      const Eigen::Quaterniond delta(
          Eigen::AngleAxisd(Radians(rotation_errors[i]), Eigen::Vector3d(0, 1, 1).normalized()));
      const Eigen::Vector3d offset = position_errors[i] * Eigen::Vector3d(2, -1, 2).normalized();
      estimates.push_back(PoseFromCenter(delta * truth[i].qvec, truth[i].Center() + offset));
    }
  }

  static std::string PoseLine(const std::string& name, const Pose& p) {
    char buffer[512];
    std::snprintf(buffer, sizeof(buffer), "%s %.17g %.17g %.17g %.17g %.17g %.17g %.17g",
                  name.c_str(), p.qvec.w(), p.qvec.x(), p.qvec.y(), p.qvec.z(), p.tvec.x(),
                  p.tvec.y(), p.tvec.z());
    return buffer;
  }

  void WriteGroundTruth(const std::filesystem::path& path) const {
    std::ofstream out(path);
    out << "# NAME QW QX QY QZ TX TY TZ CAMERA_MODEL WIDTH HEIGHT PARAMS...\n";
    for (size_t i = 0; i < truth.size(); ++i)
      out << PoseLine(names[i], truth[i]) << " SIMPLE_PINHOLE 640 480 500 320 240\n";
  }

  void WritePoses(const std::filesystem::path& path) const {
    std::ofstream out(path);
    for (size_t i = 0; i < estimates.size(); ++i) out << PoseLine(names[i], estimates[i]) << "\n";
  }

  static nlohmann::json JsonRecord(const std::string& name, const Pose& p, double total_ms) {
    const Eigen::Vector3d c = p.Center();
    nlohmann::json times = {{"forward_knn", 1.0},   {"ratio_test", 0.5}, {"query_tree", 2.0},
                            {"back_matching", 3.0}, {"pose", 4.0},       {"total", total_ms}};
    return {{"name", name},
            {"success", true},
            {"pose",
             {{"qvec", {p.qvec.w(), p.qvec.x(), p.qvec.y(), p.qvec.z()}},
              {"tvec", {p.tvec.x(), p.tvec.y(), p.tvec.z()}},
              {"center", {c.x(), c.y(), c.z()}}}},
            {"num_inliers", 100},
            {"ranked_images",
             nlohmann::json::array({{{"image_id", 1}, {"name", "db.jpg"}, {"votes", 7}}})},
            {"times_ms", times}};
  }

  void WriteJsonLines(const std::filesystem::path& path) const {
    std::ofstream out(path);
    for (size_t i = 0; i < estimates.size(); ++i)
      out << JsonRecord(names[i], estimates[i], total_ms[i]).dump() << "\n";
  }
};

}  // namespace cwloc::eval::test
