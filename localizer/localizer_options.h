#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

#include "base/enum_names.h"
#include "kdtree/kd_forest.h"
#include "localizer/pose/absolute_pose.h"

namespace cwloc {

enum class Matcher {
  kClusterWise,        // the paper: k-ratio + cluster-wise ratio tests, voting, back-matching
  kGlobalRatio,        // diagnostic baseline: plain 1-ratio against the global tree, then RANSAC
  kClusterExhaustive,  // diagnostic gold standard (Table 1): brute-force 1-ratio inside each
                       // cluster, RANSAC per cluster, the cluster with most inliers wins
};

// The names the CLI takes and the JSON reports, in enum order.
inline constexpr std::array<std::string_view, 3> kMatcherNames = {"cluster-wise", "global-ratio",
                                                                  "cluster-exhaustive"};

inline std::string_view MatcherName(Matcher matcher) {
  return kMatcherNames[static_cast<size_t>(matcher)];
}

inline std::optional<Matcher> ParseMatcher(std::string_view name) {
  return ParseEnumName<Matcher>(kMatcherNames, name);
}

// How back-matching finds a model view's query feature (docs/algorithm.md, section 3).
enum class BackMatching {
  kAuto,    // kGuided for a known camera, kFull when the focal length is estimated: on zoomed,
            // uncalibrated queries the guided matches bias the focal length and distortion
            // (docs/benchmarks.md, "Zoomed queries")
  kGuided,  // near where the view's 3D point projects under a pose fit to the forward matches,
            // when they give one; otherwise as kFull
  kFull,    // the paper: 2-NN in a kd-forest over all the query's features
};
inline constexpr std::array<std::string_view, 3> kBackMatchingNames = {"auto", "guided", "full"};

inline std::optional<BackMatching> ParseBackMatching(std::string_view name) {
  return ParseEnumName<BackMatching>(kBackMatchingNames, name);
}

// The largest k: the k + 1 neighbours of a feature fit the ratio test's fixed-size arrays.
inline constexpr uint32_t kMaxK = 63;

// Every threshold and count of the pipeline; defaults are the paper's (section 4,
// "Experimental details"). The option table (app/option_table.inc) names each knob's
// flag and range; ValidateQueryOptions checks them.
struct LocalizerOptions {
  Matcher matcher = Matcher::kClusterWise;
  // Forward matching (Algorithm 1): k nearest neighbours plus one for the k-ratio test.
  uint32_t k = 5;
  // Descriptor distance computations per search of the index's kd-forest: the search's own
  // default, which reaches the recall of the paper's FLANN setting (kd_forest.h).
  uint32_t checks = KdSearchOptions().max_checks;
  double ratio = 0.7;  // tau, used by every ratio test
  // N_F: forward matching stops once this many (query feature, view) matches have passed the
  // k-ratio *and* the cluster-wise ratio test (docs/algorithm.md explains this reading).
  uint32_t forward_matches = 200;
  // Back-matching (Algorithm 3).
  uint32_t back_matches = 200;  // N_B: stop once this many back-matches are found
  // A query whose focal length is unknown (no prior) is fit with its focal length and
  // distortion, which trade off against its depth, so it needs the correspondences over as much
  // of the image as the model gives: its back-matching starts with this N_B, and a view's
  // nearest query feature passes at this ratio instead of `ratio` (0.8: COLMAP's
  // SiftMatching.max_ratio). On internet photos the correspondences COLMAP's registrator fit
  // and cwloc's did not were mostly views of other model images and views at ratios 0.7-0.8
  // (docs/benchmarks.md, "Internet photos": matching or estimation?).
  uint32_t unknown_focal_back_matches = 1600;
  double unknown_focal_back_ratio = 0.8;
  // Until the pose is pinned: with an estimated focal length (unknown, or a prior the
  // correspondences leave weakly constrained) the back-matching goes on where N_B stopped it, to
  // twice its matches, and the pose is estimated again, while each such step shrinks the
  // camera position's uncertainty by at least `pinned_shrink`, up to max_back_matches
  // (localizer.cc, PinPose). Twice the independent evidence would shrink it by 29 %: 25 % asks
  // for nearly that, since a covariance from the keypoints alone counts more views of a
  // well-seen area as new evidence (docs/benchmarks.md, "Until the pose is pinned").
  double pinned_shrink = 0.25;
  uint32_t max_back_matches = 6400;
  uint32_t max_back_clusters = 20;    // ... or this many clusters were back-matched
  uint32_t min_matches_to_vote = 12;  // a back-matched cluster votes for co-visible ones
  uint32_t query_tree_checks = 64;    // distance computations per search of the query's forest
  BackMatching back_matching = BackMatching::kAuto;
  double guide_radius_px = 20.0;  // guided: query features this near the projection compete
  // Robust pose: inlier threshold, minimum inliers, RANSAC's limits, refinement. RANSAC is
  // seeded with `seed` below: one seed drives a query's randomness.
  AbsolutePoseOptions pose;
  // A query's gravity prior (--prior-gravity): its standard deviation, degrees.
  double prior_gravity_sigma_deg = GravityPrior().sigma_deg;
  // A latency budget per query, milliseconds after the features are known (0: none). Each stage
  // stops at its share of it (StageDeadlines in localizer.cc): N_F, N_B and RANSAC's
  // iterations then adapt, and the result lists what was cut.
  double budget_ms = 0;
  // Output.
  uint32_t ranked_images = 10;  // model images listed for location recognition
  uint64_t seed = 0;            // query feature order, the query's kd-forest, RANSAC
  // Run the pose stage; off, Localize stops after matching (a rig's images, rig_localizer.h:
  // the rig fits one pose to them all). Not an option-table knob.
  bool estimate_pose = true;
};

}  // namespace cwloc
