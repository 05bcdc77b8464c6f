#include <algorithm>
#include <cstring>
#include <deque>
#include <future>
#include <vector>

#include "base/atomic_file.h"
#include "format/index_file.h"
#include "format/index_section_table.h"
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
  uint16_t minor = 1;  // what a full index without optional sections has declared since 1.1
  for (const SectionData& section : sections) {
    if (const IndexSectionSpec* spec = FindIndexSection(section.tag))
      minor = std::max(minor, spec->minor);
  }
  return minor;
}

namespace {

// From this size on, an index is written past the page cache (the leading sections' size, when
// they are written first).
constexpr uint64_t kBypassPageCacheBytes = uint64_t{64} << 20;

// The header is written last, over the first block, which the writer keeps: a file written past
// the page cache is replaced in whole blocks.
constexpr size_t kFirstBlockBytes = 4096;

uint64_t BytesOf(std::span<const SectionData> sections) {
  uint64_t bytes = 0;
  for (const SectionData& section : sections) bytes += section.count * section.element_size;
  return bytes;
}

}  // namespace

struct IndexFileWriter::State {
  explicit State(const std::filesystem::path& path) : file(path) {}

  // Bytes at the file's end, the first block's copied aside.
  void Append(const uint8_t* bytes, size_t size) {
    if (written < kFirstBlockBytes) {
      const size_t kept = std::min<size_t>(size, kFirstBlockBytes - written);
      std::memcpy(first_block + written, bytes, kept);
    }
    file.Write(bytes, size);
    written += size;
  }
  // A section at the next aligned offset, hashed as it is written (4 MiB at a time, which the
  // write reads again from the cache).
  SectionEntry WriteSection(const SectionData& section) {
    static constexpr uint8_t kZeros[kSectionAlignment] = {};
    SectionEntry entry;
    std::memset(&entry, 0, sizeof(entry));
    entry.tag = section.tag;
    entry.flags = section.flags;
    entry.offset = AlignUp(written);
    entry.count = section.count;
    entry.element_size = section.element_size;
    Append(kZeros, entry.offset - written);
    XxHash64Stream hash;
    constexpr size_t kChunk = size_t{4} << 20;
    for (const std::span<const uint8_t> piece : PiecesOf(section)) {
      for (size_t done = 0; done < piece.size(); done += kChunk) {
        const std::span<const uint8_t> chunk =
            piece.subspan(done, std::min(kChunk, piece.size() - done));
        hash.Update(chunk);
        Append(chunk.data(), chunk.size());
      }
      entry.size += piece.size();
    }
    if (entry.size != section.count * section.element_size || section.element_size == 0) {
      throw std::logic_error("WriteIndexFile: section '" + SectionTagName(section.tag) +
                             "' bytes do not match count * element_size");
    }
    entry.checksum = hash.Digest();
    return entry;
  }

  // The header's place, once: a file whose first bytes known are big bypasses the page cache
  // (it is not read back by its writer: the city's 1.9 GB updated index wrote and synced in
  // 2.2-2.7 s instead of 3.3-3.8 s).
  void Start(uint64_t bytes_known) {
    if (written != 0) return;
    if (bytes_known >= kBypassPageCacheBytes) file.BypassPageCache();
    const FileHeader blank{};
    Append(reinterpret_cast<const uint8_t*>(&blank), sizeof(blank));
  }

  AtomicFile file;
  uint64_t written = 0;
  uint8_t first_block[kFirstBlockBytes] = {};
  std::deque<std::vector<SectionData>> ahead;  // the batches WriteAhead was given
  std::vector<SectionEntry> table;
  std::future<void> ahead_written;  // the last background batch
};

IndexFileWriter::IndexFileWriter(const std::filesystem::path& path,
                                 std::vector<SectionData> leading, bool background)
    : state_(std::make_unique<State>(path)) {
  WriteAhead(std::move(leading), background);
}

void IndexFileWriter::WriteAhead(std::vector<SectionData> sections, bool background) {
  State& state = *state_;
  if (sections.empty()) return;
  const std::vector<SectionData>& batch = state.ahead.emplace_back(std::move(sections));
  const auto write_batch = [&state, &batch] {
    state.Start(BytesOf(batch));
    for (const SectionData& section : batch) state.table.push_back(state.WriteSection(section));
  };
  if (!background) {
    if (state.ahead_written.valid()) state.ahead_written.get();
    write_batch();
    return;
  }
  // After the batch before; synced there too: the disk takes half a second per GB to sync,
  // which Commit then saves.
  state.ahead_written = std::async(
      std::launch::async, [&state, write_batch, before = std::move(state.ahead_written)]() mutable {
        if (before.valid()) before.get();
        write_batch();
        state.file.Sync();
      });
}

IndexFileWriter::~IndexFileWriter() {
  if (state_ && state_->ahead_written.valid()) state_->ahead_written.wait();
}

uint64_t IndexFileWriter::Finish(std::span<const SectionData> sections, const ContainerKind& kind,
                                 uint16_t minor, std::optional<uint64_t> expected_checksum) {
  State& state = *state_;
  if (state.ahead_written.valid()) state.ahead_written.get();
  size_t num_ahead = 0;
  bool ahead_first = true;
  for (const std::vector<SectionData>& batch : state.ahead) {
    for (const SectionData& section : batch) {
      ahead_first = ahead_first && num_ahead < sections.size() &&
                    sections[num_ahead].tag == section.tag &&
                    sections[num_ahead].count == section.count &&
                    sections[num_ahead].element_size == section.element_size;
      ++num_ahead;
    }
  }
  if (!ahead_first)
    throw std::logic_error(
        "IndexFileWriter::Finish: the sections do not begin with those written ahead");
  state.Start(BytesOf(sections));
  for (const SectionData& section : sections.subspan(num_ahead))
    state.table.push_back(state.WriteSection(section));

  static constexpr uint8_t kZeros[kSectionAlignment] = {};
  const uint64_t table_offset = AlignUp(state.written);
  state.Append(kZeros, table_offset - state.written);
  const uint64_t table_bytes = state.table.size() * sizeof(SectionEntry);
  state.Append(reinterpret_cast<const uint8_t*>(state.table.data()), table_bytes);

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
  header.section_count = static_cast<uint32_t>(state.table.size());
  header.section_table_checksum =
      XxHash64({reinterpret_cast<const uint8_t*>(state.table.data()), table_bytes});
  header.header_checksum =
      XxHash64({reinterpret_cast<const uint8_t*>(&header), offsetof(FileHeader, header_checksum)});
  if (expected_checksum && *expected_checksum != header.header_checksum) {
    throw InputError(state.file.path().string() + ": not written: its header checksum would be " +
                     HashHex(header.header_checksum) + ", not the expected " +
                     HashHex(*expected_checksum));
  }
  std::memcpy(state.first_block, &header, sizeof(header));
  state.file.Overwrite(0, state.first_block, std::min<uint64_t>(state.written, kFirstBlockBytes));
  state.file.Commit();
  return header.header_checksum;
}

uint64_t WriteIndexFile(const std::filesystem::path& path, std::span<const SectionData> sections,
                        const ContainerKind& kind, uint16_t minor,
                        std::optional<uint64_t> expected_checksum) {
  return IndexFileWriter(path, {sections.begin(), sections.end()}, /*background=*/false)
      .Finish(sections, kind, minor, expected_checksum);
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
