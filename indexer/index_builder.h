#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>

#include "delta/covisibility.h"
#include "indexer/clustering.h"
#include "indexer/georeferencing.h"
#include "indexer/model_views.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {

// `cwloc-index build --compact`: its code size and kd-trees (docs/benchmarks.md, "The compact
// index"; 2 trees localize as 4 do over the points, in 3-4 bytes per view less).
inline constexpr uint32_t kCompactCodeBytes = 32;
inline constexpr uint32_t kCompactTrees = 2;

// Parameters of `cwloc-index build`; all are recorded in the manifest.
struct IndexBuildOptions {
  std::filesystem::path model_dir;
  std::filesystem::path database_path;
  std::filesystem::path output_path;
  ClusteringOptions clustering;  // its seed is set from `seed` below
  // The global forest: num_trees (4, the paper's FLANN setting) and max_leaf_size; its seed,
  // threads and progress are set from this build's.
  KdForestBuildOptions forest;
  uint64_t seed = 0;          // kd-forest randomization and k-means initialisation
  bool keypoints = false;     // also store each view's keypoint (optional section VKXY, 8 B/view)
  bool point_colors = false;  // also store each point's colour (optional section PRGB, 3 B/point)
  // 0: every view's 128-byte descriptor (DESC). Else a compact index: one code of this many
  // bytes per 3D point (PQCB, PCOD, PVNN; indexer/point_codes.h).
  uint32_t code_bytes = 0;
  GeoreferencingOptions georeferencing;  // its fit seed is set from `seed`
  int threads = 0;                       // 0 = all cores
  // Model images left out and localized to calibrate the pose covariance (PCAL;
  // indexer/covariance_calibration.h); 0 = no calibration.
  uint32_t calibration_samples = 30;
};

struct IndexBuildReport {
  size_t num_cameras = 0, num_images = 0, num_points = 0, num_views = 0;
  size_t num_clusters = 0, num_covisibility_edges = 0;
  uint64_t file_bytes = 0;
  nlohmann::ordered_json georeference;  // the manifest's; null when not georeferenced
  double seconds_read = 0, seconds_calibration = 0, seconds_covisibility = 0,
         seconds_clustering = 0;
  double seconds_point_codes = 0;
  double seconds_neighbor_distances = 0, seconds_kd_forest = 0, seconds_write = 0,
         seconds_total = 0;
};

// Reads the model and database, computes every section, writes the index atomically.
// Throws InputError on bad input.
IndexBuildReport BuildIndex(const IndexBuildOptions& options);

struct CovarianceCalibration;

// BuildIndex's steps after the clustering: the codes, v_NN and the kd-forest of `views` (whose
// images hold their clusters), written to `output` with their co-visibility graph, the
// manifest's `source` and the optional sections given (null: not written). The calibration's
// folds run it too.
void WriteIndexOfViews(ModelViews views, const Clustering& clustering,
                       const CovisibilityGraph& graph, const IndexBuildOptions& options,
                       const ModelGeoreference* georeference,
                       const CovarianceCalibration* calibration,
                       const nlohmann::ordered_json& source, const std::filesystem::path& output,
                       IndexBuildReport* report);

// XXH64 over the model files in name order ("xxh64:HEX"): ties the index to the exact model it
// came from (the manifest's source.model.fingerprint).
std::string FingerprintModel(const std::filesystem::path& model_dir);

// The counts of a build, as the manifest (which adds kd_nodes) and `cwloc-index build --json`
// report them: cameras, images, points, views, clusters, covisibility_edges.
nlohmann::ordered_json CountsJson(const IndexBuildReport& report);

}  // namespace cwloc
