#include "format/index_section_table.h"

#include "format/index_rows.h"

namespace cwloc {
namespace {

#define CWLOC_INDEX_SECTION(name, tag, minor, presence, element, member, count, child, batch,     \
                            help)                                                                 \
  IndexSectionSpec{                                                                               \
      section::name,                                                                              \
      minor,                                                                                      \
      SectionPresence::presence,                                                                  \
      ElementBytesOf<element>(),                                                                  \
      SectionCount::count,                                                                        \
      SectionInChild::child,                                                                      \
      SectionBatch::batch,                                                                        \
      help,                                                                                       \
      [](const IndexRows& r) {                                                                    \
        return std::span<const uint8_t>(reinterpret_cast<const uint8_t*>(r.member.data()),        \
                                        r.member.size_bytes());                                   \
      },                                                                                          \
      [](std::span<const uint8_t> bytes, IndexRows* r) {                                          \
        using Value = RowValue<element>;                                                          \
        r->member = {reinterpret_cast<const Value*>(bytes.data()), bytes.size() / sizeof(Value)}; \
      },                                                                                          \
      [](size_t elements, uint32_t element_size, OwnedIndexRows* r) {                             \
        using Value = RowValue<element>;                                                          \
        r->member.resize(elements* element_size / sizeof(Value));                                 \
        return std::span<uint8_t>(reinterpret_cast<uint8_t*>(r->member.data()),                   \
                                  r->member.size() * sizeof(Value));                              \
      }},
constexpr IndexSectionSpec kSpecs[] = {
#include "format/index_section_table.inc"
};
#undef CWLOC_INDEX_SECTION

}  // namespace

uint32_t IndexSectionSpec::ElementBytes(const IndexRows& rows) const {
  return element_bytes != 0 ? element_bytes : rows.code_bytes;
}

std::span<const IndexSectionSpec> IndexSectionTable() { return kSpecs; }

const IndexSectionSpec* FindIndexSection(uint32_t tag) {
  for (const IndexSectionSpec& spec : kSpecs) {
    if (spec.tag == tag) return &spec;
  }
  return nullptr;
}

}  // namespace cwloc
