#include "format/index_file.h"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <utility>
#include <vector>

#include "format/xxhash64.h"

namespace cwloc {
namespace {

std::string Describe(const SectionEntry& entry, size_t index) {
  return "section " + std::to_string(index) + " '" + SectionTagName(entry.tag) + "'";
}

// A required section with a tag this reader does not know means a newer writer.
bool IsKnownTag(const ContainerKind& kind, uint32_t tag) {
  return std::find(kind.known_tags.begin(), kind.known_tags.end(), tag) != kind.known_tags.end();
}

}  // namespace

std::string SectionTagName(uint32_t tag) {
  std::string name;
  for (int i = 0; i < 4; ++i) {
    const unsigned char c = static_cast<unsigned char>(tag >> (8 * i));
    if (c >= 0x20 && c < 0x7f) {
      name += static_cast<char>(c);
    } else {
      char escaped[5];
      std::snprintf(escaped, sizeof(escaped), "\\x%02x", c);
      name += escaped;
    }
  }
  return name;
}

IndexFile IndexFile::Open(const std::filesystem::path& path, const ContainerKind& kind) {
  const std::string name = path.string();
  // O_NONBLOCK: a named pipe opens at once, to be refused below, instead of waiting for a writer.
  const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC | O_NOCTTY | O_NONBLOCK);
  if (fd < 0) throw InputError(name + ": cannot open: " + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw InputError(name + ": not a regular file");
  }
  const auto file_size = static_cast<uint64_t>(st.st_size);
  if (file_size < sizeof(FileHeader)) {
    ::close(fd);
    throw InputError(name + ": truncated: " + std::to_string(file_size) +
                     " bytes, smaller than the " + std::to_string(sizeof(FileHeader)) +
                     "-byte header");
  }
  void* mapping = ::mmap(nullptr, file_size, PROT_READ, MAP_SHARED, fd, 0);
  if (mapping == MAP_FAILED) {
    const int error = errno;
    ::close(fd);
    throw InputError(name + ": cannot map: " + std::strerror(error));
  }

  IndexFile file;
  file.fd_ = fd;
  file.path_ = path;
  file.data_ = static_cast<const uint8_t*>(mapping);
  file.size_ = file_size;
  const FileHeader& header = file.header();

  if (std::memcmp(header.magic, kind.magic, sizeof(header.magic)) != 0) {
    throw InputError(name + ": not a " + kind.name + " (wrong magic; expected \"" +
                     std::string(kind.magic, sizeof(header.magic)) + "\")");
  }
  if (header.byte_order_mark != kByteOrderMark) {
    throw InputError(name + ": wrong byte-order mark 0x" + HashHex(header.byte_order_mark) +
                     " (expected 0x" + HashHex(kByteOrderMark) + ")");
  }
  if (header.format_major != kind.major) {
    throw InputError(name + ": " + kind.noun + " format " + std::to_string(header.format_major) +
                     "." + std::to_string(header.format_minor) +
                     " is not readable by this cwloc, which reads format " +
                     std::to_string(kind.major) + ".x (up to " + std::to_string(kind.major) + "." +
                     std::to_string(kind.max_minor) + "); " + kind.remedy +
                     (header.format_major > kind.major ? " or upgrade cwloc" : ""));
  }
  const uint64_t header_checksum = XxHash64({file.data_, offsetof(FileHeader, header_checksum)});
  if (header_checksum != header.header_checksum) {
    throw InputError(name + ": header checksum mismatch (stored " +
                     HashHex(header.header_checksum) + ", computed " + HashHex(header_checksum) +
                     "): the file is corrupt");
  }
  if (header.file_size != file_size) {
    throw InputError(name + ": truncated or extended: the header says " +
                     std::to_string(header.file_size) + " bytes, the file has " +
                     std::to_string(file_size));
  }
  if (header.header_size != sizeof(FileHeader) ||
      header.section_entry_size != sizeof(SectionEntry)) {
    throw InputError(name + ": header size " + std::to_string(header.header_size) +
                     " / section entry size " + std::to_string(header.section_entry_size) +
                     " (expected " + std::to_string(sizeof(FileHeader)) + " / " +
                     std::to_string(sizeof(SectionEntry)) + ")");
  }
  const uint64_t unknown_features = header.required_features & ~kKnownRequiredFeatures;
  if (unknown_features != 0) {
    throw InputError(name + ": requires features unknown to this cwloc (bits 0x" +
                     HashHex(unknown_features) + "); upgrade cwloc");
  }
  const uint64_t table_offset = header.section_table_offset;
  const uint64_t table_bytes = uint64_t{header.section_count} * sizeof(SectionEntry);
  if (table_offset % kSectionAlignment != 0 || table_offset < sizeof(FileHeader) ||
      table_offset > file_size || table_bytes > file_size - table_offset) {
    throw InputError(name + ": section table (offset " + std::to_string(table_offset) + ", " +
                     std::to_string(header.section_count) +
                     " entries) lies outside the file or is misaligned");
  }
  const uint64_t table_checksum = XxHash64({file.data_ + table_offset, table_bytes});
  if (table_checksum != header.section_table_checksum) {
    throw InputError(name + ": section table checksum mismatch (stored " +
                     HashHex(header.section_table_checksum) + ", computed " +
                     HashHex(table_checksum) + "): the file is corrupt");
  }
  file.sections_ = {reinterpret_cast<const SectionEntry*>(file.data_ + table_offset),
                    header.section_count};

