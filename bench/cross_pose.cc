// cwloc-cross-pose: which of matching and estimation makes cwloc's pose differ from COLMAP's
// (issue #41; bench/cross_estimation.sh runs it). For each query it fits cwloc's pose stage
// (RANSAC, P3P or P4Pf, refinement: EstimateQueryPose, as Localize runs it) to two sets of
// 2D-3D correspondences:
//   cwloc:  those cwloc's matcher gave the pose (Localize's correspondences), and
//   colmap: those COLMAP's image_registrator used, read from its registered model (the query's
//           2D points with a point3D id), each 3D point taken as one of the index's views of it
//           (found through its track in the mapping model and the view's keypoint);
// and writes cwloc's correspondences as COLMAP sees them (query feature, mapping image id,
// point2D index in that image), for COLMAP's estimator to fit the other way round.
//
//   cwloc-cross-pose --index I --database DB --query-list Q --mapping-model sparse/0
//       --colmap-model registered/ -o poses.jsonl --pairs cwloc_pairs.txt
// poses.jsonl: one line per query, {"name", "cwloc": FIT, "colmap": FIT, "colmap_pairs",
// "colmap_pairs_mapped"}, FIT = {"success", "qvec", "tvec", "center", "focal", "k",
// "inliers", "correspondences"} (qvec, tvec: COLMAP's cam_from_world). cwloc_pairs.txt: lines
// `QUERY FEATURE IMAGE_ID POINT2D_IDX`.
#include <CLI/CLI.hpp>
#include <cmath>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

#include "app/database/database_queries.h"
#include "base/error.h"
#include "colmap/reconstruction_io.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "localizer/localizer.h"
#include "localizer/query_pose.h"

