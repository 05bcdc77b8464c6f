#include "localizer/back_matching.h"

#include <algorithm>
#include <cmath>

#include "base/stopwatch.h"

namespace cwloc {
namespace {

// Views matched between two reads of the clock (a guided match takes ~0.2 us).
constexpr uint32_t kViewsPerDeadlineCheck = 32;

}  // namespace

double BackMatchingRatio(const LocalizerOptions& options, const QueryCamera& camera) {
  return camera.calibration == Calibration::kUnknown ? options.unknown_focal_back_ratio
                                                     : options.ratio;
}

uint32_t BackMatchingTarget(const LocalizerOptions& options, const QueryCamera& camera) {
  return camera.calibration == Calibration::kUnknown
             ? std::max(options.back_matches, options.unknown_focal_back_matches)
             : options.back_matches;
}

BackMatcher::BackMatcher(const Index& index, const ClusterMembers& clusters, const Query& query,
                         std::span<const FeatureMatch> forward_matches,
                         const LocalizerOptions& options, double ratio, ClusterMask allowed,
                         PoseGuide* guide, const Deadline& stop)
    : index_(index),
      clusters_(clusters),
      query_(query),
      options_(options),
      ratio_(ratio),
      allowed_(allowed),
      guide_(guide),
      stop_(stop),
      visited_(clusters.num_clusters(), false),
      neighbors_(2) {
  search_options_.max_checks = options.query_tree_checks;
  result_.cluster_votes.assign(clusters.num_clusters(), 0);
  for (const FeatureMatch& match : forward_matches) Vote(ClusterOfView(index, match.view));
}

void BackMatcher::Vote(uint32_t cluster) {
  if (cluster >= result_.cluster_votes.size() || !ClusterAllowed(allowed_, cluster)) return;
  if (result_.cluster_votes[cluster]++ == 0) voted_.push_back(cluster);
}

std::optional<FeatureMatch> BackMatcher::MatchView(uint32_t view) {
  if (guide_ != nullptr) return guide_->Match(index_, view, ratio_);
  const KdSearchResult found =
      searcher_->Search(index_.ViewDescriptor(view, decoded_), search_options_, neighbors_);
  if (found.num_neighbors < 2) return std::nullopt;
  if (!PassesRatioTest(neighbors_[0].distance, neighbors_[1].distance, ratio_)) return std::nullopt;
  return FeatureMatch{neighbors_[0].index, view,
                      std::sqrt(static_cast<float>(neighbors_[0].distance))};
}

void BackMatcher::Run(uint32_t back_matches) {
  if (result_.stopped_by_deadline) return;
  if (voted_.empty() || query_.NumFeatures() < 2) {
    result_.stop = BackStop::kNoVotes;
    return;
  }
  Stopwatch stopwatch;
  if (!started_) {
    started_ = true;
    if (guide_ == nullptr) {
      if (stop_.Passed()) {
        result_.stopped_by_deadline = true;  // the forest alone would cost milliseconds
        result_.stop = BackStop::kDeadline;
        return;
      }
      const std::span<const uint8_t> descriptors(query_.descriptors.data(),
                                                 size_t{query_.NumFeatures()} * 128);
      KdForestBuildOptions tree_options;
      tree_options.num_trees = 4;
      tree_options.num_threads = 1;
      tree_options.seed = options_.seed;
      query_forest_ = BuildKdForest(descriptors, tree_options);
      searcher_.emplace(query_forest_->View(descriptors));
    }
    result_.seconds_query_tree = stopwatch.Seconds();
    stopwatch.Restart();
  }

  const std::vector<uint32_t>& votes = result_.cluster_votes;
  while (result_.matches.size() < back_matches &&
         result_.visited.size() < options_.max_back_clusters && !result_.stopped_by_deadline) {
    CastPendingVotes();
    uint32_t best = UINT32_MAX;
    for (uint32_t cluster : voted_) {
      if (!visited_[cluster] && (best == UINT32_MAX || votes[cluster] > votes[best] ||
                                 (votes[cluster] == votes[best] && cluster < best))) {
        best = cluster;
      }
    }
    if (best == UINT32_MAX) break;
    visited_[best] = true;
    const size_t first_match = result_.matches.size();
    for (uint32_t i = clusters_.offsets[best];
         i < clusters_.offsets[best + 1] && !result_.stopped_by_deadline; ++i) {
      const IndexImage& image = index_.images()[clusters_.images[i]];
      for (uint32_t view = image.first_view; view < image.first_view + image.num_views; ++view) {
        if (view >= index_.num_views()) break;  // a corrupt range; verify names it
        if ((view - image.first_view) % kViewsPerDeadlineCheck == 0 && stop_.Passed()) {
          result_.stopped_by_deadline = true;
          break;
        }
        // A coded index gives all of a point's views one descriptor: match each point once.
        if (index_.coded() && !tried_points_.insert(index_.view_points()[view]).second) continue;
        if (const std::optional<FeatureMatch> match = MatchView(view))
          result_.matches.push_back(*match);
      }
    }
    const uint32_t found_here = static_cast<uint32_t>(result_.matches.size() - first_match);
    result_.visited.push_back({best, votes[best], found_here});
    if (found_here >= options_.min_matches_to_vote) pending_votes_ = {best, first_match};
  }
  result_.stop = result_.stopped_by_deadline                            ? BackStop::kDeadline
                 : result_.matches.size() >= back_matches               ? BackStop::kTarget
                 : result_.visited.size() >= options_.max_back_clusters ? BackStop::kImages
                                                                        : BackStop::kNoVotes;
  result_.seconds_matching += stopwatch.Seconds();
}

void BackMatcher::CastPendingVotes() {
  if (!pending_votes_) return;
  const auto [voter, first_match] = *pending_votes_;
  pending_votes_.reset();
  // Co-visibility votes: every other cluster that sees a matched 3D point, once per match.
  for (size_t m = first_match; m < result_.matches.size(); ++m) {
    track_clusters_.clear();
    for (const uint32_t other_view :
         index_.TrackOf(index_.view_points()[result_.matches[m].view])) {
      const uint32_t cluster = ClusterOfView(index_, other_view);
      if (cluster == voter || cluster == UINT32_MAX) continue;
      if (std::find(track_clusters_.begin(), track_clusters_.end(), cluster) ==
          track_clusters_.end()) {
        track_clusters_.push_back(cluster);
        Vote(cluster);
      }
    }
  }
}

BackMatchingResult MatchBack(const Index& index, const ClusterMembers& clusters, const Query& query,
                             std::span<const FeatureMatch> forward_matches,
                             const LocalizerOptions& options, ClusterMask allowed, PoseGuide* guide,
                             const Deadline& stop) {
  BackMatcher matcher(index, clusters, query, forward_matches, options,
                      BackMatchingRatio(options, query.camera), allowed, guide, stop);
  matcher.Run(BackMatchingTarget(options, query.camera));
  return matcher.TakeResult();
}

}  // namespace cwloc
