#include "delta/make_delta.h"

#include <cstring>
#include <vector>

#include "kdtree/kd_forest_update.h"

namespace cwloc {
namespace {

// Appends child row `child` taken from parent row `parent` to `runs`, joining a run that ends
// where this one starts.
void AddRun(std::vector<RowRun>* runs, uint32_t child, uint32_t parent) {
  if (!runs->empty()) {
    RowRun& last = runs->back();
    if (last.child_first + last.count == child && last.parent_first + last.count == parent) {
      ++last.count;
      return;
    }
  }
  runs->push_back({child, parent, 1});
}

bool SameBits(float a, float b) { return std::memcmp(&a, &b, sizeof(float)) == 0; }

}  // namespace

std::array<float, 3> OffsetFrom(const IndexPointOrigin& origin, const IndexPoint& point) {
  return {float(point.xyz[0] - origin.xyz[0]), float(point.xyz[1] - origin.xyz[1]),
          float(point.xyz[2] - origin.xyz[2])};
}

bool PointMoved(const Index& parent, uint32_t parent_point, const IndexPoint& child_point) {
  if (parent.coded()) {
    return std::memcmp(OffsetFrom(parent.point_origin(), child_point).data(),
                       parent.point_offsets()[parent_point].offset, sizeof(float) * 3) != 0;
  }
  return std::memcmp(parent.PointXyz(parent_point).data(), child_point.xyz,
                     sizeof(child_point.xyz)) != 0;
}

OwnedRows<uint8_t> ChildCodes(const DescriptorCodes& parent,
                              std::span<const uint32_t> parent_of_point,
                              std::span<const uint8_t> new_codes) {
  const uint32_t code_bytes = parent.code_bytes;
  OwnedRows<uint8_t> codes(parent_of_point.size() * code_bytes);
  size_t next_new = 0;
  for (size_t p = 0; p < parent_of_point.size(); ++p) {
    const uint32_t from = parent_of_point[p];
    const uint8_t* code =
        from != kRemovedRow ? parent.Code(from) : &new_codes[next_new++ * code_bytes];
    std::memcpy(&codes[p * code_bytes], code, code_bytes);
  }
  return codes;
}

IndexDelta MakeDelta(const Index& parent, const DeltaChild& child) {
  const IndexRows& rows = child.rows;
  IndexDelta delta;
  delta.header.parent_checksum = parent.file().header().header_checksum;
  delta.header.parent_file_size = parent.file().header().file_size;
  delta.cameras.assign(rows.cameras.begin(), rows.cameras.end());
  delta.images.assign(rows.images.begin(), rows.images.end());
  delta.strings.assign(rows.strings.begin(), rows.strings.end());
  const bool coded = parent.coded();
  const uint32_t code_bytes = parent.codes().code_bytes;
  delta.code_bytes = code_bytes;
  const bool keypoints = !parent.view_keypoints().empty();
  const bool colors = !parent.point_colors().empty();
  const bool ids = !parent.point_ids().empty();

  std::vector<uint32_t> child_of_parent_point(parent.num_points(), kRemovedRow);
  for (uint32_t q = 0; q < rows.points.size(); ++q) {
    const uint32_t from = child.parent_of_point[q];
    if (from == kRemovedRow) {
      const IndexPoint& point = rows.points[q];
      delta.new_points.push_back(IndexPoint{{point.xyz[0], point.xyz[1], point.xyz[2]}, 0, 0});
      if (ids) delta.new_point_ids.push_back(rows.point_ids[q]);
      if (colors) delta.new_point_colors.push_back(rows.point_colors[q]);
      if (coded) {
        const uint8_t* code = &rows.codes[size_t(q) * code_bytes];
        delta.new_point_codes.insert(delta.new_point_codes.end(), code, code + code_bytes);
        delta.new_view_neighbors.push_back(rows.point_neighbor_distances[q]);
      }
      continue;
    }
    child_of_parent_point[from] = q;
    AddRun(&delta.point_runs, q, from);
    if (PointMoved(parent, from, rows.points[q])) {
      const IndexPoint& point = rows.points[q];
      delta.point_moves.push_back({q, 0, {point.xyz[0], point.xyz[1], point.xyz[2]}});
    }
    if (colors && std::memcmp(&parent.point_colors()[from], &rows.point_colors[q], 3) != 0)
      delta.point_color_changes.push_back({q, rows.point_colors[q], 0});
    if (coded &&
        !SameBits(rows.point_neighbor_distances[q], parent.point_neighbor_distances()[from]))
      delta.view_neighbor_changes.push_back({q, rows.point_neighbor_distances[q]});
  }

  for (uint32_t w = 0; w < rows.view_points.size(); ++w) {
    const uint32_t v = child.parent_of_view[w];
    if (v == kRemovedRow) {
      if (!coded) {
        const uint8_t* row = &rows.descriptors[size_t(w) * kDescriptorBytes];
        delta.new_descriptors.insert(delta.new_descriptors.end(), row, row + kDescriptorBytes);
        delta.new_view_neighbors.push_back(rows.view_neighbor_distances[w]);
      }
      delta.new_view_points.push_back(rows.view_points[w]);
      if (keypoints) delta.new_view_keypoints.push_back(rows.view_keypoints[w]);
      continue;
    }
    AddRun(&delta.view_runs, w, v);
    if (child_of_parent_point[parent.view_points()[v]] != rows.view_points[w])
      delta.view_point_changes.push_back({w, rows.view_points[w]});
    if (!coded && !SameBits(rows.view_neighbor_distances[w], parent.view_neighbor_distances()[v]))
      delta.view_neighbor_changes.push_back({w, rows.view_neighbor_distances[w]});
  }
  return delta;
}

}  // namespace cwloc