  // Sections lie after the header, inside the file, aligned, in increasing order, without overlap.
  uint64_t previous_end = sizeof(FileHeader);
  for (size_t i = 0; i < file.sections_.size(); ++i) {
    const SectionEntry& entry = file.sections_[i];
    const std::string what = name + ": " + Describe(entry, i);
    if (entry.offset % kSectionAlignment != 0) {
      throw InputError(what + ": offset " + std::to_string(entry.offset) +
                       " is not 64-byte aligned");
    }
    if (entry.offset < previous_end || entry.offset > file_size ||
        entry.size > file_size - entry.offset) {
      throw InputError(what + ": bytes [" + std::to_string(entry.offset) + ", +" +
                       std::to_string(entry.size) +
                       ") overlap another section or lie outside the " + std::to_string(file_size) +
                       "-byte file");
    }
    if (entry.element_size == 0 || entry.count > entry.size / entry.element_size ||
        entry.count * entry.element_size != entry.size) {
      throw InputError(what + ": " + std::to_string(entry.size) + " bytes do not hold " +
                       std::to_string(entry.count) + " elements of " +
                       std::to_string(entry.element_size) + " bytes");
    }
    if ((entry.flags & kSectionRequired) && !IsKnownTag(kind, entry.tag)) {
      throw InputError(what + ": a required section unknown to this cwloc; upgrade cwloc");
    }
    previous_end = entry.offset + entry.size;
  }
  return file;
}

IndexFile::IndexFile(IndexFile&& other) noexcept { *this = std::move(other); }

IndexFile& IndexFile::operator=(IndexFile&& other) noexcept {
  if (this != &other) {
    Unmap();
    path_ = std::move(other.path_);
    data_ = std::exchange(other.data_, nullptr);
    size_ = std::exchange(other.size_, 0);
    sections_ = std::exchange(other.sections_, {});
    fd_ = std::exchange(other.fd_, -1);
  }
  return *this;
}

IndexFile::~IndexFile() { Unmap(); }

void IndexFile::Unmap() {
  if (data_ != nullptr) ::munmap(const_cast<uint8_t*>(data_), size_);
  data_ = nullptr;
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

const SectionEntry* IndexFile::FindSection(uint32_t tag) const {
  for (const SectionEntry& entry : sections_) {
    if (entry.tag == tag) return &entry;
  }
  return nullptr;
}

const SectionEntry& IndexFile::RequireSection(uint32_t tag, size_t element_size) const {
  const SectionEntry* entry = FindSection(tag);
  if (entry == nullptr) {
    throw InputError(path_.string() + ": section '" + SectionTagName(tag) + "' is missing");
  }
  if (entry->element_size != element_size) {
    throw InputError(path_.string() + ": section '" + SectionTagName(tag) + "' has " +
                     std::to_string(entry->element_size) + "-byte elements (expected " +
                     std::to_string(element_size) + ")");
  }
  return *entry;
}

void IndexFile::MapAllPages() const {
#ifdef MADV_POPULATE_READ
  ::madvise(const_cast<uint8_t*>(data_), size_, MADV_POPULATE_READ);
#endif
}

void IndexFile::VerifyChecksums() const {
  VerifyChecksums([](uint32_t) { return true; });
}

void IndexFile::VerifyChecksums(const std::function<bool(uint32_t tag)>& which) const {
  // Read, not hashed through the mapping: the kernel copies page-cache pages through its own
  // large mappings, where 4 KiB user pages cost a TLB miss each (3.5x slower on a VM).
  std::vector<uint8_t> chunk(size_t{4} << 20);
  for (size_t i = 0; i < sections_.size(); ++i) {
    const SectionEntry& entry = sections_[i];
    if (!which(entry.tag)) continue;
    XxHash64Stream hash;
    for (uint64_t done = 0; done < entry.size;) {
      const size_t want = size_t(std::min<uint64_t>(chunk.size(), entry.size - done));
      const ssize_t got = ::pread(fd_, chunk.data(), want, off_t(entry.offset + done));
      if (got < 0 && errno == EINTR) continue;
      if (got <= 0) {
        throw InputError(path_.string() + ": " + Describe(entry, i) + ": cannot read: " +
                         (got < 0 ? std::strerror(errno) : "the file was truncated"));
      }
      hash.Update({chunk.data(), size_t(got)});
      done += uint64_t(got);
    }
    const uint64_t checksum = hash.Digest();
    if (checksum != entry.checksum) {
      throw InputError(path_.string() + ": " + Describe(entry, i) + ": checksum mismatch (stored " +
                       HashHex(entry.checksum) + ", computed " + HashHex(checksum) +
                       "): the section is corrupt");
    }
  }
}

}  // namespace cwloc
