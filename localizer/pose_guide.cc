#include "localizer/pose_guide.h"

#include <algorithm>
#include <cmath>

#include "kdtree/descriptor_distance.h"

namespace cwloc {

std::optional<double> MedianPointDepth(const Index& index, std::span<const uint32_t> points,
                                       const CameraPose& pose) {
  std::vector<double> depths;
  depths.reserve(points.size());
  for (const uint32_t point : points) {
    if (point >= index.num_points()) continue;
    const auto xyz = index.PointXyz(point);
    depths.push_back(pose.Apply(Eigen::Vector3d(xyz[0], xyz[1], xyz[2])).z());
  }
  if (depths.empty()) return std::nullopt;
  const auto middle = depths.begin() + depths.size() / 2;
  std::nth_element(depths.begin(), middle, depths.end());
  return *middle;
}

PoseGuide::PoseGuide(const Query& query, PoseHypothesis hypothesis, double radius_px)
    : query_(query),
      hypothesis_(std::move(hypothesis)),
      rotation_(hypothesis_.pose.RotationMatrix()),
      radius_px_(radius_px) {
  // Competitors for the ratio test come from a window that holds about kCompetitors features
  // at the query's mean density, and at least the radius: a sparse query still has a second
  // neighbour to compare with.
  constexpr double kCompetitors = 8;
  const double area = double(query.camera.width) * double(query.camera.height);
  const double density = std::max<uint32_t>(query.NumFeatures(), 1) / std::max(area, 1.0);
  reach_px_ = std::max(radius_px, std::sqrt(kCompetitors / (M_PI * density)));
  cell_px_ = std::max(reach_px_, 1.0);
  columns_ = std::max<uint32_t>(1, uint32_t(std::ceil(query.camera.width / cell_px_)));
  rows_ = std::max<uint32_t>(1, uint32_t(std::ceil(query.camera.height / cell_px_)));
  // Counting sort of the features by cell; keypoints outside the image go to the border cells.
  const uint32_t num_features = query.NumFeatures();
  std::vector<uint32_t> cell_of(num_features);
  cell_start_.assign(size_t{columns_} * rows_ + 1, 0);
  for (uint32_t f = 0; f < num_features; ++f) {
    const double x = query.keypoints[2 * f] / cell_px_, y = query.keypoints[2 * f + 1] / cell_px_;
    const uint32_t column = uint32_t(std::clamp(x, 0.0, double(columns_ - 1)));
    const uint32_t row = uint32_t(std::clamp(y, 0.0, double(rows_ - 1)));
    cell_of[f] = row * columns_ + column;
    ++cell_start_[cell_of[f] + 1];
  }
  for (size_t c = 1; c < cell_start_.size(); ++c) cell_start_[c] += cell_start_[c - 1];
  features_.resize(num_features);
  feature_xy_.resize(2 * size_t{num_features});
  std::vector<uint32_t> next(cell_start_.begin(), cell_start_.end() - 1);
  for (uint32_t f = 0; f < num_features; ++f) {
    const uint32_t slot = next[cell_of[f]]++;
    features_[slot] = f;
    feature_xy_[2 * slot] = query.keypoints[2 * f];
    feature_xy_[2 * slot + 1] = query.keypoints[2 * f + 1];
  }
  candidates_.resize(num_features);
  distances_.resize(num_features);
}

std::optional<FeatureMatch> PoseGuide::Match(const Index& index, uint32_t view, double ratio) {
  if (view >= index.num_views()) return std::nullopt;
  const uint32_t point_index = index.view_points()[view];
  if (point_index >= index.num_points()) return std::nullopt;
  const std::array<double, 3> xyz = index.PointXyz(point_index);
  const Eigen::Vector3d in_camera =
      rotation_ * Eigen::Vector3d(xyz[0], xyz[1], xyz[2]) + hypothesis_.pose.translation;
  std::array<double, 2> pixel;
  if (!ProjectToPixel(hypothesis_.model_id, hypothesis_.params,
                      {in_camera.x(), in_camera.y(), in_camera.z()}, &pixel)) {
    return std::nullopt;
  }
  const double x = pixel[0], y = pixel[1];
  if (!(x > -radius_px_ && y > -radius_px_ && x < query_.camera.width + radius_px_ &&
        y < query_.camera.height + radius_px_)) {
    return std::nullopt;
  }
  const auto cell = [this](double v, uint32_t count) {
    return uint32_t(std::clamp(v / cell_px_, 0.0, double(count - 1)));
  };
  const uint32_t column_begin = cell(x - reach_px_, columns_);
  const uint32_t column_end = cell(x + reach_px_, columns_);
  const uint32_t row_begin = cell(y - reach_px_, rows_);
  const uint32_t row_end = cell(y + reach_px_, rows_);
  const double reach_squared = reach_px_ * reach_px_;
  // Locals, so that the compiler need not reload the members in the loops.
  const float* xy = feature_xy_.data();
  const uint32_t* features = features_.data();
  uint32_t* candidates = candidates_.data();
  uint32_t num_candidates = 0;
  for (uint32_t row = row_begin; row <= row_end; ++row) {
    const uint32_t first = cell_start_[row * columns_ + column_begin];
    const uint32_t last = cell_start_[row * columns_ + column_end + 1];
    for (uint32_t i = first; i < last; ++i) {
      const double dx = xy[2 * i] - x, dy = xy[2 * i + 1] - y;
      candidates[num_candidates] = features[i];
      num_candidates += dx * dx + dy * dy <= reach_squared;
    }
  }
  if (num_candidates < 2) return std::nullopt;
  uint32_t* distances = distances_.data();
  BestDistanceFunctions().batch(index.ViewDescriptor(view, decoded_), query_.descriptors.data(),
                                candidates, num_candidates, distances);
  // Nearest and second nearest in descriptor space; ties go to the lower feature index.
  const auto closer = [&](uint32_t a, uint32_t b) {
    return distances[a] < distances[b] ||
           (distances[a] == distances[b] && candidates[a] < candidates[b]);
  };
  uint32_t best = 0, second = 1;
  if (closer(1, 0)) std::swap(best, second);
  for (uint32_t i = 2; i < num_candidates; ++i) {
    if (closer(i, best)) {
      second = best;
      best = i;
    } else if (closer(i, second)) {
      second = i;
    }
  }
  if (!PassesRatioTest(distances[best], distances[second], ratio)) return std::nullopt;
  const uint32_t feature = candidates[best];
  const double dx = query_.keypoints[2 * feature] - x, dy = query_.keypoints[2 * feature + 1] - y;
  if (dx * dx + dy * dy > radius_px_ * radius_px_) return std::nullopt;
  return FeatureMatch{feature, view, std::sqrt(float(distances[best]))};
}

}  // namespace cwloc
