#pragma once

// The delta between an index and a child made of it (`cwloc-index update` from a grown model,
// `extract --parent-tile` from an updated index): the child's arrays, and which parent row each
// child view and point is. AppliedDelta (apply_delta.h) composes the child back from the parent
// and the delta; the caller sets the header's child checksum and forest fields.

#include <cstdint>
#include <span>
#include <string_view>
#include <vector>

#include "delta/delta_file.h"
#include "format/index.h"
#include "format/index_rows.h"
#include "kdtree/kd_forest_update.h"

namespace cwloc {

// Borrowed: the child's rows, and each child view's and point's parent row (kRemovedRow: a new
// one). A compact parent's child (codes per point) has no descriptors, and gives its points'
// positions in `rows.points` beside their offsets.
struct DeltaChild {
  IndexRows rows;
  std::span<const uint32_t> parent_of_view;
  std::span<const uint32_t> parent_of_point;
};

// A kept point moved when its position differs: a compact index compares the float offsets
// from its origin it stores, so a point moves when its offset's bits change.
bool PointMoved(const Index& parent, uint32_t parent_point, const IndexPoint& child_point);

// A compact child point's offset from the parent's origin, as apply stores it.
std::array<float, 3> OffsetFrom(const IndexPointOrigin& origin, const IndexPoint& point);

// A compact child's codes (points x code bytes): the parent's for a kept point, the next of
// `new_codes` for a new one (kRemovedRow in `parent_of_point`), in row order.
OwnedRows<uint8_t> ChildCodes(const DescriptorCodes& parent,
                              std::span<const uint32_t> parent_of_point,
                              std::span<const uint8_t> new_codes);

// The delta's rows and small sections; its header names the parent.
IndexDelta MakeDelta(const Index& parent, const DeltaChild& child);

}  // namespace cwloc
