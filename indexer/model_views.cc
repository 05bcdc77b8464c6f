#include "indexer/model_views.h"

#include <algorithm>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <unordered_map>

#include "base/bounded_file.h"
#include "base/error.h"
#include "base/huge_pages.h"
#include "base/progress.h"
#include "camera/camera_models.h"
#include "delta/tracks.h"

namespace cwloc {
namespace {

IndexCamera ToIndexCamera(const colmap::Camera& camera) {
  IndexCamera out{};
  out.camera_id = camera.camera_id;
  out.model_id = static_cast<int32_t>(camera.model_id);
  out.width = static_cast<uint32_t>(camera.width);
  out.height = static_cast<uint32_t>(camera.height);
  if (camera.params.size() > kMaxCameraParams) {
    throw InputError("camera " + std::to_string(camera.camera_id) + " has " +
                     std::to_string(camera.params.size()) +
                     " parameters; the index stores at most " + std::to_string(kMaxCameraParams));
  }
  out.num_params = static_cast<uint32_t>(camera.params.size());
  std::copy(camera.params.begin(), camera.params.end(), out.params);
  return out;
}

constexpr uint32_t kNoPoint = UINT32_MAX;

// A model point's row from its COLMAP id (`ids` ascending): a table indexed by id where the ids
// are dense, as COLMAP numbers them; a hash map where they are not. A city's 10.8M views looked
// up in a hash map took 2 s.
class PointIndexOfId {
 public:
  explicit PointIndexOfId(std::span<const point3D_t> ids) {
    const point3D_t largest = ids.empty() ? 0 : ids.back();
    if (largest < 4 * uint64_t(ids.size()) + 1024) {
      table_.assign(size_t(largest) + 1, kNoPoint);
      for (uint32_t p = 0; p < ids.size(); ++p) table_[ids[p]] = p;
    } else {
      map_.reserve(ids.size());
      for (uint32_t p = 0; p < ids.size(); ++p) map_[ids[p]] = p;
    }
  }
  uint32_t operator()(point3D_t id) const {
    if (!table_.empty() || map_.empty()) return id < table_.size() ? table_[id] : kNoPoint;
    const auto found = map_.find(id);
    return found == map_.end() ? kNoPoint : found->second;
  }

