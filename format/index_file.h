#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "base/error.h"
#include "format/index_layout.h"

namespace cwloc {

// A read-only memory mapping of an index file (and its descriptor, open while it lives). Open()
// costs O(number of sections): it checks the header, its checksum, the section table and every
// section's bounds, alignment and size, never touching the big arrays. Section contents are
// checked where they are used, and fully by VerifyChecksums() (and the indexer's verify command).
// What a container file holds: a cwloc index, or a delta between two (delta/delta_file.h).
// Both share the header, the section table and their checksums; the magic tells them apart.
struct ContainerKind {
  const char* magic;  // 8 characters
  const char* name;   // "cwloc index": "not a cwloc index (wrong magic ...)"
  const char* noun;   // "index": "index format 2.0 is not readable ..."
  uint16_t major;     // the one major version a reader reads
  uint16_t max_minor;
  const char* remedy;                    // what to do about a major this cwloc does not read
  std::span<const uint32_t> known_tags;  // a required section with another tag is refused
};
inline constexpr ContainerKind kIndexContainer{
    "CWLOCIDX",   "cwloc index", "index",
    kFormatMajor, kFormatMinor,  "rebuild the index with this cwloc-index",
    section::kAll};

class IndexFile {
 public:
  static IndexFile Open(const std::filesystem::path& path,
                        const ContainerKind& kind = kIndexContainer);
  IndexFile(IndexFile&& other) noexcept;
  IndexFile& operator=(IndexFile&& other) noexcept;
  ~IndexFile();

  const std::filesystem::path& path() const { return path_; }
  const FileHeader& header() const { return *reinterpret_cast<const FileHeader*>(data_); }
  std::span<const SectionEntry> sections() const { return sections_; }
  std::span<const uint8_t> bytes() const { return {data_, size_}; }

  // nullptr when the file has no such section.
  const SectionEntry* FindSection(uint32_t tag) const;

  // The section's elements as T. Throws InputError when the section is missing or its element
  // size is not sizeof(T).
  template <typename T>
  std::span<const T> Section(uint32_t tag) const {
    const SectionEntry& entry = RequireSection(tag, sizeof(T));
    return {reinterpret_cast<const T*>(data_ + entry.offset), static_cast<size_t>(entry.count)};
  }
  // The same as bytes, for elements of `element_size` bytes.
  std::span<const uint8_t> SectionBytes(uint32_t tag, size_t element_size) const {
    const SectionEntry& entry = RequireSection(tag, element_size);
    return {data_ + entry.offset, static_cast<size_t>(entry.size)};
  }

  // Recomputes every section checksum; throws InputError naming the first corrupt section.
  void VerifyChecksums() const;
  // The same for the sections whose tag `which` accepts.
  void VerifyChecksums(const std::function<bool(uint32_t tag)>& which) const;

  // Maps every page of the file in one call, for a reader about to touch most of it (update,
  // apply): one page fault at a time costs seconds on a multi-GB index. Reads what the page cache
  // lacks. A no-op where the kernel cannot (before Linux 5.14).
  void MapAllPages() const;

 private:
  IndexFile() = default;
  const SectionEntry& RequireSection(uint32_t tag, size_t element_size) const;
  void Unmap();

  std::filesystem::path path_;
  const uint8_t* data_ = nullptr;
  size_t size_ = 0;
  std::span<const SectionEntry> sections_;
  int fd_ = -1;  // kept for VerifyChecksums' reads
};

// One section to write: its bytes are copied into the file at a 64-byte aligned offset.
struct SectionData {
  uint32_t tag = 0;
  uint32_t flags = 0;
  uint32_t element_size = 1;
  uint64_t count = 0;
  std::span<const uint8_t> bytes{};  // count * element_size bytes, unless `pieces` has them
  // The bytes in order, when they are not one span (a child's descriptors: the parent's kept
  // runs and the new rows between them, written from where they are).
  std::vector<std::span<const uint8_t>> pieces{};
};

// The format minor a file with these sections declares: the oldest 1.x that knows them all
// (at least 1.1; format/index_section_table.inc says which minor introduced each section).
uint16_t FormatMinorOf(std::span<const SectionData> sections);

// Writes an index (or a delta) atomically through an AtomicFile (base/atomic_file.h: an unnamed
// temporary file in the target directory, fsync, put in place), in steps so that its leading
// sections (a full index's descriptors, three quarters of its bytes, then the other rows) go to
// the disk while the caller still composes the rest: the constructor and WriteAhead write them,
// on a second thread when `background`; Finish writes the rest, the section table and the
// header, and puts the file in place. Destroyed unfinished (an exception), it leaves nothing. The
// leading sections' bytes must stay alive until Finish. The output depends only on the sections
// (padding is zero), so equal input gives equal bytes.
class IndexFileWriter {
 public:
  IndexFileWriter(const std::filesystem::path& path, std::vector<SectionData> leading,
                  bool background);
  ~IndexFileWriter();
  // More leading sections, written after those given before (a batch known later).
  void WriteAhead(std::vector<SectionData> sections, bool background);
  IndexFileWriter(const IndexFileWriter&) = delete;
  IndexFileWriter& operator=(const IndexFileWriter&) = delete;

  // `sections`: the whole file's, those written ahead first (std::logic_error when not).
  // `kind` and `minor` set the header (an index's minor is FormatMinorOf its sections). Returns
  // the header checksum; with `expected_checksum`, a different one is refused (InputError) and
  // nothing is put in place.
  uint64_t Finish(std::span<const SectionData> sections, const ContainerKind& kind, uint16_t minor,
                  std::optional<uint64_t> expected_checksum);

 private:
  struct State;
  std::unique_ptr<State> state_;
};

// The one-step write: every section given to IndexFileWriter at once, then finished.
uint64_t WriteIndexFile(const std::filesystem::path& path, std::span<const SectionData> sections,
                        const ContainerKind& kind = kIndexContainer, uint16_t minor = 0,
                        std::optional<uint64_t> expected_checksum = std::nullopt);

// Recomputes, in memory, every section checksum of a container whose table lies inside
// `bytes`, then the table's and the header's (a section outside the bytes keeps its checksum):
// what an edit that must get past the checksums does, as the corruption sweeps and the
// fuzzers make edits.
void RecomputeChecksums(std::span<uint8_t> bytes);

template <typename T>
SectionData MakeSection(uint32_t tag, std::span<const T> elements,
                        uint32_t flags = kSectionRequired) {
  return {tag,
          flags,
          static_cast<uint32_t>(sizeof(T)),
          elements.size(),
          {reinterpret_cast<const uint8_t*>(elements.data()), elements.size_bytes()}};
}

}  // namespace cwloc
