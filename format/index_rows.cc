#include "format/index_rows.h"

namespace cwloc {

IndexRows OwnedIndexRows::Borrow() const {
  IndexRows rows;
#define CWLOC_INDEX_SECTION(name, tag, minor, presence, element, member, ...) rows.member = member;
#include "format/index_section_table.inc"
#undef CWLOC_INDEX_SECTION
  rows.code_bytes = code_bytes;
  return rows;
}

void BorrowKdForest(const KdForest& forest, IndexRows* rows) {
  rows->kd_nodes = forest.nodes;
  rows->kd_roots = forest.roots;
  rows->kd_leaves = forest.leaves;
}

void TakeParentsSections(const IndexRows& parent, IndexRows* child) {
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    if (spec.child == SectionInChild::kParents) spec.borrow(spec.bytes(parent), child);
  }
  child->code_bytes = parent.code_bytes;
}

std::vector<SectionData> IndexSectionsOf(const IndexRows& rows, std::optional<SectionBatch> batch) {
  std::vector<SectionData> sections;
  for (const IndexSectionSpec& spec : IndexSectionTable()) {
    if ((batch && spec.batch != *batch) || !spec.InIndexOfKind(rows.compact())) continue;
    SectionData section{spec.tag, spec.optional() ? 0 : kSectionRequired, spec.ElementBytes(rows),
                        0, spec.bytes(rows)};
    uint64_t bytes = section.bytes.size();
    if (spec.tag == section::kDescriptors && !rows.descriptor_pieces.empty()) {
      section.pieces.assign(rows.descriptor_pieces.begin(), rows.descriptor_pieces.end());
      bytes = 0;
      for (const std::span<const uint8_t> piece : section.pieces) bytes += piece.size();
    }
    // An optional section is written when there is something in it.
    if (spec.optional() && bytes == 0) continue;
    section.count = bytes / section.element_size;
    sections.push_back(std::move(section));
  }
  return sections;
}

}  // namespace cwloc
