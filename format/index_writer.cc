#include <algorithm>
#include <cstring>
#include <vector>

#include "base/atomic_file.h"
#include "format/index_file.h"
#include "format/xxhash64.h"

namespace cwloc {
namespace {

uint64_t AlignUp(uint64_t value) {
  return (value + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment;
}

// A section's bytes in order: its pieces, or its one span.
std::span<const std::span<const uint8_t>> PiecesOf(const SectionData& section) {
  if (!section.pieces.empty()) return section.pieces;
  return {&section.bytes, 1};
}

}  // namespace

uint16_t FormatMinorOf(std::span<const SectionData> sections) {
  uint16_t minor = 1;
  for (const SectionData& section : sections) {
    if (section.tag == section::kCodebook || section.tag == section::kPointCodes ||
        section.tag == section::kPointNeighbor || section.tag == section::kPointOrigin ||
        section.tag == section::kPointOffsets)
      minor = std::max<uint16_t>(minor, 2);
    if (section.tag == section::kCovarianceCalibration) minor = std::max<uint16_t>(minor, 3);
    if (section.tag == section::kPointColors) minor = std::max<uint16_t>(minor, 4);
    if (section.tag == section::kPointIds) minor = std::max<uint16_t>(minor, 5);
  }
  return minor;
}

// From this size on, an index is written past the page cache.
constexpr uint64_t kBypassPageCacheBytes = uint64_t{64} << 20;

uint64_t WriteIndexFile(const std::filesystem::path& path, std::span<const SectionData> sections,
                        const ContainerKind& kind, uint16_t minor,
                        std::optional<uint64_t> expected_checksum) {
  std::vector<SectionEntry> table(sections.size());
  uint64_t offset = sizeof(FileHeader);
  for (size_t i = 0; i < sections.size(); ++i) {
    const SectionData& section = sections[i];
    XxHash64Stream hash;
    uint64_t size = 0;
    for (const std::span<const uint8_t> piece : PiecesOf(section)) {
      hash.Update(piece);
      size += piece.size();
    }
    if (size != section.count * section.element_size || section.element_size == 0) {
      throw std::logic_error("WriteIndexFile: section '" + SectionTagName(section.tag) +
                             "' bytes do not match count * element_size");
    }
    SectionEntry& entry = table[i];
    std::memset(&entry, 0, sizeof(entry));
    entry.tag = section.tag;
    entry.flags = section.flags;
    entry.offset = AlignUp(offset);
    entry.size = size;
    entry.count = section.count;
    entry.element_size = section.element_size;
    entry.checksum = hash.Digest();
    offset = entry.offset + entry.size;
  }
  const uint64_t table_offset = AlignUp(offset);
  const uint64_t table_bytes = table.size() * sizeof(SectionEntry);

  FileHeader header;
  std::memset(&header, 0, sizeof(header));
  std::memcpy(header.magic, kind.magic, sizeof(header.magic));
  header.byte_order_mark = kByteOrderMark;
  header.format_major = kind.major;
  header.format_minor = &kind == &kIndexContainer ? FormatMinorOf(sections) : minor;
  header.header_size = sizeof(FileHeader);
  header.section_entry_size = sizeof(SectionEntry);
  header.file_size = table_offset + table_bytes;
  header.section_table_offset = table_offset;
  header.section_count = static_cast<uint32_t>(table.size());
  header.section_table_checksum =
      XxHash64({reinterpret_cast<const uint8_t*>(table.data()), table_bytes});
  header.header_checksum =
      XxHash64({reinterpret_cast<const uint8_t*>(&header), offsetof(FileHeader, header_checksum)});
  if (expected_checksum && *expected_checksum != header.header_checksum) {
    throw InputError(path.string() + ": not written: its header checksum would be " +
                     HashHex(header.header_checksum) + ", not the expected " +
                     HashHex(*expected_checksum));
  }

  AtomicFile file(path);
  // A big index is not read back by its writer: its pages need not pass the page cache (the
  // city's 1.9 GB updated index wrote and synced in 2.2-2.7 s instead of 3.3-3.8 s).
  if (header.file_size >= kBypassPageCacheBytes) file.BypassPageCache();
  static constexpr uint8_t kZeros[kSectionAlignment] = {};
  file.Write(reinterpret_cast<const uint8_t*>(&header), sizeof(header));
  uint64_t written = sizeof(header);
  for (size_t i = 0; i < sections.size(); ++i) {
    file.Write(kZeros, table[i].offset - written);
    for (const std::span<const uint8_t> piece : PiecesOf(sections[i]))
      file.Write(piece.data(), piece.size());
    written = table[i].offset + table[i].size;
  }
  file.Write(kZeros, table_offset - written);
  file.Write(reinterpret_cast<const uint8_t*>(table.data()), table_bytes);
  file.Commit();
  return header.header_checksum;
}

void RecomputeChecksums(std::span<uint8_t> bytes) {
  if (bytes.size() < sizeof(FileHeader)) return;
  FileHeader header;
  std::memcpy(&header, bytes.data(), sizeof(header));
  const uint64_t table = header.section_table_offset;
  const uint64_t count = header.section_count;
  if (table > bytes.size() || count > (bytes.size() - table) / sizeof(SectionEntry)) return;
  for (uint64_t i = 0; i < count; ++i) {
    SectionEntry entry;
    std::memcpy(&entry, &bytes[table + i * sizeof(entry)], sizeof(entry));
    if (entry.offset > bytes.size() || entry.size > bytes.size() - entry.offset) continue;
    entry.checksum = XxHash64(bytes.subspan(entry.offset, entry.size));
    std::memcpy(&bytes[table + i * sizeof(entry)], &entry, sizeof(entry));
  }
  header.section_table_checksum = XxHash64(bytes.subspan(table, count * sizeof(SectionEntry)));
  header.header_checksum =
      XxHash64({reinterpret_cast<const uint8_t*>(&header), offsetof(FileHeader, header_checksum)});
  std::memcpy(bytes.data(), &header, sizeof(header));
}

}  // namespace cwloc
