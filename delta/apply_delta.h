#pragma once

#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "delta/delta_file.h"
#include "format/index.h"
#include "format/index_rows.h"

namespace cwloc {

// The child index that `delta` makes of `parent`, composed in memory: the delta's rows and
// small sections, the parent's kept rows, and what both determine (tracks, co-visibility
// graph, kd-forest, the parent's GEOR and PCAL). `cwloc-index update` writes its output with it
// too, so that apply repeats it bit for bit. Borrows both.
// Throws InputError naming the parent when its kd-forest is not a valid one (ValidateKdForest),
// as the forest's update trusts it to be.
void CheckParentKdForest(const Index& parent);

class AppliedDelta {
 public:
  // kChecked: the caller ran CheckParentKdForest (`cwloc-index update`, while it read the model).
  enum class ParentForest { kUnchecked, kChecked };
  // Refuses (InputError naming `delta_name`) a delta made for another parent (a chain applied
  // out of order) and one whose rows do not fit the parent.
  // Starts writing the child to `output` (IndexFileWriter: a full child's descriptors, on a
  // second thread when `threads` > 1) while it composes the rest; Write finishes it.
  AppliedDelta(const Index& parent, const IndexDelta& delta, const std::string& delta_name,
               const std::filesystem::path& output, int threads,
               ParentForest parent_forest = ParentForest::kUnchecked);
  ~AppliedDelta();
  AppliedDelta(const AppliedDelta&) = delete;
  AppliedDelta& operator=(const AppliedDelta&) = delete;

  size_t num_kd_nodes() const;
  size_t num_covisibility_edges() const;
  // Finishes the child's file with `manifest` as its MANI, puts it in place atomically and
  // returns its header checksum; refuses (InputError, nothing put in place) a child whose
  // checksum is not `expected_checksum`. Once.
  uint64_t Write(std::string_view manifest, std::optional<uint64_t> expected_checksum) const;

 private:
  struct Child;
  // The child's rows so far: those composed, the delta's small sections and the parent's whole
  // ones (TakeParentsSections).
  IndexRows Rows() const;
  const Index& parent_;
  const IndexDelta& delta_;
  std::unique_ptr<Child> child_;
};

struct ApplyDeltaReport {
  size_t parent_views = 0, child_views = 0, child_images = 0;
  uint64_t file_bytes = 0;
  double seconds = 0;
};

// `cwloc-index apply`: reads both files (verifying every checksum of each) and writes the
// child, which must have the checksum the delta names.
ApplyDeltaReport ApplyDelta(const std::filesystem::path& index_path,
                            const std::filesystem::path& delta_path,
                            const std::filesystem::path& output, int threads);

}  // namespace cwloc
