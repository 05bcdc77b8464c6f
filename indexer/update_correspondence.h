#pragma once

// What `cwloc-index update` finds between an index and the grown model: the model read as a
// build reads it (old images' view rows taken from the index where their observations did not
// change), and which child row each parent image, view and point is.

#include <cstdint>
#include <future>
#include <string>
#include <unordered_set>
#include <vector>

#include "colmap/database.h"
#include "format/index.h"
#include "indexer/index_update.h"
#include "indexer/model_views.h"

namespace cwloc {

struct GrownModel {
  ModelViews views;
  std::string layout;  // "classic" or "rigs", as the manifest's source says
  // Per parent image: its view rows are the index's, left unwritten in views.descriptors.
  std::vector<bool> rows_reused;
  // A compact parent's: model images whose descriptors were not read (their rows are left
  // unwritten): they see no point the update may code anew.
  std::unordered_set<image_t> unread_images;
  size_t images_read = 0;  // model images whose descriptors came from the database
  // The COLMAP model, freed on a second thread meanwhile (its millions of small allocations
  // took 0.4 s on a city); destroying this waits for it.
  std::future<void> model_freed;
};

// The grown model gathered as a build gathers it, but an old image whose observations are of
// the same points in the same order keeps its view rows from the index (one in 64 is compared
// with the database: UpdateRefused when they differ); a compact parent's reads only the
// descriptors of images that see a point it may code anew; without the images of
// options.remove_images_file, as `colmap image_deleter` takes them out.
GrownModel ReadGrownModel(const IndexUpdateOptions& options, const Index& parent,
                          const colmap::DatabaseReader& database);

// Writes the view rows of `image` (the child's) that the gather left to the index: those of its
// parent image `old_image`, row for row (rows_reused).
void WriteRowsFromIndex(const Index& parent, const IndexImage& old_image, const IndexImage& image,
                        ModelViews* child);

// Parent row -> child row and back (kRemovedRow: none) of images, views and points.
struct Correspondence {
  std::vector<uint32_t> child_of_parent_image, parent_of_child_image;
  std::vector<uint32_t> child_of_parent_view, parent_of_child_view;
  std::vector<uint32_t> child_of_parent_point, parent_of_child_point;
  std::vector<bool> image_changed;  // per child image: new, or not its parent's views row for row
  double extent = 0;                // of the parent's camera centres, for the move thresholds
};

// Images by COLMAP id (an old one must keep its name, camera and pose: UpdateRefused
// otherwise), an old image's views found again in order among its rows (a view the model
// dropped must still be in the database), points by COLMAP id.
Correspondence MatchToParent(const IndexUpdateOptions& options, const Index& parent,
                             const GrownModel& grown, const colmap::DatabaseReader& database);

}  // namespace cwloc
