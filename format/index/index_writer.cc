#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <vector>

#include "format/index/index_file.h"
#include "format/index/xxhash64.h"

namespace cwloc {
namespace {

uint64_t AlignUp(uint64_t value) { return (value + kSectionAlignment - 1) / kSectionAlignment * kSectionAlignment; }

// A temporary file next to the target that disappears unless Commit() renames it into place.
class TempFile {
 public:
  explicit TempFile(const std::filesystem::path& target) : target_(target) {
    std::string pattern = target.string() + ".tmp-XXXXXX";
    fd_ = ::mkstemp(pattern.data());
    if (fd_ < 0) Fail("cannot create a temporary file next to it");
    temp_ = pattern;
    ::fchmod(fd_, 0644);
  }
  ~TempFile() {
    if (fd_ >= 0) ::close(fd_);
    if (!temp_.empty()) ::unlink(temp_.c_str());
  }

  void Write(const uint8_t* data, size_t size) {
    while (size > 0) {
      const ssize_t n = ::write(fd_, data, size);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) Fail("write failed");
      data += n;
      size -= static_cast<size_t>(n);
    }
  }

  void Commit() {
    if (::fsync(fd_) != 0) Fail("fsync failed");
    if (::close(fd_) != 0) {
      fd_ = -1;
      Fail("close failed");
    }
    fd_ = -1;
    if (::rename(temp_.c_str(), target_.c_str()) != 0) Fail("cannot rename the temporary file into place");
    temp_.clear();
    // Make the rename itself durable.
    const std::filesystem::path dir = target_.has_parent_path() ? target_.parent_path() : ".";
    const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (dir_fd >= 0) {
      ::fsync(dir_fd);
      ::close(dir_fd);
    }
  }

 private:
  [[noreturn]] void Fail(const std::string& what) {
    throw InputError(target_.string() + ": " + what + ": " + std::strerror(errno));
  }

  std::filesystem::path target_;
  std::string temp_;
  int fd_ = -1;
};

}  // namespace

void WriteIndexFile(const std::filesystem::path& path, std::span<const SectionData> sections) {
  std::vector<SectionEntry> table(sections.size());
  uint64_t offset = sizeof(FileHeader);
  for (size_t i = 0; i < sections.size(); ++i) {
    const SectionData& section = sections[i];
    if (section.bytes.size() != section.count * section.element_size || section.element_size == 0) {
      throw std::logic_error("WriteIndexFile: section '" + SectionTagName(section.tag) +
                             "' bytes do not match count * element_size");
    }
    SectionEntry& entry = table[i];
    std::memset(&entry, 0, sizeof(entry));
    entry.tag = section.tag;
    entry.flags = section.flags;
    entry.offset = AlignUp(offset);
    entry.size = section.bytes.size();
    entry.count = section.count;
    entry.element_size = section.element_size;
    entry.checksum = XxHash64(section.bytes);
    offset = entry.offset + entry.size;
  }
  const uint64_t table_offset = AlignUp(offset);
  const uint64_t table_bytes = table.size() * sizeof(SectionEntry);

  FileHeader header;
  std::memset(&header, 0, sizeof(header));
  std::memcpy(header.magic, kIndexMagic, sizeof(kIndexMagic));
  header.byte_order_mark = kByteOrderMark;
  header.format_major = kFormatMajor;
  header.format_minor = kFormatMinor;
  header.header_size = sizeof(FileHeader);
  header.section_entry_size = sizeof(SectionEntry);
  header.file_size = table_offset + table_bytes;
  header.section_table_offset = table_offset;
  header.section_count = static_cast<uint32_t>(table.size());
  header.section_table_checksum = XxHash64({reinterpret_cast<const uint8_t*>(table.data()), table_bytes});
  header.header_checksum = XxHash64({reinterpret_cast<const uint8_t*>(&header), offsetof(FileHeader, header_checksum)});

  TempFile file(path);
  static constexpr uint8_t kZeros[kSectionAlignment] = {};
  file.Write(reinterpret_cast<const uint8_t*>(&header), sizeof(header));
  uint64_t written = sizeof(header);
  for (size_t i = 0; i < sections.size(); ++i) {
    file.Write(kZeros, table[i].offset - written);
    file.Write(sections[i].bytes.data(), sections[i].bytes.size());
    written = table[i].offset + table[i].size;
  }
  file.Write(kZeros, table_offset - written);
  file.Write(reinterpret_cast<const uint8_t*>(table.data()), table_bytes);
  file.Commit();
}

}  // namespace cwloc
