#include "indexer/index_builder.h"

#include <nlohmann/json.hpp>

#include "base/bounded_file.h"
#include "base/error.h"
#include "base/parallel_for.h"
#include "base/stopwatch.h"
#include "colmap/reconstruction_io.h"
#include "cwloc/version.h"
#include "delta/covisibility.h"
#include "format/xxhash64.h"
#include "indexer/build_option_table.h"
#include "indexer/covariance_calibration.h"
#include "indexer/index_writer.h"
#include "indexer/model_views.h"
#include "indexer/neighbor_distances.h"
#include "indexer/point_codes.h"
#include "kdtree/descriptor_codes.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {
IndexBuildReport BuildIndex(const IndexBuildOptions& options) {
  const Stopwatch total;
  IndexBuildReport report;
  ValidateBuildOptions(options);
  const bool coded = options.code_bytes != 0;
  // The small inputs are read after the model; refuse a bad one before minutes of reading.
  if (!options.georeferencing.georef_file.empty())
    CheckInputFile(options.georeferencing.georef_file, kGeorefFile);
  if (options.clustering.method == ClusteringMethod::kFile)
    CheckInputFile(options.clustering.file, kClusterFile);

  Stopwatch stage;
  const colmap::Reconstruction model =
      colmap::ReadReconstruction(options.model_dir, ResolveThreads(options.threads));
  const colmap::DatabaseReader database(options.database_path);
  ModelViews views = GatherModelViews(model, database);
  if (views.num_views() == 0) {
    throw InputError(options.model_dir.string() +
                     ": the model has no 3D points with views; nothing to index");
  }
  if (coded && views.points.size() < DescriptorCodes::kCentroids) {
    throw InputError(options.model_dir.string() + ": a compact index learns 256 codes per part " +
                     "from the 3D points, and the model has " +
                     std::to_string(views.points.size()) + "; build a full index (no --compact)");
  }
  if (views.num_views() >= UINT32_MAX)
    throw InputError("more than 2^32 - 1 views; split the model");
  GeoreferencingOptions georeferencing = options.georeferencing;
  georeferencing.fit.seed = options.seed;
  const std::optional<ModelGeoreference> georeference = GeoreferenceModel(views, georeferencing);
  report.seconds_read = stage.Seconds();

  const int threads = ResolveThreads(options.threads);
  stage.Restart();
  const CovisibilityGraph graph =
      BuildCovisibilityGraph(views.images, views.points, views.tracks, views.view_points, threads);
  report.seconds_covisibility = stage.Seconds();

  stage.Restart();
  ClusteringOptions clustering_options = options.clustering;
  clustering_options.seed = options.seed;
  const Clustering clustering = ClusterImages(clustering_options, views, graph);
  for (size_t i = 0; i < views.images.size(); ++i)
    views.images[i].cluster = clustering.cluster_of_image[i];
  report.seconds_clustering = stage.Seconds();

  std::optional<CovarianceCalibration> calibration;
  if (options.calibration_samples > 0) {
    stage.Restart();
    calibration = CalibrateCovariance(views, clustering.method, database, options);
    report.seconds_calibration = stage.Seconds();
  }

  const nlohmann::ordered_json source = {{"model",
                                          {{"path", options.model_dir.string()},
                                           {"layout", model.rigs.empty() ? "classic" : "rigs"},
                                           {"fingerprint", FingerprintModel(options.model_dir)}}},
                                         {"database", {{"path", options.database_path.string()}}}};
  WriteIndexOfViews(std::move(views), clustering, graph, options,
                    georeference ? &*georeference : nullptr, calibration ? &*calibration : nullptr,
                    source, options.output_path, &report);
  report.seconds_total = total.Seconds();
  return report;
}

