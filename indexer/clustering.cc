#include "indexer/clustering.h"

#include <Eigen/Dense>
#include <Eigen/Sparse>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <unordered_map>

#include "base/bounded_file.h"
#include "base/error.h"

namespace cwloc {
namespace {

Clustering ReadClusteringFile(const std::filesystem::path& path, const ModelViews& views) {
  CheckInputFile(path, kClusterFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open clustering file");
  std::unordered_map<std::string, int64_t> cluster_by_name;
  std::string line;
  for (int line_number = 1; std::getline(in, line); ++line_number) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream fields(line);
    std::string name;
    int64_t cluster;
    if (!(fields >> name >> cluster) || cluster < 0) {
      throw InputError(path.string() + ":" + std::to_string(line_number) +
                       ": expected 'IMAGE_NAME CLUSTER_ID' with a non-negative integer id");
    }
    if (!cluster_by_name.emplace(name, cluster).second) {
      throw InputError(path.string() + ":" + std::to_string(line_number) + ": image '" + name +
                       "' listed twice");
    }
  }
  // Dense ids in increasing order of the file's ids.
  std::map<int64_t, uint32_t> dense;
  std::vector<int64_t> raw(views.images.size());
  for (size_t i = 0; i < views.images.size(); ++i) {
    const IndexImage& image = views.images[i];
    const std::string name(views.ImageName(image));
    const auto it = cluster_by_name.find(name);
    if (it == cluster_by_name.end()) {
      throw InputError(path.string() + ": model image '" + name + "' has no cluster");
    }
    raw[i] = it->second;
    dense.emplace(it->second, 0);
  }
  uint32_t next = 0;
  for (auto& [id, value] : dense) value = next++;
  Clustering clustering{{}, next, "file"};
  for (int64_t id : raw) clustering.cluster_of_image.push_back(dense[id]);
  return clustering;
}

// Normalized spectral clustering (Shi & Malik, as the paper used): the leading eigenvectors of
// D^-1/2 S D^-1/2 for the shared-points matrix S, by subspace iteration, then k-means on the
// row-normalized embedding.
Clustering SpectralClustering(const ClusteringOptions& options, const CovisibilityGraph& graph,
                              size_t num_images) {
  const uint32_t k = options.target_clusters;
  const int dims = static_cast<int>(std::min<size_t>({size_t{50}, size_t{k}, num_images}));
  const int n = static_cast<int>(num_images);

  Eigen::VectorXd degree = Eigen::VectorXd::Ones(n);  // +1 self loop keeps isolated images finite
  std::vector<Eigen::Triplet<double>> triplets;
  for (int i = 0; i < n; ++i) {
    triplets.emplace_back(i, i, 1.0);
    for (uint32_t e = graph.offsets[i]; e < graph.offsets[i + 1]; ++e) {
      triplets.emplace_back(i, graph.edges[e].image_index, graph.edges[e].shared_points);
      degree[i] += graph.edges[e].shared_points;
    }
  }
  Eigen::SparseMatrix<double> affinity(n, n);
  affinity.setFromTriplets(triplets.begin(), triplets.end());
  const Eigen::VectorXd inv_sqrt = degree.cwiseSqrt().cwiseInverse();
  const Eigen::SparseMatrix<double> normalized =
      inv_sqrt.asDiagonal() * affinity * inv_sqrt.asDiagonal();

  std::mt19937_64 rng(options.seed);
  std::normal_distribution<double> normal;
  Eigen::MatrixXd basis(n, dims);
  for (int c = 0; c < dims; ++c) {
    for (int r = 0; r < n; ++r) basis(r, c) = normal(rng);
  }
  // Shifting by I maps the spectrum from [-1, 1] to [0, 2], so iteration finds the largest.
  // Orthonormalizing every few steps is enough to keep the subspace from collapsing.
  for (int iteration = 1; iteration <= 120; ++iteration) {
    basis = Eigen::MatrixXd(normalized * basis + basis);
    if (iteration % 6 == 0) {
      Eigen::HouseholderQR<Eigen::MatrixXd> qr(basis);
      basis = qr.householderQ() * Eigen::MatrixXd::Identity(n, dims);
    }
  }
  for (int r = 0; r < n; ++r) {
    const double norm = basis.row(r).norm();
    if (norm > 0) basis.row(r) /= norm;
  }

  // k-means++ initialisation, then Lloyd iterations.
  Eigen::MatrixXd centres(k, dims);
  std::vector<double> nearest(n, std::numeric_limits<double>::max());
  centres.row(0) = basis.row(std::uniform_int_distribution<int>(0, n - 1)(rng));
  for (uint32_t c = 1; c < k; ++c) {
    for (int r = 0; r < n; ++r)
      nearest[r] = std::min(nearest[r], (basis.row(r) - centres.row(c - 1)).squaredNorm());
    std::discrete_distribution<int> pick(nearest.begin(), nearest.end());
    centres.row(c) = basis.row(pick(rng));
  }
  std::vector<uint32_t> assignment(n, 0);
  for (int iteration = 0; iteration < 50; ++iteration) {
    bool changed = false;
    for (int r = 0; r < n; ++r) {
      Eigen::Index best;
      (centres.rowwise() - basis.row(r)).rowwise().squaredNorm().minCoeff(&best);
      if (assignment[r] != best) changed = true;
      assignment[r] = static_cast<uint32_t>(best);
    }
    if (!changed && iteration > 0) break;
    Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(k, dims);
    std::vector<int> counts(k, 0);
    for (int r = 0; r < n; ++r) {
      sums.row(assignment[r]) += basis.row(r);
      ++counts[assignment[r]];
    }
    for (uint32_t c = 0; c < k; ++c) {
      if (counts[c] > 0) centres.row(c) = sums.row(c) / counts[c];
    }
  }
  // Empty clusters vanish: renumber densely in order of first appearance.
  std::vector<uint32_t> dense(k, UINT32_MAX);
  Clustering clustering{{}, 0, "covisibility"};
  for (uint32_t a : assignment) {
    if (dense[a] == UINT32_MAX) dense[a] = clustering.num_clusters++;
    clustering.cluster_of_image.push_back(dense[a]);
  }
  return clustering;
}

}  // namespace

Clustering ClusterImages(const ClusteringOptions& options, const ModelViews& views,
                         const CovisibilityGraph& graph) {
  const size_t num_images = views.images.size();
  switch (options.method) {
    case ClusteringMethod::kPerImage: {
      Clustering clustering{{}, static_cast<uint32_t>(num_images), "image"};
      for (uint32_t i = 0; i < num_images; ++i) clustering.cluster_of_image.push_back(i);
      return clustering;
    }
    case ClusteringMethod::kFile:
      return ReadClusteringFile(options.file, views);
    case ClusteringMethod::kCovisibility:
      if (options.target_clusters < 1 || options.target_clusters > num_images) {
        throw InputError("--clusters " + std::to_string(options.target_clusters) +
                         ": expected a count in [1, " + std::to_string(num_images) +
                         "] (the number of model images)");
      }
      return SpectralClustering(options, graph, num_images);
  }
  return {};
}

}  // namespace cwloc
