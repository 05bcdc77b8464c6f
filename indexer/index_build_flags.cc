#include "indexer/index_build_flags.h"

#include "base/error.h"

namespace cwloc {

void ApplyBuildFlags(const IndexBuildFlags& flags, IndexBuildOptions* options) {
  if (!flags.cluster_file.empty() && flags.clusters)
    throw InputError("--cluster-file excludes --clusters");
  if (!flags.cluster_file.empty()) {
    options->clustering.method = ClusteringMethod::kFile;
    options->clustering.file = flags.cluster_file;
  } else if (flags.clusters) {
    options->clustering.method = ClusteringMethod::kCovisibility;
    options->clustering.target_clusters = *flags.clusters;
  }
  if (flags.compact && !flags.code_bytes_given) options->code_bytes = kCompactCodeBytes;
  if (flags.compact && !flags.trees_given) options->forest.num_trees = kCompactTrees;
}

nlohmann::ordered_json BuildReportJson(const IndexBuildOptions& options,
                                       const IndexBuildReport& report) {
  return {{"output", options.output_path.string()},
          {"file_bytes", report.file_bytes},
          {"bytes_per_view", double(report.file_bytes) / double(report.num_views)},
          {"counts", CountsJson(report)},
          {"seconds",
           {{"read", report.seconds_read},
            {"covisibility", report.seconds_covisibility},
            {"clustering", report.seconds_clustering},
            {"calibration", report.seconds_calibration},
            {"point_codes", report.seconds_point_codes},
            {"view_neighbors", report.seconds_neighbor_distances},
            {"kd_forest", report.seconds_kd_forest},
            {"write", report.seconds_write},
            {"total", report.seconds_total}}},
          {"georeference", report.georeference}};
}

}  // namespace cwloc
