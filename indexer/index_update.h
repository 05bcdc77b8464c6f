#pragma once

#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "base/error.h"
#include "base/option_value.h"
#include "delta/delta_file.h"
#include "format/index.h"

namespace cwloc {

// `cwloc-index update` (docs/cli.md): the index of a grown COLMAP model made from the index of
// the model before, and optionally the delta that turns one into the other.
struct IndexUpdateOptions {
  std::filesystem::path index_path;  // the parent index
  std::filesystem::path model_dir;   // the grown model
  std::filesystem::path database_path;
  std::filesystem::path output_path;
  std::filesystem::path delta_path;          // empty: no delta written
  std::filesystem::path remove_images_file;  // image names, one per line, to take out
  // Build flags given to the update (flag without dashes, value): each must equal the index's.
  std::vector<std::pair<std::string, OptionValue>> build_flags;
  bool rebuild_if_needed = false;  // a full build instead of a refusal
  int threads = 0;
};

// Old images whose camera centre moved by more than this fraction of the extent of the old
// cameras' centres, or turned by more than kMaxPoseTurnRadians, mean the model was adjusted
// again, not grown: COLMAP keeps registered poses bit for bit when it adds images
// (image_registrator, point_triangulator, mapper --Mapper.fix_existing_images 1).
inline constexpr double kMaxCentreShift = 1e-6;
inline constexpr double kMaxPoseTurnRadians = 1e-6;
// The same for the old 3D points, which a bundle adjustment with fixed poses may refine: the
// update takes their new positions, but refuses when the median point moved by more than this
// fraction of that extent.
inline constexpr double kMaxMedianPointShift = 1e-3;
// The kd-forest takes new rows by insertion until the rows inserted since it was last built
// exceed this fraction of the rows it was built over; then it is rebuilt (the balance bound).
inline constexpr double kForestRebuildFraction = 0.25;

// The end of every refusal's message.
inline constexpr const char* kFullBuildNeeded =
    ": a full build is needed (cwloc-index build, or update --rebuild-if-needed)";

// Why an update is no update: a full build is needed.
class UpdateRefused : public InputError {
 public:
  using InputError::InputError;
};

struct IndexUpdateReport {
  bool rebuilt = false;        // --rebuild-if-needed built the index afresh
  std::string rebuild_reason;  // the refusal it answered
  size_t images_added = 0, images_removed = 0, images_changed = 0;
  size_t views_added = 0, views_removed = 0, points_added = 0, points_removed = 0;
  size_t points_moved = 0, clusters_recomputed = 0, neighbor_distances_changed = 0;
  size_t points_recoded = 0;  // a compact index's old points whose views changed: coded anew
  size_t images_read = 0;     // model images whose descriptors were read from the database
  size_t num_images = 0, num_points = 0, num_views = 0, num_clusters = 0;
  bool forest_rebuilt = false;
  bool coded = false;  // a compact index: v_NN (and the kd-forest's rows) per point
  uint64_t file_bytes = 0, delta_bytes = 0;
  // seconds_apply: the child composed from the parent and the delta (tracks, co-visibility,
  // kd-forest), as apply composes it.
  double seconds_read = 0, seconds_compare = 0, seconds_neighbor_distances = 0, seconds_apply = 0,
         seconds_write = 0, seconds_total = 0;
};

// Throws UpdateRefused (unless rebuild_if_needed) when the model was not grown from the one the
// index was built from, InputError on bad input; writes nothing then.
IndexUpdateReport UpdateIndex(const IndexUpdateOptions& options);

// What a child's manifest says of its updates (`update`: counted on from the parent's record)
// and the kd-forest's balance bound: the rows inserted since the forest was built, past
// kForestRebuildFraction of the rows it was built over, rebuild it. Sets `header`'s forest
// fields from the parent's build parameters; its parent fields must be set.
struct ChildUpdate {
  nlohmann::ordered_json record;
  bool forest_rebuilt = false;
};
ChildUpdate NextUpdate(const nlohmann::ordered_json& parent_manifest, const Index& parent,
                       size_t child_rows, size_t rows_inserted, size_t images_added,
                       size_t images_removed, DeltaHeader* header);

nlohmann::ordered_json UpdateReportJson(const IndexUpdateOptions& options,
                                        const IndexUpdateReport& report);

}  // namespace cwloc
