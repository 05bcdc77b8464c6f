#include "tests/localizer/matching_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <set>
#include <span>

#include "camera/camera_models.h"
#include "format/index_file.h"
#include "format/index_layout.h"
#include "kdtree/descriptor_distance.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc::test {
namespace {

double Uniform(SplitMix64& rng, double lo, double hi) {
  return lo + (hi - lo) * static_cast<double>(rng.Next() >> 11) * 0x1.0p-53;
}

template <typename T>
std::span<const T> Span(const std::vector<T>& v) {
  return {v.data(), v.size()};
}

}  // namespace

MatchingScene RandomMatchingScene(SplitMix64& rng, const MatchingSceneOptions& options) {
  MatchingScene scene;
  IndexCamera camera{};
  camera.camera_id = 1;
  camera.model_id = static_cast<int32_t>(CameraModelId::kSimplePinhole);
  camera.width = 640;
  camera.height = 480;
  camera.num_params = 3;
  camera.params[0] = 768;
  camera.params[1] = 320;
  camera.params[2] = 240;
  scene.cameras.push_back(camera);

  // The points each image sees, one entry per observation.
  const uint32_t num_images = options.num_images;
  std::vector<std::vector<uint32_t>> observed(num_images);
  std::vector<uint32_t> images(num_images);
  for (uint32_t p = 0; p < options.num_points; ++p) {
    const uint32_t length =
        std::min(options.min_track_length +
                     rng.Uniform(options.max_track_length - options.min_track_length + 1),
                 num_images);
    // `length` distinct images: the first `length` of a partial Fisher-Yates shuffle.
    std::iota(images.begin(), images.end(), 0u);
    for (uint32_t k = 0; k < length; ++k) {
      std::swap(images[k], images[k + rng.Uniform(num_images - k)]);
      observed[images[k]].push_back(p);
    }
    if (length > 0 && rng.Uniform(options.twice_one_in) == 0) observed[images[0]].push_back(p);
  }

  // Views, image by image, in random order within an image.
  for (uint32_t i = 0; i < num_images; ++i) {
    rng.Shuffle(std::span<uint32_t>(observed[i]));
    const std::string name = "img_" + std::to_string(i + 1) + ".jpg";
    IndexImage image{};
    image.image_id = i + 1;
    image.camera_index = 0;
    image.name_offset = static_cast<uint32_t>(scene.strings.size());
    image.name_size = static_cast<uint32_t>(name.size());
    scene.strings += name;
    image.cam_from_world_rotation[0] = 1;
    image.first_view = static_cast<uint32_t>(scene.view_points.size());
    image.num_views = static_cast<uint32_t>(observed[i].size());
    image.cluster = i;
    scene.images.push_back(image);
    for (const uint32_t point : observed[i]) {
      scene.view_points.push_back(point);
      for (int d = 0; d < kDescriptorBytes; ++d) {
        scene.descriptors.push_back(static_cast<uint8_t>(rng.Uniform(64)));
      }
    }
  }

  // Points, and their tracks grouped by point in view order.
  scene.points.resize(options.num_points);
  for (IndexPoint& point : scene.points) {
    for (double& x : point.xyz) x = Uniform(rng, -2, 2);
  }
  for (const uint32_t point : scene.view_points) ++scene.points[point].track_length;
  uint32_t first_track = 0;
  for (IndexPoint& point : scene.points) {
    point.first_track = first_track;
    first_track += point.track_length;
  }
  scene.tracks.resize(scene.num_views());
  std::vector<uint32_t> next(scene.points.size(), 0);
  for (uint32_t view = 0; view < scene.num_views(); ++view) {
    const IndexPoint& point = scene.points[scene.view_points[view]];
    scene.tracks[point.first_track + next[scene.view_points[view]]++] = view;
  }

  // v_NN within each cluster (an image), by brute force.
  scene.view_neighbor_distances.assign(scene.num_views(), std::numeric_limits<float>::infinity());
  for (const IndexImage& image : scene.images) {
    for (uint32_t u = image.first_view; u < image.first_view + image.num_views; ++u) {
      uint32_t best = std::numeric_limits<uint32_t>::max();
      for (uint32_t v = image.first_view; v < image.first_view + image.num_views; ++v) {
        if (scene.view_points[v] == scene.view_points[u]) continue;
        best = std::min(best, SquaredL2(&scene.descriptors[size_t{u} * kDescriptorBytes],
                                        &scene.descriptors[size_t{v} * kDescriptorBytes]));
      }
      if (best != std::numeric_limits<uint32_t>::max()) {
        scene.view_neighbor_distances[u] = std::sqrt(static_cast<float>(best));
      }
    }
  }

  // Co-visibility: per image, every other image with the number of points both see.
  std::vector<uint32_t> image_of_view(scene.num_views());
  for (uint32_t i = 0; i < num_images; ++i) {
    std::fill_n(image_of_view.begin() + scene.images[i].first_view, scene.images[i].num_views, i);
  }
  scene.covisibility_offsets.push_back(0);
  for (uint32_t i = 0; i < num_images; ++i) {
    const std::set<uint32_t> points(observed[i].begin(), observed[i].end());
    std::vector<uint32_t> shared(num_images, 0);
    for (const uint32_t p : points) {
      const IndexPoint& point = scene.points[p];
      std::set<uint32_t> others;
      for (uint32_t t = point.first_track; t < point.first_track + point.track_length; ++t) {
        if (image_of_view[scene.tracks[t]] != i) others.insert(image_of_view[scene.tracks[t]]);
      }
      for (const uint32_t other : others) ++shared[other];
    }
    for (uint32_t other = 0; other < num_images; ++other) {
      if (shared[other] > 0) scene.covisibility_edges.push_back({other, shared[other]});
    }
    scene.covisibility_offsets.push_back(static_cast<uint32_t>(scene.covisibility_edges.size()));
  }
  return scene;
}

