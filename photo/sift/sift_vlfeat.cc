// The reference path: VLFeat's SIFT driven exactly as COLMAP 3.8's ExtractSiftFeaturesCPU
// drives it (src/feature/sift.cc), so its output is COLMAP's up to VLFeat's build.
#include "photo/sift/sift_vlfeat.h"

extern "C" {
#include <vl/sift.h>
}

#include <algorithm>
#include <memory>
#include <mutex>
#include <stdexcept>

#include "base/parallel_for.h"
#include "photo/sift/sift_levels.h"

namespace cwloc::sift_internal {
namespace {

struct FilterDeleter {
  void operator()(VlSiftFilt* f) const { vl_sift_delete(f); }
};

// vl_sift_new rewrites a global exp() table (the same values each time); one at a time.
std::unique_ptr<VlSiftFilt, FilterDeleter> NewFilter(const GreyImage& image,
                                                     const SiftOptions& options) {
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  return std::unique_ptr<VlSiftFilt, FilterDeleter>(
      vl_sift_new(static_cast<int>(image.width), static_cast<int>(image.height),
                  options.num_octaves, options.octave_resolution, options.first_octave));
}

}  // namespace

SiftFeatures ExtractSiftVlfeat(const GreyImage& image, const SiftOptions& options) {
  auto filter = NewFilter(image, options);
  if (!filter) throw std::runtime_error("SIFT: VLFeat could not allocate its filter");
  VlSiftFilt* f = filter.get();
  vl_sift_set_peak_thresh(f, options.peak_threshold);
  vl_sift_set_edge_thresh(f, options.edge_threshold);

  std::vector<SiftLevel> levels;
  int prev_level = -1;  // as in COLMAP, not reset between octaves
  bool first = true;
  while (true) {
    if (first) {
      std::vector<float> data(image.pixels.size());
      for (size_t i = 0; i < data.size(); ++i) data[i] = float(image.pixels[i]) / 255.0f;
      if (vl_sift_process_first_octave(f, data.data())) break;
      first = false;
    } else if (vl_sift_process_next_octave(f)) {
      break;
    }
    vl_sift_detect(f);
    const VlSiftKeypoint* keys = vl_sift_get_keypoints(f);
    const int num_keys = vl_sift_get_nkeypoints(f);
    if (num_keys == 0) continue;

    // Orientations of every keypoint of the octave (the first call fills VLFeat's gradient
    // buffer, so it runs alone; the rest only read the filter).
    struct Angles {
      double angle[4];
      int count;
    };
    std::vector<Angles> angles(static_cast<size_t>(num_keys));
    auto orient = [&](size_t i) {
      if (options.upright) {
        angles[i].count = 1;
        angles[i].angle[0] = 0.0;
      } else {
        angles[i].count = vl_sift_calc_keypoint_orientations(f, angles[i].angle, &keys[i]);
      }
    };
    orient(0);
    ParallelFor(size_t(num_keys - 1), options.num_threads, [&](size_t i) { orient(i + 1); });

    // COLMAP's grouping: a new level starts whenever the level index changes.
    struct Task {
      size_t level, slot, key;
      double angle;
    };
    std::vector<Task> tasks;
    for (int i = 0; i < num_keys; ++i) {
      if (keys[i].is != prev_level || levels.empty()) levels.emplace_back();
      prev_level = keys[i].is;
      SiftLevel& level = levels.back();
      level.num_detections += 1;
      const int used = std::min(angles[size_t(i)].count, options.max_num_orientations);
      for (int o = 0; o < used; ++o) {
        const double angle = angles[size_t(i)].angle[o];
        tasks.push_back({levels.size() - 1, level.keypoints.size(), size_t(i), angle});
        level.keypoints.push_back(
            {keys[i].x + 0.5f, keys[i].y + 0.5f, keys[i].sigma, static_cast<float>(angle)});
      }
    }
    for (size_t l = 0; l < levels.size(); ++l) {
      levels[l].descriptors.resize(levels[l].keypoints.size() * kSiftDescriptorDim);
    }
    ParallelFor(tasks.size(), options.num_threads, [&](size_t t) {
      const Task& task = tasks[t];
      float* out = levels[task.level].descriptors.data() + task.slot * kSiftDescriptorDim;
      std::fill(out, out + kSiftDescriptorDim, 0.0f);
      vl_sift_calc_keypoint_descriptor(f, out, &keys[task.key], task.angle);
    });
  }

  std::vector<size_t> counts;
  for (const SiftLevel& level : levels) counts.push_back(level.num_detections);
  return AssembleFeatures(levels, FirstLevelToKeep(counts, options.max_num_features), options);
}

}  // namespace cwloc::sift_internal
