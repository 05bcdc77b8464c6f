#include "tools/eval/recognition.h"

#include <fstream>
#include <sstream>
#include <unordered_map>

#include "base/bounded_file.h"
#include "base/error.h"
#include "colmap/reconstruction_io.h"

namespace cwloc::eval {

std::map<std::string, std::vector<uint64_t>> ReadQueryPoints(const std::filesystem::path& path) {
  CheckInputFile(path, kEvalInputFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open query points file");
  std::map<std::string, std::vector<uint64_t>> points;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    std::istringstream fields(line);
    std::string name;
    if (!(fields >> name) || name[0] == '#') continue;
    std::vector<uint64_t>& ids = points[name];
    std::string token;
    while (fields >> token) {
      size_t used = 0;
      unsigned long long id = 0;
      try {
        id = std::stoull(token, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != token.size() || token[0] == '-') {
        throw InputError(path.string() + ":" + std::to_string(number) +
                         ": expected NAME POINT3D_ID..., got '" + token + "'");
      }
      ids.push_back(id);
    }
  }
  return points;
}

std::map<std::string, std::vector<uint64_t>> QueryPointsFromModel(
    const std::filesystem::path& model_dir, const std::vector<std::string>& names) {
  const colmap::Reconstruction model = colmap::ReadReconstruction(model_dir);
  std::unordered_map<std::string, const colmap::Image*> by_name;
  for (const auto& [id, image] : model.images) by_name[image.name] = &image;
  std::map<std::string, std::vector<uint64_t>> points;
  for (const std::string& name : names) {
    std::vector<uint64_t>& ids = points[name];
    const auto it = by_name.find(name);
    if (it == by_name.end()) continue;
    for (const colmap::Point2D& point : it->second->points2D) {
      if (point.point3D_id != kInvalidPoint3DId) ids.push_back(point.point3D_id);
    }
  }
  return points;
}

RecognitionTruth MakeRecognitionTruth(
    const std::filesystem::path& mapping_model_dir,
    const std::map<std::string, std::vector<uint64_t>>& query_points, int min_shared) {
  const colmap::Reconstruction model = colmap::ReadReconstruction(mapping_model_dir);
  RecognitionTruth truth;
  truth.min_shared = min_shared;
  for (const auto& [name, ids] : query_points) {
    std::map<uint32_t, std::set<uint64_t>> shared;  // model image -> query points it sees
    for (const uint64_t id : ids) {
      const auto point = model.points3D.find(id);
      if (point == model.points3D.end()) continue;  // not in the mapping model
      for (const colmap::TrackElement& element : point->second.track)
        shared[element.image_id].insert(id);
    }
    std::set<uint32_t>& right = truth.right_images[name];
    for (const auto& [image_id, points] : shared) {
      if (static_cast<int>(points.size()) >= min_shared) right.insert(image_id);
    }
  }
  return truth;
}

RecognitionScores ScoreRecognition(const RunResults& run,
                                   const std::vector<std::string>& query_names,
                                   const RecognitionTruth& truth) {
  std::unordered_map<std::string, const QueryResult*> results;
  for (const QueryResult& result : run.queries) results[result.name] = &result;
  RecognitionScores scores;
  for (const std::string& name : query_names) {
    ++scores.queries;
    const auto right = truth.right_images.find(name);
    if (right == truth.right_images.end() || right->second.empty()) continue;
    ++scores.with_right_image;
    const auto result = results.find(name);
    if (result == results.end()) continue;
    const std::vector<uint32_t>& ranked = result->second->ranked_image_ids;
    for (size_t r = 0; r < kRecognitionRanks.size(); ++r) {
      const size_t top = std::min<size_t>(kRecognitionRanks[r], ranked.size());
      for (size_t i = 0; i < top; ++i) {
        if (right->second.count(ranked[i]) > 0) {
          ++scores.hits[r];
          break;
        }
      }
    }
  }
  return scores;
}

}  // namespace cwloc::eval
