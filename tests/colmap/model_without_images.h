#pragma once
// A COLMAP model without some of its images, as `colmap image_deleter` leaves it: the tests'
// "old" model, of which the model itself is the grown one (cwloc-index update).
#include <set>

#include "colmap/reconstruction.h"

namespace cwloc::test {

// The images' observations go, and so does every point left with fewer than two.
inline colmap::Reconstruction ModelWithoutImages(colmap::Reconstruction model,
                                                 const std::set<image_t>& ids) {
  for (image_t id : ids) model.images.erase(id);
  for (auto it = model.points3D.begin(); it != model.points3D.end();) {
    std::vector<colmap::TrackElement>& track = it->second.track;
    std::erase_if(track, [&](const colmap::TrackElement& e) { return ids.count(e.image_id) > 0; });
    if (track.size() >= 2) {
      ++it;
      continue;
    }
    for (const colmap::TrackElement& e : track)
      model.images[e.image_id].points2D[e.point2D_idx].point3D_id = kInvalidPoint3DId;
    it = model.points3D.erase(it);
  }
  return model;
}

}  // namespace cwloc::test
