#pragma once

// An index's arrays, one member per line of the section table (format/index_section_table.inc):
// IndexRows borrows them (what Index reads in place, and what every writer writes), and
// OwnedIndexRows holds them for a producer that composes them (the build's model views, a tile,
// a delta's child), which then lends them out as IndexRows.

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "base/huge_pages.h"
#include "format/index_file.h"
#include "format/index_section_table.h"
#include "format/index_sections.h"
#include "kdtree/kd_forest.h"
#include "kdtree/kd_forest_builder.h"

namespace cwloc {

// Every array an index stores, borrowed. A full index fills `points`, `descriptors` and
// `view_neighbor_distances`, a compact one (code_bytes != 0) `point_origin`, `point_offsets`,
// `codebook`, `codes` and `point_neighbor_distances`; an optional section is written when its
// member is not empty.
struct IndexRows {
#define CWLOC_INDEX_SECTION(name, tag, minor, presence, element, member, ...) \
  std::span<const RowValue<element>> member;
#include "format/index_section_table.inc"
#undef CWLOC_INDEX_SECTION
  uint32_t code_bytes = 0;  // PCOD's element size; 0: a full index
  // DESC's bytes in order, when they are not one span (an applied delta's: the parent's kept
  // runs and the delta's new rows, written from where they are); `descriptors` is then empty.
  std::span<const std::span<const uint8_t>> descriptor_pieces;

  bool compact() const { return code_bytes != 0; }
  size_t num_views() const { return view_points.size(); }
};

// A member's storage: what an owner's resize() leaves unwritten (a producer writes every row, and
// a big array nothing writes is never backed: base/huge_pages.h); text as a string.
template <typename T>
struct OwnedRowsOf {
  using type = std::vector<T, UnwrittenAllocator<T>>;
};
template <>
struct OwnedRowsOf<char> {
  using type = std::string;
};
template <typename T>
using OwnedRows = typename OwnedRowsOf<T>::type;

// The same members, owned.
struct OwnedIndexRows {
#define CWLOC_INDEX_SECTION(name, tag, minor, presence, element, member, ...) \
  OwnedRows<RowValue<element>> member;
#include "format/index_section_table.inc"
#undef CWLOC_INDEX_SECTION
  uint32_t code_bytes = 0;

  size_t num_views() const { return view_points.size(); }
  // Every member lent out.
  IndexRows Borrow() const;
};

// KDND, KDRT and KDLF: a kd-forest built or updated in memory.
void BorrowKdForest(const KdForest& forest, IndexRows* rows);

// The sections a child (a tile, a delta's child) takes whole from its parent (kParents: a
// compact index's origin and codebook, GEOR, PCAL), and its code size.
void TakeParentsSections(const IndexRows& parent, IndexRows* child);

// The sections of an index with these rows, in the file's order: those its kind holds (an
// optional one when not empty). With `batch`, that batch's alone: a full index's descriptors
// and the rows of points and views, which an IndexFileWriter can write ahead, need neither the
// manifest nor the kd-forest nor the co-visibility graph. Its format version is FormatMinorOf
// the sections.
std::vector<SectionData> IndexSectionsOf(const IndexRows& rows,
                                         std::optional<SectionBatch> batch = std::nullopt);

}  // namespace cwloc
