#pragma once

#include <cstdint>
#include <random>
#include <vector>

#include "format/index/index.h"
#include "format/kdtree/kd_forest.h"
#include "localizer/localizer_options.h"
#include "localizer/query.h"

namespace cwloc {

// The ratio test ||q - a|| / ||q - b|| <= tau, on the squared distances the kd-forest returns.
inline bool PassesRatioTest(uint32_t nearest_squared, uint32_t other_squared, double ratio) {
  return static_cast<double>(nearest_squared) <= ratio * ratio * static_cast<double>(other_squared);
}

// A 2D-3D candidate: a query feature matched to a model view (hence to the view's 3D point).
struct FeatureMatch {
  uint32_t feature = 0;
  uint32_t view = 0;
  float distance = 0;  // L2 between the descriptors
};

struct ForwardMatchingStats {
  uint32_t features_searched = 0;
  uint32_t passed_k_ratio = 0;
  uint32_t local_ratio_tests = 0;  // clusters with two neighbours of distinct points
  uint32_t t_ratio_tests = 0;      // clusters with a single neighbour
  double seconds_knn = 0;
  double seconds_ratio_test = 0;
};

// Algorithms 1 and 2 of the paper, interleaved: query features in random order, (k+1)-NN in
// the global kd-forest, the k-ratio test, then the cluster-wise ratio test on the k
// neighbours; stops once options.forward_matches matches have passed both.
std::vector<FeatureMatch> MatchForward(const Index& index, const Query& query, const LocalizerOptions& options,
                                       std::mt19937_64& rng, KdForestSearcher& searcher,
                                       ForwardMatchingStats* stats);

// The diagnostic baseline: every query feature's 2-NN in the global forest, the plain 1-ratio
// test.
std::vector<FeatureMatch> MatchGlobalRatio(const Index& index, const Query& query, const LocalizerOptions& options,
                                           KdForestSearcher& searcher, ForwardMatchingStats* stats);

}  // namespace cwloc