namespace cwloc {
namespace {

// A keypoint's place in its image, to find a view by the keypoint the index stored for it.
using KeypointKey = std::tuple<uint32_t, float, float>;  // image id, x, y

nlohmann::json FitJson(const QueryPose& fit, size_t correspondences) {
  const AbsolutePoseResult& pose = fit.pose;
  nlohmann::json out = {{"success", pose.success},
                        {"inliers", pose.num_inliers},
                        {"correspondences", correspondences}};
  if (!pose.success) return out;
  const Eigen::Quaterniond& q = pose.pose.rotation;
  const Eigen::Vector3d& t = pose.pose.translation;
  const Eigen::Vector3d center = pose.pose.Center();
  out["qvec"] = {q.w(), q.x(), q.y(), q.z()};
  out["tvec"] = {t.x(), t.y(), t.z()};
  out["center"] = {center.x(), center.y(), center.z()};
  out["focal"] = pose.focal_length_px;
  out["k"] = pose.radial_distortion;
  return out;
}

int Run(const std::string& index_path, const std::string& database, const std::string& list,
        const std::string& mapping_path, const std::string& colmap_path, const std::string& out,
        const std::string& pairs_path) {
  const Index index = Index::Open(index_path);
  if (index.view_keypoints().empty())
    throw InputError(index_path +
                     ": no view keypoints (build it with cwloc-index build --keypoints)");
  const DatabaseQueries queries(database);
  const colmap::Reconstruction mapping = colmap::ReadReconstruction(mapping_path);
  const colmap::Reconstruction registered = colmap::ReadReconstruction(colmap_path);

  // Index views by their image and keypoint, and mapping keypoints with a 3D point by theirs.
  // SIFT gives one place several orientations, so a key may hold several: the one whose 3D
  // point is the other side's is taken.
  std::multimap<KeypointKey, uint32_t> views_at;
  for (const IndexImage& image : index.images()) {
    for (uint32_t view = image.first_view; view < image.first_view + image.num_views; ++view) {
      const ViewKeypoint& keypoint = index.view_keypoints()[view];
      views_at.insert({{image.image_id, keypoint.x, keypoint.y}, view});
    }
  }
  std::multimap<KeypointKey, uint32_t> points2D_at;
  for (const auto& [image_id, image] : mapping.images) {
    for (uint32_t i = 0; i < image.points2D.size(); ++i) {
      if (image.points2D[i].point3D_id == kInvalidPoint3DId) continue;
      points2D_at.insert({{image_id, float(image.points2D[i].x), float(image.points2D[i].y)}, i});
    }
  }
  const auto same_place = [](const std::array<double, 3>& a, const std::array<double, 3>& b) {
    return std::abs(a[0] - b[0]) + std::abs(a[1] - b[1]) + std::abs(a[2] - b[2]) < 1e-6;
  };

  LocalizerOptions options;
  const Localizer localizer(index);
  std::ofstream poses(out), pairs(pairs_path);
  std::ifstream names(list);
  std::string line;
  while (std::getline(names, line)) {
    const std::string name = line.substr(0, line.find(' '));
    if (name.empty()) continue;
    const Query query = queries.Load(name);
    nlohmann::json record = {{"name", name}};

    // cwloc's correspondences, fit again alone (the same pose as Localize's, a check), and
    // written as COLMAP's pairs.
    std::vector<FeatureMatch> mine;
    const LocalizationResult localized = localizer.Localize(query, options, nullptr, &mine);
    record["cwloc"] = FitJson(EstimateQueryPose(index, query, mine, options), mine.size());
    record["cwloc"]["localize_success"] = localized.success;
    for (const FeatureMatch& match : mine) {
      const uint32_t image_index = index.ImageOfView(match.view);
      const uint32_t image_id = index.images()[image_index].image_id;
      const ViewKeypoint& keypoint = index.view_keypoints()[match.view];
      const std::array<double, 3> xyz = index.PointXyz(index.view_points()[match.view]);
      const colmap::Image& image = mapping.images.at(image_id);
      const auto [first, last] = points2D_at.equal_range({image_id, keypoint.x, keypoint.y});
      for (auto at = first; at != last; ++at) {
        const point3D_t point_id = image.points2D[at->second].point3D_id;
        if (!same_place(mapping.points3D.at(point_id).xyz, xyz)) continue;
        pairs << name << ' ' << match.feature << ' ' << image_id << ' ' << at->second << '\n';
        break;
      }
    }

    // COLMAP's correspondences: its registered query's 2D points with a 3D point.
    std::vector<FeatureMatch> theirs;
    size_t colmap_pairs = 0;
    for (const auto& [image_id, image] : registered.images) {
      if (image.name != name) continue;
      for (uint32_t feature = 0; feature < image.points2D.size(); ++feature) {
        const point3D_t point_id = image.points2D[feature].point3D_id;
        if (point_id == kInvalidPoint3DId) continue;
        ++colmap_pairs;
        const auto point = mapping.points3D.find(point_id);
        if (point == mapping.points3D.end()) continue;
        std::optional<uint32_t> view;
        for (const colmap::TrackElement& element : point->second.track) {
          const colmap::Point2D& seen =
              mapping.images.at(element.image_id).points2D.at(element.point2D_idx);
          const auto [first, last] =
              views_at.equal_range({element.image_id, float(seen.x), float(seen.y)});
          for (auto at = first; at != last && !view; ++at) {
            if (same_place(index.PointXyz(index.view_points()[at->second]), point->second.xyz))
              view = at->second;
          }
          if (view) break;
        }
        if (view) theirs.push_back({feature, *view, 0.0f});
      }
    }
    record["colmap_pairs"] = colmap_pairs;
    record["colmap_pairs_mapped"] = theirs.size();
    if (!theirs.empty())
      record["colmap"] = FitJson(EstimateQueryPose(index, query, theirs, options), theirs.size());
    poses << record.dump() << '\n';
  }
  if (!poses || !pairs) throw InputError(out + " or " + pairs_path + ": cannot be written");
  return 0;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{"cwloc's pose stage on cwloc's and on COLMAP's correspondences (issue #41)"};
  std::string index, database, list, mapping, colmap, out, pairs;
  app.add_option("--index", index, "The mapping model's index")->required();
  app.add_option("--database", database, "The database with the queries' features")->required();
  app.add_option("--query-list", list, "The queries, one name per line")->required();
  app.add_option("--mapping-model", mapping, "The model the index was built from")->required();
  app.add_option("--colmap-model", colmap, "COLMAP's model with the queries registered")
      ->required();
  app.add_option("-o", out, "Both fits per query, JSON lines")->required();
  app.add_option("--pairs", pairs, "cwloc's correspondences as COLMAP pairs")->required();
  CLI11_PARSE(app, argc, argv);
  return cwloc::RunTool("cwloc-cross-pose", [&] {
    return cwloc::Run(index, database, list, mapping, colmap, out, pairs);
  });
}
