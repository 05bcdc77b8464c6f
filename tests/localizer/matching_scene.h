#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "base/split_mix64.h"
#include "format/index_sections.h"

namespace cwloc::test {

// The matching tests' model, made in memory without COLMAP files, SQLite or the indexer, so
// that the tests run in device builds too: 10 images of one camera, 400 points each seen by 2
// to 6 images (one point in 20 twice by one image, as COLMAP allows), each image's views in
// random order with random descriptors in [0, 64), and one cluster per image (cluster = image
// row), as `cwloc-index build` clusters by default. Poses and positions are placeholders: the
// matching stages never read them.
struct MatchingSceneOptions {
  uint32_t num_images = 10;
  uint32_t num_points = 400;
  uint32_t min_track_length = 2;
  uint32_t max_track_length = 6;
  uint32_t twice_one_in = 20;  // a point is seen twice by one image with probability 1 / this
};

// The index sections of the scene, computed as `cwloc-index build` computes them from the same
// model (tests/indexer/matching_scene_test.cc checks that its index is the indexer's).
struct MatchingScene {
  std::vector<IndexCamera> cameras;
  std::vector<IndexImage> images;
  std::string strings;  // image names
  std::vector<IndexPoint> points;
  std::vector<uint32_t> tracks;  // views grouped by point, in view order
  std::vector<uint8_t> descriptors;
  std::vector<uint32_t> view_points;
  std::vector<float> view_neighbor_distances;  // v_NN: nearest view of another point in the cluster
  std::vector<uint32_t> covisibility_offsets;
  std::vector<CovisibilityEdge> covisibility_edges;

  size_t num_views() const { return view_points.size(); }
};

// Draws a scene from `rng`.
MatchingScene RandomMatchingScene(SplitMix64& rng, const MatchingSceneOptions& options = {});

// Writes the scene's index, with the kd-forest `cwloc-index build` makes by default (4 trees,
// leaves of 8, seed 0) and a short manifest.
void WriteMatchingIndex(const MatchingScene& scene, const std::filesystem::path& path);

}  // namespace cwloc::test
