#include "indexer/update_correspondence.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <memory>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

#include "base/bounded_file.h"
#include "base/parallel_for.h"
#include "colmap/reconstruction_io.h"
#include "geo/index_georeference.h"
#include "kdtree/kd_forest_update.h"

namespace cwloc {
namespace {

// An old image whose views the update takes from the index is compared with the database when
// its row is a multiple of this: a database extracted again differs in every image.
constexpr uint32_t kVerifiedImageStride = 64;

// The angle between two cam_from_world rotations (w, x, y, z), exact for small ones.
double TurnRadians(const double* qa, const double* qb) {
  return Eigen::Quaterniond(qa[0], qa[1], qa[2], qa[3])
      .angularDistance(Eigen::Quaterniond(qb[0], qb[1], qb[2], qb[3]));
}

bool SameCamera(const IndexCamera& a, const IndexCamera& b) {
  return a.model_id == b.model_id && a.width == b.width && a.height == b.height &&
         a.num_params == b.num_params &&
         std::memcmp(a.params, b.params, sizeof(double) * a.num_params) == 0;
}

const uint8_t* Row(std::span<const uint8_t> descriptors, size_t row) {
  return descriptors.data() + row * kDescriptorBytes;
}

// Whether `image` of the index observes the points `point_ids` (COLMAP ids, in point2D order),
// one view each, as the model's image does now.
bool ObservesAsInIndex(const Index& parent, const IndexImage& image,
                       std::span<const point3D_t> point_ids) {
  if (image.num_views != point_ids.size()) return false;
  for (uint32_t k = 0; k < image.num_views; ++k) {
    if (parent.point_ids()[parent.view_points()[image.first_view + k]] != point_ids[k])
      return false;
  }
  return true;
}

// A compact index codes a point by its views' mean descriptor, so its update reads the
// descriptors of the images that see a point it may code anew: a new point, an old one whose
// track length changes, or one seen by a new image or an old image whose observations changed
// (a superset of the points RecodeChangedPoints re-codes: an old point seen only by unchanged
// images, as often as before, keeps every view). Returns the other images' ids, `removed`
// (--remove-images) aside, whose views are counted out of the tracks.
std::unordered_set<image_t> ImagesWithoutCodedPoints(
    const colmap::Reconstruction& model, const Index& parent,
    const std::unordered_map<uint32_t, uint32_t>& parent_row_of_id,
    const std::unordered_set<image_t>& removed) {
  std::unordered_set<image_t> changed;  // new, or observing other points than in the index
  std::vector<point3D_t> observed;
  for (const auto& [image_id, image] : model.images) {
    const auto found = parent_row_of_id.find(uint32_t(image_id));
    observed.clear();
    for (const colmap::Point2D& point2D : image.points2D) {
      if (point2D.point3D_id != kInvalidPoint3DId) observed.push_back(point2D.point3D_id);
    }
    if (found == parent_row_of_id.end() ||
        !ObservesAsInIndex(parent, parent.images()[found->second], observed))
      changed.insert(image_id);
  }
  const std::span<const uint64_t> parent_ids = parent.point_ids();
  std::unordered_set<image_t> read;
  uint32_t p = 0;  // both ascend by id
  for (const auto& [point_id, point] : model.points3D) {
    while (p < parent_ids.size() && parent_ids[p] < point_id) ++p;
    const bool old = p < parent_ids.size() && parent_ids[p] == point_id;
    size_t live = 0;
    bool seen_by_changed = false;
    for (const colmap::TrackElement& element : point.track) {
      if (removed.count(element.image_id)) continue;
      ++live;
      seen_by_changed = seen_by_changed || changed.count(element.image_id);
    }
    if (old && !seen_by_changed && live == parent.TrackOf(p).size()) continue;
    for (const colmap::TrackElement& element : point.track) read.insert(element.image_id);
  }
  std::unordered_set<image_t> unread;
  for (const auto& [image_id, image] : model.images) {
    if (!read.count(image_id) && !removed.count(image_id)) unread.insert(image_id);
  }
  return unread;
}

}  // namespace

GrownModel ReadGrownModel(const IndexUpdateOptions& options, const Index& parent,
                          const colmap::DatabaseReader& database) {
  // Freed once gathered: the index's arrays hold what the rest needs.
  auto model = std::make_unique<colmap::Reconstruction>(
      colmap::ReadReconstruction(options.model_dir, ResolveThreads(options.threads)));
  GrownModel grown;
  grown.layout = model->rigs.empty() ? "classic" : "rigs";
  // An old image whose observations are of the same points in the same order keeps its view
  // rows, taken from the index instead of the database; one in kVerifiedImageStride of them is
  // compared with the database, which must hold the same descriptors.
  const std::span<const uint8_t> parent_descriptors = parent.descriptors();
  std::unordered_map<uint32_t, uint32_t> parent_row_of_id;
  for (uint32_t i = 0; i < parent.images().size(); ++i)
    parent_row_of_id[parent.images()[i].image_id] = i;
  grown.rows_reused.assign(parent.images().size(), false);
  // The images that --remove-images takes out, by id.
  std::vector<ListedImage> removed_names;
  if (!options.remove_images_file.empty())
    removed_names = ReadImageNameList(options.remove_images_file);
  std::unordered_set<image_t> removed;
  {
    std::unordered_map<std::string_view, image_t> id_of_name;
    for (const auto& [image_id, image] : model->images) id_of_name[image.name] = image_id;
    for (const ListedImage& image : removed_names) {
      const auto found = id_of_name.find(image.name);
      if (found == id_of_name.end()) {
        throw InputError(options.remove_images_file.string() + ":" + std::to_string(image.line) +
                         ": image '" + image.name + "' is not in the model " +
                         options.model_dir.string());
      }
      removed.insert(found->second);
    }
  }
  // A compact index stores no view descriptors: they come from the database, for the images
  // that see a point coded anew; the others' rows stay unwritten, never read (their points keep
  // their codes, and PVNN is computed on decoded codes).
  if (parent.coded())
    grown.unread_images = ImagesWithoutCodedPoints(*model, parent, parent_row_of_id, removed);
  // Whether an image's view rows need not be read in the database: the gather leaves them
  // unwritten, and the update reads a full index's in the index where it needs them.
  const auto rows_without_database = [&](image_t image_id, std::span<const point3D_t> point_ids) {
    if (parent.coded()) return grown.unread_images.count(image_id) != 0;
    const auto found = parent_row_of_id.find(uint32_t(image_id));
    if (found == parent_row_of_id.end()) return false;
    const IndexImage& image = parent.images()[found->second];
    if (!ObservesAsInIndex(parent, image, point_ids)) return false;
    const uint8_t* rows = Row(parent_descriptors, image.first_view);
    if (found->second % kVerifiedImageStride == 0) {
      const colmap::Descriptors stored = database.ReadDescriptors(image_id);
      const colmap::Image& model_image = model->images.at(image_id);
      uint32_t k = 0;
      for (uint32_t i = 0; i < model_image.points2D.size(); ++i) {
        if (model_image.points2D[i].point3D_id == kInvalidPoint3DId) continue;
        if (i >= stored.rows || std::memcmp(stored.Row(i), rows + size_t(k) * kDescriptorBytes,
                                            kDescriptorBytes) != 0) {
          throw UpdateRefused(options.database_path.string() + ": the descriptors of image '" +
                              std::string(parent.ImageName(image)) +
                              "' differ from those the index was built from" + kFullBuildNeeded);
        }
        ++k;
      }
    }
    grown.rows_reused[found->second] = true;
    return true;
  };
  const KnownViewRows known_rows = [&](image_t image_id, std::span<const point3D_t> point_ids) {
    const bool known = rows_without_database(image_id, point_ids);
    grown.images_read += !known;
    return known;
  };
  grown.views = GatherModelViews(*model, database, known_rows);
  grown.model_freed =
      std::async(std::launch::async, [freed = std::move(model)]() mutable { freed.reset(); });
  if (!removed.empty()) {
    ModelViews& child = grown.views;
    // The points dropped with the removed images take views from images whose rows the index
    // has, which are then matched view by view: their rows are written first.
    const auto reused_parent_image = [&](const IndexImage& image) -> const IndexImage* {
      const auto found = parent_row_of_id.find(image.image_id);
      if (found == parent_row_of_id.end() || !grown.rows_reused[found->second]) return nullptr;
      return &parent.images()[found->second];
    };
    std::vector<bool> left_out(child.images.size(), false);
    for (uint32_t i = 0; i < child.images.size(); ++i) {
      left_out[i] = removed.count(child.images[i].image_id) != 0;
      if (const IndexImage* old_image = reused_parent_image(child.images[i]))
        WriteRowsFromIndex(parent, *old_image, child.images[i], &child);
    }
    child = WithoutImages(child, left_out);
    for (const IndexImage& image : child.images) {
      const IndexImage* old_image = reused_parent_image(image);
      if (old_image != nullptr && old_image->num_views != image.num_views)
        grown.rows_reused[parent_row_of_id.at(image.image_id)] = false;
    }
  }
  return grown;
}

void WriteRowsFromIndex(const Index& parent, const IndexImage& old_image, const IndexImage& image,
                        ModelViews* child) {
  if (old_image.num_views != image.num_views)
    throw std::logic_error("update: an image whose rows the index has changed its views");
  std::memcpy(&child->descriptors[size_t(image.first_view) * kDescriptorBytes],
              Row(parent.descriptors(), old_image.first_view),
              size_t(image.num_views) * kDescriptorBytes);
}

namespace {

// The old images found again by COLMAP id, each keeping its name, camera and pose; sets match's
// image rows and the old cameras' extent.
void MatchImages(const IndexUpdateOptions& options, const Index& parent, const ModelViews& child,
                 Correspondence* match) {
  std::vector<uint32_t>& child_of_parent_image = match->child_of_parent_image;
  std::vector<uint32_t>& parent_of_child_image = match->parent_of_child_image;
  const std::span<const IndexImage> parent_images = parent.images();
  std::unordered_map<uint32_t, uint32_t> child_row_of_id;
  for (uint32_t i = 0; i < child.images.size(); ++i) child_row_of_id[child.images[i].image_id] = i;
  child_of_parent_image.assign(parent_images.size(), kRemovedRow);
  parent_of_child_image.assign(child.images.size(), kRemovedRow);
  Eigen::AlignedBox3d box;
  for (const IndexImage& image : parent_images) box.extend(CameraCenterOf(image));
  const double extent = match->extent = std::max(box.diagonal().norm(), 1e-9);
  for (uint32_t i = 0; i < parent_images.size(); ++i) {
    const IndexImage& old_image = parent_images[i];
    const auto found = child_row_of_id.find(old_image.image_id);
    if (found == child_row_of_id.end()) continue;  // removed
    const IndexImage& image = child.images[found->second];
    const std::string old_name(parent.ImageName(old_image));
    if (child.ImageName(image) != old_name) {
      throw UpdateRefused(options.model_dir.string() + ": image " + std::to_string(image.image_id) +
                          " is '" + std::string(child.ImageName(image)) + "' in the model and '" +
                          old_name + "' in the index: not the model the index was built from" +
                          kFullBuildNeeded);
    }
    if (!SameCamera(parent.cameras()[old_image.camera_index], child.cameras[image.camera_index])) {
      throw UpdateRefused(options.model_dir.string() + ": the camera of image '" + old_name +
                          "' changed (intrinsics refined again?)" + kFullBuildNeeded);
    }
    const double shift = (CameraCenterOf(old_image) - CameraCenterOf(image)).norm();
    const double turn =
        TurnRadians(old_image.cam_from_world_rotation, image.cam_from_world_rotation);
    if (shift > kMaxCentreShift * extent || turn > kMaxPoseTurnRadians) {
      char text[160];
      std::snprintf(text, sizeof(text),
                    "' moved by %.3g (%.2g of the cameras' extent) and turned %.3g degrees", shift,
                    shift / extent, turn * 180 / M_PI);
      throw UpdateRefused(options.model_dir.string() + ": the pose of image '" + old_name + text +
                          ": the model was adjusted again, not grown" + kFullBuildNeeded);
    }
    child_of_parent_image[i] = found->second;
    parent_of_child_image[found->second] = i;
  }
}

// Views of the old images: the parent's rows found again, in order, among the image's: by
// descriptor, or in a compact index (which stores none) by point id. Sets match's view rows and
// which images changed; a full index's view found nowhere must be in the database.
void MatchViews(const IndexUpdateOptions& options, const Index& parent, const GrownModel& grown,
                const colmap::DatabaseReader& database, Correspondence* match) {
  const ModelViews& child = grown.views;
  const std::span<const uint8_t> parent_descriptors = parent.descriptors();
  const std::span<const IndexImage> parent_images = parent.images();
  const std::vector<uint32_t>& child_of_parent_image = match->child_of_parent_image;
  const auto same_view = [&](uint32_t parent_view, uint32_t child_view) {
    if (parent.coded()) {
      return parent.point_ids()[parent.view_points()[parent_view]] ==
             child.point_ids[child.view_points[child_view]];
    }
    return std::memcmp(Row(parent_descriptors, parent_view), Row(child.descriptors, child_view),
                       kDescriptorBytes) == 0;
  };
  std::vector<uint32_t>& child_of_parent_view = match->child_of_parent_view;
  std::vector<uint32_t>& parent_of_child_view = match->parent_of_child_view;
  std::vector<bool>& image_changed = match->image_changed;
  child_of_parent_view.assign(parent.num_views(), kRemovedRow);
  parent_of_child_view.assign(child.num_views(), kRemovedRow);
  image_changed.assign(child.images.size(), true);
  for (uint32_t i = 0; i < parent_images.size(); ++i) {
    if (child_of_parent_image[i] == kRemovedRow) continue;
    const IndexImage& old_image = parent_images[i];
    const IndexImage& image = child.images[child_of_parent_image[i]];
    std::vector<uint32_t> unmatched;
    // Rows the parent has (the gather left them unwritten): row for row.
    const bool copied = grown.rows_reused[i];
    if (copied && old_image.num_views != image.num_views)
      throw std::logic_error("update: an image whose rows the index has changed its views");
    for (uint32_t a = 0; copied && a < old_image.num_views; ++a) {
      child_of_parent_view[old_image.first_view + a] = image.first_view + a;
      parent_of_child_view[image.first_view + a] = old_image.first_view + a;
    }
    for (uint32_t a = 0, b = 0; !copied && a < old_image.num_views; ++a) {
      uint32_t found = b;
      while (found < image.num_views &&
             !same_view(old_image.first_view + a, image.first_view + found))
        ++found;
      if (found == image.num_views) {
        unmatched.push_back(a);
        continue;
      }
      child_of_parent_view[old_image.first_view + a] = image.first_view + found;
      parent_of_child_view[image.first_view + found] = old_image.first_view + a;
      b = found + 1;
    }
    if (!unmatched.empty() && !parent.coded()) {
      // Observations the model dropped still have their descriptors in the database;
      // anything else means the database is not the one the index was built from.
      const colmap::Descriptors stored = database.ReadDescriptors(image.image_id);
      for (uint32_t a : unmatched) {
        bool found = false;
        for (uint32_t r = 0; r < stored.rows && !found; ++r)
          found = std::memcmp(stored.Row(r), Row(parent_descriptors, old_image.first_view + a),
                              kDescriptorBytes) == 0;
        if (!found) {
          throw UpdateRefused(options.database_path.string() + ": the descriptors of image '" +
                              std::string(parent.ImageName(old_image)) +
                              "' differ from those the index was built from" + kFullBuildNeeded);
        }
      }
    }
    image_changed[child_of_parent_image[i]] =
        !(old_image.num_views == image.num_views && unmatched.empty());
  }
}

// Points: by their COLMAP ids, which ascend in both.
void MatchPoints(const Index& parent, const ModelViews& child, Correspondence* match) {
  const std::span<const uint64_t> parent_point_ids = parent.point_ids();
  std::vector<uint32_t>& child_of_parent_point = match->child_of_parent_point;
  std::vector<uint32_t>& parent_of_child_point = match->parent_of_child_point;
  child_of_parent_point.assign(parent.num_points(), kRemovedRow);
  parent_of_child_point.assign(child.points.size(), kRemovedRow);
  for (uint32_t p = 0, q = 0; p < parent_point_ids.size() && q < child.point_ids.size();) {
    if (parent_point_ids[p] < child.point_ids[q]) {
      ++p;
    } else if (child.point_ids[q] < parent_point_ids[p]) {
      ++q;
    } else {
      child_of_parent_point[p] = q;
      parent_of_child_point[q] = p;
      ++p, ++q;
    }
  }
}

}  // namespace

Correspondence MatchToParent(const IndexUpdateOptions& options, const Index& parent,
                             const GrownModel& grown, const colmap::DatabaseReader& database) {
  Correspondence match;
  MatchImages(options, parent, grown.views, &match);
  MatchViews(options, parent, grown, database, &match);
  MatchPoints(parent, grown.views, &match);
  return match;
}

}  // namespace cwloc
