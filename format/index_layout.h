#pragma once

// The on-disk structures of a cwloc index file (docs/format.md is the byte-level spec).
// All integers are little-endian and fixed-width; structs are read in place from the mapping.

#include <algorithm>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace cwloc {

static_assert(
    std::endian::native == std::endian::little,
    "cwloc index files are little-endian and read in place; big-endian hosts are not supported");

inline constexpr uint32_t kByteOrderMark = 0x01020304;
inline constexpr uint16_t kFormatMajor = 1;
// The newest section's minor (format/index_section_table.inc): what this cwloc reads up to.
inline constexpr uint16_t kFormatMinor = std::max({
#define CWLOC_INDEX_SECTION(name, tag, minor, ...) uint16_t{minor},
#include "format/index_section_table.inc"
#undef CWLOC_INDEX_SECTION
});
inline constexpr uint64_t kSectionAlignment = 64;

// Feature bits: a reader refuses a file with a required bit it does not know.
inline constexpr uint64_t kKnownRequiredFeatures = 0;

struct FileHeader {
  char magic[8];                  // "CWLOCIDX"
  uint32_t byte_order_mark;       // kByteOrderMark
  uint16_t format_major;          // a reader refuses a major it does not know
  uint16_t format_minor;          // newer minors only add optional sections/fields
  uint32_t header_size;           // sizeof(FileHeader)
  uint32_t section_entry_size;    // sizeof(SectionEntry)
  uint64_t required_features;     // bits a reader must understand
  uint64_t optional_features;     // bits a reader may ignore
  uint64_t file_size;             // total bytes; a shorter file is truncated
  uint64_t section_table_offset;  // 64-byte aligned
  uint32_t section_count;
  uint32_t reserved0;               // zero
  uint64_t section_table_checksum;  // XXH64 of the section table bytes
  uint8_t reserved[48];             // zero
  uint64_t header_checksum;         // XXH64 of the bytes before this field
};
static_assert(sizeof(FileHeader) == 128);
static_assert(offsetof(FileHeader, section_table_offset) == 48);
static_assert(offsetof(FileHeader, header_checksum) == 120);

inline constexpr uint32_t kSectionRequired = 1u
                                             << 0;  // a reader that does not know the tag refuses

struct SectionEntry {
  uint32_t tag;           // four ASCII characters, e.g. "DESC"
  uint32_t flags;         // kSectionRequired
  uint64_t offset;        // from the start of the file, 64-byte aligned
  uint64_t size;          // bytes, excluding padding
  uint64_t count;         // number of elements
  uint32_t element_size;  // bytes per element; size == count * element_size
  uint32_t reserved;      // zero
  uint64_t checksum;      // XXH64 of the section's bytes
};
static_assert(sizeof(SectionEntry) == 48);
static_assert(offsetof(SectionEntry, checksum) == 40);

constexpr uint32_t SectionTag(const char (&name)[5]) {
  return uint32_t(uint8_t(name[0])) | (uint32_t(uint8_t(name[1])) << 8) |
         (uint32_t(uint8_t(name[2])) << 16) | (uint32_t(uint8_t(name[3])) << 24);
}

// The sections of format 1.x, one constant per line of the section table
// (format/index_section_table.inc; docs/format.md describes each one's layout).
namespace section {
#define CWLOC_INDEX_SECTION(name, tag, ...) inline constexpr uint32_t name = SectionTag(tag);
#include "format/index_section_table.inc"
#undef CWLOC_INDEX_SECTION
// Every tag this cwloc reads: a required section with another tag is refused.
inline constexpr uint32_t kAll[] = {
#define CWLOC_INDEX_SECTION(name, ...) name,
#include "format/index_section_table.inc"
#undef CWLOC_INDEX_SECTION
};
}  // namespace section

// "DESC" for a tag, with non-printable bytes escaped, for messages.
std::string SectionTagName(uint32_t tag);

}  // namespace cwloc
