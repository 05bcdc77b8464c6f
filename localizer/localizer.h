#pragma once

#include <optional>

#include "format/index.h"
#include "localizer/geo_priors.h"
#include "localizer/localization_result.h"
#include "localizer/localizer_options.h"
#include "localizer/matching.h"
#include "localizer/query.h"

namespace cwloc {

// Localizes queries against one index. Construction is O(images); Localize is const and
// thread-safe, so one Localizer serves every thread of a batch.
class Localizer {
 public:
  explicit Localizer(const Index& index);

  // The pipeline: the query is checked, the matcher yields 2D-3D correspondences, the pose
  // stage fits them. Throws InputError naming the query for one that cannot be processed at
  // all (no features, an unusable camera); a query that simply fails to localize returns
  // success = false with the reason.
  LocalizationResult Localize(const Query& query, const LocalizerOptions& options) const;

  // The part of Localize's check that concerns the query's priors: a latitude in [-90, 90], a
  // finite longitude and height, a positive radius, a non-zero gravity, and a georeferenced
  // index for either. Throws InputError naming the query. (The API calls it first, so that a
  // bad prior is the caller's argument rather than a bad query.)
  void ValidatePriors(const Query& query) const;

  const Index& index() const { return index_; }
  // Set when the index is georeferenced.
  const std::optional<IndexGeo>& geo() const { return geo_; }

 private:
  const Index& index_;
  ClusterMembers clusters_;
  std::optional<IndexGeo> geo_;
};

}  // namespace cwloc
