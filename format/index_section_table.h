#pragma once

// The section table (format/index_section_table.inc) as data: what the writer
// (IndexSectionsOf), the reader (Index::Open), `cwloc-index verify` and `info`, and the tiles and
// delta children made of an index (`extract`, `update`, `apply`) know of each section.

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>
#include <type_traits>

#include "format/index_layout.h"

namespace cwloc {

struct IndexRows;
struct OwnedIndexRows;

// Which index holds the section; a compact index is one with PCOD.
enum class SectionPresence { kRequired, kFullIndex, kCompactIndex, kOptional };
// Its element count, which Index::Open checks (kAny: where it matters, by hand).
enum class SectionCount { kOne, kPerView, kPerPoint, kAny };
// What a tile and a delta's child hold of it.
enum class SectionInChild { kKeptWithRow, kParents, kMade };
// Which of the writer's batches writes it (IndexFileWriter writes the first two ahead).
enum class SectionBatch { kDescriptorBatch, kRowBatch, kLastBatch };

// An IndexRows member's value type: an array element's (DESC and PCOD are spans of bytes), else
// the element itself.
template <typename Element>
struct RowValueOf {
  using type = Element;
};
template <typename T, size_t N>
struct RowValueOf<T[N]> {
  using type = T;
};
template <typename T>
struct RowValueOf<T[]> {
  using type = T;
};
template <typename Element>
using RowValue = typename RowValueOf<Element>::type;

// Bytes per element; 0 for an array whose size the rows give (uint8_t[]: PCOD's code_bytes).
template <typename Element>
constexpr uint32_t ElementBytesOf() {
  if constexpr (std::is_unbounded_array_v<Element>) {
    return 0;
  } else {
    return sizeof(Element);
  }
}

struct IndexSectionSpec {
  uint32_t tag;
  uint16_t minor;
  SectionPresence presence;
  uint32_t element_bytes;  // 0: IndexRows::code_bytes
  SectionCount count;
  SectionInChild child;
  SectionBatch batch;
  std::string_view help;
  // The member's bytes.
  std::span<const uint8_t> (*bytes)(const IndexRows& rows);
  // Points the member at `bytes` (whole elements, aligned for them).
  void (*borrow)(std::span<const uint8_t> bytes, IndexRows* rows);
  // The owned member resized to `elements` elements of `element_bytes`, as bytes to write.
  std::span<uint8_t> (*resize)(size_t elements, uint32_t element_bytes, OwnedIndexRows* rows);

  // Whether an index of this kind (compact: with PCOD) may hold the section.
  bool InIndexOfKind(bool compact) const {
    return presence != (compact ? SectionPresence::kFullIndex : SectionPresence::kCompactIndex);
  }
  bool optional() const { return presence == SectionPresence::kOptional; }
  // The section's element size for these rows.
  uint32_t ElementBytes(const IndexRows& rows) const;
};

// Every section, in the file's order.
std::span<const IndexSectionSpec> IndexSectionTable();

// The section with this tag; nullptr for a tag this cwloc does not know.
const IndexSectionSpec* FindIndexSection(uint32_t tag);

}  // namespace cwloc
