#pragma once

#include "format/index/index.h"
#include "localizer/back_matching.h"
#include "localizer/localization_result.h"
#include "localizer/localizer_options.h"
#include "localizer/query.h"

namespace cwloc {

// Localizes queries against one index. Construction is O(images); Localize is const and
// thread-safe, so one Localizer serves every thread of a batch.
class Localizer {
 public:
  explicit Localizer(const Index& index);

  // Throws InputError for a query that cannot be processed at all (an unknown camera model, a
  // camera without parameters); a query that simply fails to localize returns success = false
  // with the reason.
  LocalizationResult Localize(const Query& query, const LocalizerOptions& options) const;

  const Index& index() const { return index_; }

 private:
  const Index& index_;
  ClusterMembers clusters_;
};

// Checks options against absurd values; throws InputError naming the option.
void ValidateLocalizerOptions(const LocalizerOptions& options);

}  // namespace cwloc
