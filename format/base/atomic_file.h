#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <string_view>

namespace cwloc {

// Replaces a file so that readers, even after a crash, see the old content or the new one,
// never a part: the content goes to a temporary file with a unique name in the destination's
// directory (a rename is atomic only within one file system), and Commit() fsyncs it, renames
// it over the destination and fsyncs the directory so that the rename survives a power loss.
// Destroyed without Commit() (an exception), it removes the temporary file. Every failure
// throws InputError naming the destination.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& path() const { return path_; }
  // For writers that open the file by name themselves (SQLite): the file is created empty.
  const std::filesystem::path& temp_path() const { return temp_path_; }

  void Write(const void* data, size_t size);
  void Commit();

 private:
  [[noreturn]] void Fail(std::string_view what, int error_number) const;

  std::filesystem::path path_;
  std::filesystem::path temp_path_;  // empty once renamed into place
  int fd_ = -1;
};

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