void WriteMatchingIndex(const MatchingScene& scene, const std::filesystem::path& path) {
  KdForestBuildOptions forest_options;
  forest_options.num_threads = 1;
  const KdForest forest = BuildKdForest(scene.descriptors, forest_options);
  // Point p is COLMAP point p + 1 of the scene's model (matching_scene_test.cc writes it so).
  std::vector<uint64_t> point_ids(scene.points.size());
  for (size_t p = 0; p < point_ids.size(); ++p) point_ids[p] = p + 1;
  const std::string manifest = "{\"format_version\": \"" + std::to_string(kFormatMajor) + "." +
                               std::to_string(kFormatMinor) +
                               "\", \"tool\": \"tests/localizer/matching_scene.cc\"}\n";
  const std::vector<SectionData> sections = {
      MakeSection<char>(section::kManifest, {manifest.data(), manifest.size()}),
      MakeSection(section::kCameras, Span(scene.cameras)),
      MakeSection(section::kImages, Span(scene.images)),
      MakeSection<char>(section::kStrings, {scene.strings.data(), scene.strings.size()}),
      MakeSection(section::kPoints, Span(scene.points)),
      MakeSection(section::kTracks, Span(scene.tracks)),
      SectionData{section::kDescriptors, kSectionRequired, kDescriptorBytes, scene.num_views(),
                  scene.descriptors},
      MakeSection(section::kViewPoint, Span(scene.view_points)),
      MakeSection(section::kViewNeighbor, Span(scene.view_neighbor_distances)),
      MakeSection(section::kKdNodes, Span(forest.nodes)),
      MakeSection(section::kKdRoots, Span(forest.roots)),
      MakeSection(section::kKdLeaves, Span(forest.leaves)),
      MakeSection(section::kCovisOffsets, Span(scene.covisibility_offsets)),
      MakeSection(section::kCovisEdges, Span(scene.covisibility_edges)),
      MakeSection(section::kPointIds, Span(point_ids), /*flags=*/0),
  };
  WriteIndexFile(path, sections);
}

}  // namespace cwloc::test