void WriteIndexOfViews(ModelViews views, const Clustering& clustering,
                       const CovisibilityGraph& graph, const IndexBuildOptions& options,
                       const ModelGeoreference* georeference,
                       const CovarianceCalibration* calibration,
                       const nlohmann::ordered_json& source, const std::filesystem::path& output,
                       IndexBuildReport* report) {
  const bool coded = options.code_bytes != 0;
  const int threads = ResolveThreads(options.threads);
  Stopwatch stage;
  PointCodes point_codes;
  if (coded) {
    point_codes = CodePointDescriptors(views, options.code_bytes, options.seed, threads);
    report->seconds_point_codes = stage.Seconds();
  }

  stage.Restart();
  // The full index's v_NN is per view; the compact one's per point, on the decoded codes
  // (this overwrites the views' descriptors, which it no longer stores).
  const std::vector<float> neighbor_distances =
      coded ? ComputePointNeighborDistances(&views, point_codes.decoded, clustering, threads)
            : ComputeViewNeighborDistances(views, clustering, threads);
  report->seconds_neighbor_distances = stage.Seconds();

  stage.Restart();
  // The forest's rows: views, or the compact index's points (as the localizer decodes them).
  const KdForest forest = BuildIndexForest(coded ? std::span<const uint8_t>(point_codes.decoded)
                                                 : std::span<const uint8_t>(views.descriptors),
                                           options.forest, options.seed, threads);
  report->seconds_kd_forest = stage.Seconds();

  report->num_cameras = views.cameras.size();
  report->num_images = views.images.size();
  report->num_points = views.points.size();
  report->num_views = views.num_views();
  report->num_clusters = clustering.num_clusters;
  report->num_covisibility_edges = graph.edges.size();

  nlohmann::ordered_json manifest;
  // Set once the sections are known (FormatMinorOf).
  manifest["format_version"] = "";  // set by WriteIndex
  manifest["tool"] = "cwloc-index";
  manifest["tool_version"] = kToolVersion;
  manifest["counts"] = CountsJson(*report);
  manifest["counts"]["kd_nodes"] = forest.nodes.size();
  nlohmann::ordered_json clustering_json = {{"method", clustering.method},
                                            {"num_clusters", clustering.num_clusters}};
  if (options.clustering.method == ClusteringMethod::kFile)
    clustering_json["file"] = options.clustering.file.string();
  if (options.clustering.method == ClusteringMethod::kCovisibility) {
    clustering_json["target_clusters"] = options.clustering.target_clusters;
  }
  manifest["build_parameters"] = {
      {"kd_trees", options.forest.num_trees},
      {"kd_leaf_size", options.forest.max_leaf_size},
      {"seed", options.seed},
      {"keypoints", options.keypoints},
      {"clustering", clustering_json},
      {"view_neighbor", coded ? "per point: nearest other point's decoded code in any cluster "
                                "that sees the point"
                              : "nearest view of another 3D point in the same cluster"}};
  // Absent: no colours, as before format 1.4 (and the manifest of an index without them is too).
  if (options.point_colors) manifest["build_parameters"]["point_colors"] = true;
  if (coded) {  // absent: a full index, as before format 1.2
    manifest["build_parameters"]["descriptors"] = {{"storage", "point_codes"},
                                                   {"per_point", "mean of its views"},
                                                   {"code", "product quantization"},
                                                   {"code_bytes", options.code_bytes}};
  }
  manifest["source"] = source;
  manifest["georeference"] = georeference ? georeference->manifest : nlohmann::ordered_json();
  report->georeference = manifest["georeference"];
  // Absent: not calibrated, as before format 1.3.
  if (calibration) manifest["covariance_calibration"] = calibration->manifest;

  stage.Restart();
  const PointOffsets point_offsets = coded ? OffsetPoints(views.points) : PointOffsets{};
  // What the model views hold that this index does not store: a compact one's points and
  // descriptors are its offsets and codes, keypoints and colours are optional.
  IndexRows rows = views.Borrow();
  (coded ? rows.point_neighbor_distances : rows.view_neighbor_distances) = neighbor_distances;
  BorrowKdForest(forest, &rows);
  rows.covisibility_offsets = graph.offsets;
  rows.covisibility_edges = graph.edges;
  if (coded) {
    rows.point_origin = {&point_offsets.origin, 1};
    rows.point_offsets = point_offsets.offsets;
    rows.codebook = point_codes.codebook;
    rows.codes = point_codes.codes;
    rows.code_bytes = options.code_bytes;
  }
  if (!options.keypoints) rows.view_keypoints = {};
  if (!options.point_colors) rows.point_colors = {};
  if (georeference) rows.georeference = {&georeference->section, 1};
  if (calibration) rows.covariance_calibration = {&calibration->section, 1};
  WriteIndex(output, rows, std::move(manifest));
  report->seconds_write = stage.Seconds();
  report->file_bytes = std::filesystem::file_size(output);
}

std::string FingerprintModel(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string ext = entry.path().extension().string();
    if (entry.is_regular_file() && (ext == ".bin" || ext == ".txt")) files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  uint64_t hash = 0;
  for (const auto& file : files) {
    const std::string name = file.filename().string();
    hash = XxHash64({reinterpret_cast<const uint8_t*>(name.data()), name.size()}, hash);
    // In chunks: read whole, a city's 650 MB model cost 4 s of page faults.
    XxHash64Stream content(hash);
    ReadFileInChunks(file, kColmapModelFile,
                     [&](std::span<const uint8_t> chunk) { content.Update(chunk); });
    hash = content.Digest();
  }
  return "xxh64:" + HashHex(hash);
}

nlohmann::ordered_json CountsJson(const IndexBuildReport& report) {
  return {{"cameras", report.num_cameras},   {"images", report.num_images},
          {"points", report.num_points},     {"views", report.num_views},
          {"clusters", report.num_clusters}, {"covisibility_edges", report.num_covisibility_edges}};
}

}  // namespace cwloc
