#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>

namespace cwloc {

// Replaces a file so that readers, even after a crash, see the old content or the new one,
// never a part: the content goes to a temporary file in the destination's directory (a rename
// is atomic only within one file system), and Commit() fsyncs it, puts it in place and fsyncs
// the directory so that this survives a power loss.
//
// The temporary file has no name (Linux's O_TMPFILE), so a writer killed before Commit() leaves
// nothing behind; Commit() links it to the destination, or, when that exists, to a unique
// `<name>.tmp-<pid>-u<n>` renamed over it at once. Where the file system has no O_TMPFILE, and
// for writers that must open the file by name (SQLite: Temporary::kNamed), the temporary file
// is named `<name>.tmp-<pid>-<n>` from the start. A writer first removes the temporary files of
// dead writers of the same destination (their pid no longer runs), so a kill leaves nothing for
// long. Destroyed without Commit() (an exception), it removes its temporary file. Every failure
// throws InputError naming the destination.
class AtomicFile {
 public:
  enum class Temporary { kUnnamed, kNamed };
  explicit AtomicFile(std::filesystem::path path, Temporary temporary = Temporary::kUnnamed);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // Temporary::kNamed: the file writers open by name themselves (SQLite), created empty. Empty
  // while the temporary file has no name.
  const std::filesystem::path& temp_path() const { return temp_path_; }

  // From here on (before the first Write), the content goes to the disk directly (O_DIRECT)
  // through an aligned buffer instead of through the page cache: for a big file written once
  // and not read back soon (an index of GBs), whose pages would only be copied, written back
  // and dropped. Where the file system refuses, writes stay buffered.
  void BypassPageCache();
  void Write(const void* data, size_t size);
  // Replaces `size` bytes at `offset` among those written so far (a header whose checksums are
  // known last). Past the page cache, bytes already on the disk are replaced in whole blocks of
  // 4 KiB: `offset` and `size` must then be multiples of it (std::logic_error otherwise).
  void Overwrite(uint64_t offset, const void* data, size_t size);
  // Appends the first `size` bytes of the open file `source_fd` (read from offset 0, its own
  // offset untouched), kernel-side where the file systems allow (copy_file_range).
  void CopyFrom(int source_fd, uint64_t size);
  // A new read-only descriptor of the content written so far, which stays valid after Commit()
  // (CheckpointedFile copies the committed content on from it); the caller closes it.
  int OpenForReading() const;
  // Makes what was written so far durable (fdatasync), so that Commit() has less left to sync:
  // a writer's second thread calls it while the first composes the rest.
  void Sync();
  void Commit();

 private:
  [[noreturn]] void Fail(std::string_view what, int error_number) const;
  void WriteBack();
  void WriteThrough(const char* bytes, size_t size);
  void FlushDirect(bool last);

  std::filesystem::path path_;
  std::filesystem::path temp_path_;  // empty when unnamed or once renamed into place
  int fd_ = -1;
  uint64_t written_ = 0;       // bytes written so far
  uint64_t written_back_ = 0;  // of which writeback was started
  // BypassPageCache(): content not yet written, in a block-aligned buffer (empty otherwise).
  std::unique_ptr<char, void (*)(void*)> direct_{nullptr, nullptr};
  size_t direct_used_ = 0;
};

// Removes `<destination name>.tmp-<pid>-...` files and folders next to `destination` whose
// writer no longer runs (no process has that pid): what a killed writer left. A pid that runs,
// perhaps reused, keeps its temporaries; so does this process.
void RemoveDeadWritersTemporaries(const std::filesystem::path& destination);

// An AtomicFile behind a large buffer, for writers of many small pieces (COLMAP models).
class AtomicFileWriter {
 public:
  explicit AtomicFileWriter(std::filesystem::path path);

  // A cursor with at least `n` writable bytes (n <= kBufferSize); hand the end back to Advance.
  char* Ensure(size_t n) {
    if (kBufferSize - used_ < n) Flush();
    return buffer_.get() + used_;
  }
  void Advance(char* end) { used_ = static_cast<size_t>(end - buffer_.get()); }
  void Append(const void* data, size_t size);
  void Append(std::string_view text) { Append(text.data(), text.size()); }

  void Commit();
  const std::filesystem::path& path() const { return file_.path(); }

  static constexpr size_t kBufferSize = size_t{4} << 20;

 private:
  void Flush();

  AtomicFile file_;
  std::unique_ptr<char[]> buffer_;
  size_t used_ = 0;
};

}  // namespace cwloc
