#include "tests/support/sift_agreement_util.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <unordered_map>

#include "colmap/database.h"
#include "photo/image_decode.h"

namespace cwloc::sift_bench {

GreyImage DecodeJpegLikeColmap(const std::filesystem::path& path) {
  return DecodeGreyImage(ReadPhotoFile(path), path);
}

SiftFeatures ReadColmapFeatures(const std::filesystem::path& database, const std::string& name) {
  colmap::DatabaseReader reader(database);
  const auto image = reader.FindImage(name);
  if (!image) throw std::runtime_error(database.string() + ": no image " + name);
  const colmap::ImageFeatures read = reader.ReadFeatures(image->image_id);
  SiftFeatures features;
  for (const colmap::Keypoint& k : read.keypoints) {
    features.keypoints.push_back({k.x, k.y, k.Scale(), k.Orientation()});
  }
  features.descriptors = read.descriptors.data;
  return features;
}

namespace {

// Buckets of keypoints on a grid of 1 px cells.
class PointGrid {
 public:
  explicit PointGrid(const std::vector<SiftKeypoint>& keypoints) {
    for (size_t i = 0; i < keypoints.size(); ++i) {
      cells_[Key(Cell(keypoints[i].x), Cell(keypoints[i].y))].push_back(i);
    }
  }
  template <typename Fn>
  void ForNear(float x, float y, Fn&& fn) const {
    const int64_t cx = Cell(x), cy = Cell(y);
    for (int64_t dy = -1; dy <= 1; ++dy) {
      for (int64_t dx = -1; dx <= 1; ++dx) {
        const auto it = cells_.find(Key(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (size_t i : it->second) fn(i);
      }
    }
  }

 private:
  static int64_t Cell(float v) { return static_cast<int64_t>(std::floor(v)); }
  static int64_t Key(int64_t x, int64_t y) { return (x + (1 << 20)) * (int64_t{1} << 22) + y; }
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

float DescriptorDistance(const uint8_t* a, const uint8_t* b) {
  int sum = 0;
  for (int i = 0; i < kSiftDescriptorDim; ++i) {
    const int d = int(a[i]) - int(b[i]);
    sum += d * d;
  }
  return std::sqrt(float(sum));
}

double AngleDifferenceDeg(double a, double b) {
  double d = std::fmod(std::abs(a - b), 2 * std::numbers::pi);
  if (d > std::numbers::pi) d = 2 * std::numbers::pi - d;
  return d * 180.0 / std::numbers::pi;
}

// Counts keypoints of `a` found in `b`; optionally records nearest descriptor distances.
size_t CountFound(const SiftFeatures& a, const SiftFeatures& b, const AgreementCriteria& c,
                  std::vector<float>* nearest, size_t* same_position) {
  const PointGrid grid(b.keypoints);
  size_t found = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const SiftKeypoint& ka = a.keypoints[i];
    float best = std::numeric_limits<float>::infinity();
    bool same = false;
    grid.ForNear(ka.x, ka.y, [&](size_t j) {
      const SiftKeypoint& kb = b.keypoints[j];
      if (ka.x == kb.x && ka.y == kb.y) same = true;
      const double dx = ka.x - kb.x, dy = ka.y - kb.y;
      if (dx * dx + dy * dy > c.max_position_px * c.max_position_px) return;
      if (AngleDifferenceDeg(ka.orientation, kb.orientation) > c.max_orientation_deg) return;
      best = std::min(best, DescriptorDistance(a.Descriptor(i), b.Descriptor(j)));
    });
    if (same && same_position) ++*same_position;
    if (std::isfinite(best)) {
      if (nearest) nearest->push_back(best);
      if (best <= c.max_descriptor_distance) ++found;
    }
  }
  return found;
}

}  // namespace

Agreement CompareFeatures(const SiftFeatures& a, const SiftFeatures& b,
                          const AgreementCriteria& criteria) {
  Agreement result;
  result.num_a = a.size();
  result.num_b = b.size();
  result.a_found_in_b = CountFound(a, b, criteria, &result.nearest_descriptor_distances,
                                   &result.a_same_position_in_b);
  result.b_found_in_a = CountFound(b, a, criteria, nullptr, nullptr);
  return result;
}

}  // namespace cwloc::sift_bench

namespace cwloc::sift_bench {

std::vector<std::string> ImplementationNames() {
  if (!SiftVlfeatAvailable()) return {"cwloc"};
  return {"cwloc", "vlfeat"};
}

SiftOptions::Implementation ParseImplementation(const std::string& name) {
  if (name == "cwloc") return SiftOptions::Implementation::kCwloc;
  if (name == "vlfeat") return SiftOptions::Implementation::kVlfeat;
  throw std::invalid_argument("unknown SIFT implementation " + name);
}

}  // namespace cwloc::sift_bench