 private:
  std::vector<uint32_t> table_;
  std::unordered_map<point3D_t, uint32_t> map_;
};

// Drops the points no view sees (none in a consistent model) and renumbers the views' points.
void DropPointsWithoutViews(ModelViews* views) {
  std::vector<uint32_t> num_views(views->points.size(), 0);
  for (uint32_t point : views->view_points) ++num_views[point];
  if (std::find(num_views.begin(), num_views.end(), 0) == num_views.end()) return;
  std::vector<uint32_t> new_index(views->points.size(), UINT32_MAX);
  decltype(views->points) kept_points;
  decltype(views->point_ids) kept_ids;
  decltype(views->point_colors) kept_colors;
  for (size_t p = 0; p < views->points.size(); ++p) {
    if (num_views[p] == 0) continue;
    new_index[p] = static_cast<uint32_t>(kept_points.size());
    kept_points.push_back(views->points[p]);
    kept_ids.push_back(views->point_ids[p]);
    kept_colors.push_back(views->point_colors[p]);
  }
  for (uint32_t& point : views->view_points) point = new_index[point];
  views->points = std::move(kept_points);
  views->point_ids = std::move(kept_ids);
  views->point_colors = std::move(kept_colors);
}

}  // namespace

ModelViews GatherModelViews(const colmap::Reconstruction& model,
                            const colmap::DatabaseReader& database,
                            const KnownViewRows& known_rows) {
  const std::string db_name = database.path().string();
  ModelViews views;

  std::unordered_map<camera_t, uint32_t> camera_index;
  for (const auto& [camera_id, camera] : model.cameras) {
    camera_index[camera_id] = static_cast<uint32_t>(views.cameras.size());
    views.cameras.push_back(ToIndexCamera(camera));
  }

  // Point index of every observed point, in id order; tracks are filled after the views.
  const size_t num_points = model.points3D.size();
  ReserveOnHugePages(&views.points, num_points);
  ReserveOnHugePages(&views.point_ids, num_points);
  ReserveOnHugePages(&views.point_colors, num_points);
  for (const auto& [point_id, point] : model.points3D) {
    IndexPoint p{};
    std::copy(point.xyz.begin(), point.xyz.end(), p.xyz);
    views.points.push_back(p);
    views.point_ids.push_back(point_id);
    views.point_colors.push_back({{point.color[0], point.color[1], point.color[2]}});
  }
  const PointIndexOfId point_index(views.point_ids);

  const size_t total_views = model.NumObservations();
  ReserveOnHugePages(&views.descriptors, total_views * kDescriptorBytes);
  views.descriptors.resize(total_views * kDescriptorBytes);  // untouched until written
  ReserveOnHugePages(&views.view_points, total_views);
  ReserveOnHugePages(&views.view_keypoints, total_views);

  Progress progress("reading descriptors", model.images.size());
  for (const auto& [image_id, image] : model.images) {
    const auto stored = database.FindImage(image.name);
    if (!stored) {
      throw InputError(db_name + ": model image " + std::to_string(image_id) + " '" + image.name +
                       "' is not in the database");
    }
    if (stored->image_id != image_id) {
      throw InputError(db_name + ": model image " + std::to_string(image_id) + " '" + image.name +
                       "' has image_id " + std::to_string(stored->image_id) + " in the database");
    }
    std::vector<point3D_t> observed;
    for (const colmap::Point2D& point2D : image.points2D) {
      if (point2D.point3D_id != kInvalidPoint3DId) observed.push_back(point2D.point3D_id);
    }
    const bool known = known_rows && known_rows(image_id, observed);
    const colmap::Descriptors descriptors =
        known ? colmap::Descriptors{} : database.ReadDescriptors(image_id);
    const uint32_t num_descriptors = known ? database.NumDescriptors(image_id) : descriptors.rows;
    if (num_descriptors != image.points2D.size()) {
      throw InputError(
          db_name + ": image " + std::to_string(image_id) + " '" + image.name + "' has " +
          std::to_string(num_descriptors) + " descriptors but " +
          std::to_string(image.points2D.size()) +
          " 2D points in the model (the model and the database do not belong together)");
    }
    const auto camera = camera_index.find(image.camera_id);
    if (camera == camera_index.end()) {
      throw InputError("model image " + std::to_string(image_id) + " refers to missing camera " +
                       std::to_string(image.camera_id));
    }

    IndexImage row{};
    row.image_id = image_id;
    row.camera_index = camera->second;
    row.name_offset = static_cast<uint32_t>(views.strings.size());
    row.name_size = static_cast<uint32_t>(image.name.size());
    views.strings += image.name;
    std::copy(image.cam_from_world.rotation.begin(), image.cam_from_world.rotation.end(),
              row.cam_from_world_rotation);
    std::copy(image.cam_from_world.translation.begin(), image.cam_from_world.translation.end(),
              row.cam_from_world_translation);
    row.first_view = static_cast<uint32_t>(views.view_points.size());
    for (size_t i = 0; i < image.points2D.size(); ++i) {
      const colmap::Point2D& point2D = image.points2D[i];
      if (point2D.point3D_id == kInvalidPoint3DId) continue;
      const uint32_t point = point_index(point2D.point3D_id);
      if (point == kNoPoint) {
        throw InputError("model image " + std::to_string(image_id) + " point2D " +
                         std::to_string(i) + " refers to missing 3D point " +
                         std::to_string(point2D.point3D_id));
      }
      views.view_points.push_back(point);
      views.view_keypoints.push_back(
          {static_cast<float>(point2D.x), static_cast<float>(point2D.y)});
      if (!known) {
        std::memcpy(&views.descriptors[(views.view_points.size() - 1) * kDescriptorBytes],
                    descriptors.Row(static_cast<uint32_t>(i)), kDescriptorBytes);
      }
    }
    row.num_views = static_cast<uint32_t>(views.view_points.size()) - row.first_view;
    views.images.push_back(row);
    progress.Advance();
  }
  progress.Finish();
  if (views.view_points.size() != total_views)
    throw std::logic_error("GatherModelViews: the model's observations are not its tracks'");

  DropPointsWithoutViews(&views);
  views.tracks = TracksOfViews(views.view_points, views.points);
  return views;
}

ModelViews WithoutImages(const ModelViews& views, const std::vector<bool>& left_out) {
  const auto image_of_view = [&] {
    std::vector<uint32_t> image(views.num_views());
    for (uint32_t i = 0; i < views.images.size(); ++i) {
      const IndexImage& row = views.images[i];
      std::fill_n(image.begin() + row.first_view, row.num_views, i);
    }
    return image;
  }();
  // A point stays with two or more views left (or all of its views, when it had fewer).
  std::vector<uint32_t> new_point(views.points.size(), UINT32_MAX);
  ModelViews out;
  out.cameras = views.cameras;
  for (uint32_t p = 0; p < views.points.size(); ++p) {
    const IndexPoint& point = views.points[p];
    uint32_t kept = 0;
    for (uint32_t t = 0; t < point.track_length; ++t)
      kept += !left_out[image_of_view[views.tracks[point.first_track + t]]];
    if (kept < std::min<uint32_t>(2, point.track_length)) continue;
    new_point[p] = static_cast<uint32_t>(out.points.size());
    out.points.push_back(point);
    out.point_ids.push_back(views.point_ids[p]);
    if (!views.point_colors.empty()) out.point_colors.push_back(views.point_colors[p]);
  }
  const bool keypoints = !views.view_keypoints.empty();
  out.descriptors.resize(views.descriptors.size());
  for (uint32_t i = 0; i < views.images.size(); ++i) {
    if (left_out[i]) continue;
    IndexImage row = views.images[i];
    row.name_offset = static_cast<uint32_t>(out.strings.size());
    out.strings += views.ImageName(views.images[i]);
    row.first_view = static_cast<uint32_t>(out.view_points.size());
    for (uint32_t v = views.images[i].first_view; v < views.images[i].first_view + row.num_views;
         ++v) {
      const uint32_t point = new_point[views.view_points[v]];
      if (point == UINT32_MAX) continue;
      out.view_points.push_back(point);
      if (keypoints) out.view_keypoints.push_back(views.view_keypoints[v]);
      std::memcpy(&out.descriptors[(out.view_points.size() - 1) * kDescriptorBytes],
                  &views.descriptors[size_t{v} * kDescriptorBytes], kDescriptorBytes);
    }
    row.num_views = static_cast<uint32_t>(out.view_points.size()) - row.first_view;
    out.images.push_back(row);
  }
  std::vector<uint32_t> new_cluster;
  uint32_t num_clusters = 0;
  for (IndexImage& image : out.images) {
    if (image.cluster >= new_cluster.size()) new_cluster.resize(image.cluster + 1, UINT32_MAX);
    if (new_cluster[image.cluster] == UINT32_MAX) new_cluster[image.cluster] = num_clusters++;
    image.cluster = new_cluster[image.cluster];
  }
  out.descriptors.resize(out.view_points.size() * kDescriptorBytes);
  out.tracks = TracksOfViews(out.view_points, out.points);
  return out;
}

std::vector<ListedImage> ReadImageNameList(const std::filesystem::path& path) {
  CheckInputFile(path, kQueryListFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the image list");
  std::vector<ListedImage> names;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    names.push_back({number, line.substr(first, line.find_last_not_of(" \t\r") + 1 - first)});
  }
  return names;
}

}  // namespace cwloc
