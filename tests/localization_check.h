#pragma once
// What the end-to-end tests read to judge cwloc-localize: its JSON lines, ground-truth poses in
// cwloc-synth's queries_gt.txt format, the scale file, and the pose errors between them. Kept
// apart from tools/eval on purpose: the tests check the pipeline, not cwloc-eval.
#include <Eigen/Geometry>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace cwloc::test {

// COLMAP's world-to-camera pose: X_cam = rotation * X_world + translation.
struct CameraPose {
  Eigen::Quaterniond rotation = Eigen::Quaterniond::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d Center() const { return -(rotation.conjugate() * translation); }
};

struct GroundTruthQuery {
  CameraPose pose;
  std::string camera;  // "MODEL W H PARAMS...", as --camera takes it
};

// queries_gt.txt: "NAME QW QX QY QZ TX TY TZ MODEL W H PARAMS..."; '#' starts a comment line.
inline std::map<std::string, GroundTruthQuery> ReadGroundTruth(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot open");
  std::map<std::string, GroundTruthQuery> queries;
  for (std::string line; std::getline(in, line);) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    double q[4], t[3];
    if (!(fields >> name >> q[0] >> q[1] >> q[2] >> q[3] >> t[0] >> t[1] >> t[2])) {
      throw std::runtime_error(path.string() + ": bad line '" + line + "'");
    }
    GroundTruthQuery& query = queries[name];
    query.pose.rotation = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
    query.pose.translation = Eigen::Vector3d(t[0], t[1], t[2]);
    std::getline(fields >> std::ws, query.camera);
  }
  return queries;
}

// scale_to_metres.txt (X_metres = s * R * X_model + t): s, the metres per model unit.
inline double ReadMetresPerUnit(const std::filesystem::path& path) {
  std::ifstream in(path);
  for (std::string line; std::getline(in, line);) {
    std::istringstream fields(line);
    std::string key;
    double scale;
    if (fields >> key && key == "scale" && fields >> scale) return scale;
  }
  throw std::runtime_error(path.string() + ": no 'scale S' line");
}

// cam_from_rig (COLMAP's name: X_cam = R X_rig + t) of a camera on a rig whose reference
// camera is `reference`, its translation times `scale`, as a --frames line's "QW QX QY QZ TX
// TY TZ".
inline std::string CamFromRigText(const CameraPose& camera, const CameraPose& reference,
                                  double scale = 1.0) {
  const Eigen::Quaterniond q = (camera.rotation * reference.rotation.conjugate()).normalized();
  const Eigen::Vector3d t = scale * (camera.translation - q * reference.translation);
  char text[256];
  std::snprintf(text, sizeof(text), "%.17g %.17g %.17g %.17g %.17g %.17g %.17g", q.w(), q.x(),
                q.y(), q.z(), t.x(), t.y(), t.z());
  return text;
}

inline std::vector<nlohmann::json> ReadJsonLines(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<nlohmann::json> lines;
  for (std::string line; std::getline(in, line);) {
    if (!line.empty()) lines.push_back(nlohmann::json::parse(line));
  }
  return lines;
}

// The pose of a localization result (schemas/localization-result.schema.json).
inline CameraPose PoseOfResult(const nlohmann::json& result) {
  const auto& q = result.at("pose").at("qvec");
  const auto& t = result.at("pose").at("tvec");
  CameraPose pose;
  pose.rotation = Eigen::Quaterniond(q.at(0).get<double>(), q.at(1).get<double>(),
                                     q.at(2).get<double>(), q.at(3).get<double>())
                      .normalized();
  pose.translation =
      Eigen::Vector3d(t.at(0).get<double>(), t.at(1).get<double>(), t.at(2).get<double>());
  return pose;
}

struct PoseError {
  double position_m = 0;    // distance between the camera centres, in metres
  double rotation_deg = 0;  // angle of the relative rotation
};

inline PoseError ErrorOf(const CameraPose& estimate, const CameraPose& truth,
                         double metres_per_unit) {
  constexpr double kPi = 3.14159265358979323846;
  return {metres_per_unit * (estimate.Center() - truth.Center()).norm(),
          estimate.rotation.angularDistance(truth.rotation) * 180 / kPi};
}

}  // namespace cwloc::test
