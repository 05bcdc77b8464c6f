#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "delta/covisibility.h"
#include "indexer/model_views.h"

namespace cwloc {

enum class ClusteringMethod {
  kPerImage,      // one cluster per model image (the paper's best setting, the default)
  kFile,          // "image name -> cluster id" lines from a file
  kCovisibility,  // spectral clustering of the shared-points matrix into a target count
};

struct ClusteringOptions {
  ClusteringMethod method = ClusteringMethod::kPerImage;
  std::filesystem::path file;    // kFile
  uint32_t target_clusters = 0;  // kCovisibility
  uint64_t seed = 0;             // k-means initialisation for kCovisibility
};

struct Clustering {
  std::vector<uint32_t> cluster_of_image;  // per image row, dense ids [0, num_clusters)
  uint32_t num_clusters = 0;
  std::string method;  // "image", "file" or "covisibility"
};

// Throws InputError for an unreadable or malformed clustering file (naming file and line), a
// model image missing from it, or a target count outside [1, number of images].
Clustering ClusterImages(const ClusteringOptions& options, const ModelViews& views,
                         const CovisibilityGraph& graph);

}  // namespace cwloc
