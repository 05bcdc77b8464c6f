#include "base/atomic_file.h"

#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

#include "base/error.h"

namespace cwloc {
namespace {

std::string TempPrefix(const std::filesystem::path& path) {
  return path.filename().string() + ".tmp-";
}

// O_EXCL on a name no other writer picks: the process id tells processes apart, the counter
// the files of this one; a name left behind by a crash is skipped. Returns -1 with errno set.
int CreateTempFile(const std::filesystem::path& path, std::filesystem::path* temp_path) {
  static std::atomic<uint64_t> counter{0};
  const std::string prefix = TempPrefix(path) + std::to_string(::getpid()) + "-";
  for (int attempt = 0; attempt < 100; ++attempt) {
    *temp_path = path.parent_path() / (prefix + std::to_string(counter++));
    const int fd = ::open(temp_path->c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
    if (fd >= 0 || errno != EEXIST) return fd;
  }
  return -1;
}

// An unnamed file in `dir`, or -1 with errno set (EOPNOTSUPP etc. where O_TMPFILE is missing).
int CreateUnnamedFile(const std::filesystem::path& path) {
  const std::filesystem::path dir = path.has_parent_path() ? path.parent_path() : ".";
#ifdef O_TMPFILE
  return ::open(dir.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0644);
#else
  errno = EOPNOTSUPP;
  return -1;
#endif
}

// Gives the unnamed file behind `fd` the name `target`; fails with EEXIST when it exists.
int LinkUnnamedFile(int fd, const std::filesystem::path& target) {
  const std::string self = "/proc/self/fd/" + std::to_string(fd);
  return ::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, target.c_str(), AT_SYMLINK_FOLLOW);
}

}  // namespace

void RemoveDeadWritersTemporaries(const std::filesystem::path& destination) {
  const std::string prefix = TempPrefix(destination);
  const std::filesystem::path dir = destination.has_parent_path() ? destination.parent_path() : ".";
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(dir, error)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind(prefix, 0) != 0) continue;
    char* end = nullptr;
    const long pid = std::strtol(name.c_str() + prefix.size(), &end, 10);
    if (pid <= 0 || *end != '-' || pid == ::getpid()) continue;
    if (::kill(static_cast<pid_t>(pid), 0) != 0 && errno == ESRCH) {
      std::filesystem::remove_all(entry.path(), error);
    }
  }
}

AtomicFile::AtomicFile(std::filesystem::path path, Temporary temporary) : path_(std::move(path)) {
  RemoveDeadWritersTemporaries(path_);
  if (temporary == Temporary::kUnnamed) {
    fd_ = CreateUnnamedFile(path_);
    // Only a missing directory or permission is final; other errors mean no O_TMPFILE here.
    if (fd_ < 0 && (errno == ENOENT || errno == EACCES || errno == ENOTDIR || errno == EROFS)) {
      Fail("cannot create a temporary file next to it", errno);
    }
    if (fd_ >= 0) return;
  }
  fd_ = CreateTempFile(path_, &temp_path_);
  if (fd_ < 0) {
    const int error_number = errno;
    temp_path_.clear();
    Fail("cannot create a temporary file next to it", error_number);
  }
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!temp_path_.empty()) ::unlink(temp_path_.c_str());
}

// A big file is written back as it grows: each window is sent to the disk once written, and
// dropped from the page cache once the next one is, so its dirty pages stay few and their
// memory is reused, and Commit()'s fsync has little left to do. On this project's VM, where
// fresh memory is dear, `cwloc-index update` wrote and synced a 1.9 GB index in 3.1-3.8 s
// instead of 5.0-6.7 s. Hints: their errors are fsync's to report.
constexpr uint64_t kWriteBackWindow = uint64_t{32} << 20;

void AtomicFile::WriteBack() {
  while (written_ - written_back_ >= kWriteBackWindow) {
    ::sync_file_range(fd_, static_cast<off64_t>(written_back_), kWriteBackWindow,
                      SYNC_FILE_RANGE_WRITE);
    if (written_back_ >= kWriteBackWindow) {
      const auto previous = static_cast<off64_t>(written_back_ - kWriteBackWindow);
      ::sync_file_range(
          fd_, previous, kWriteBackWindow,
          SYNC_FILE_RANGE_WAIT_BEFORE | SYNC_FILE_RANGE_WRITE | SYNC_FILE_RANGE_WAIT_AFTER);
      ::posix_fadvise(fd_, previous, kWriteBackWindow, POSIX_FADV_DONTNEED);
    }
    written_back_ += kWriteBackWindow;
  }
}

// O_DIRECT wants the buffer, the file offset and the length aligned to the disk's logical
// block, 4 KiB or less on the disks in use. 16 MiB per write keeps the disk's queue full.
constexpr size_t kDirectAlignment = 4096;
constexpr size_t kDirectBufferSize = size_t{16} << 20;

void AtomicFile::BypassPageCache() {
  if (written_ != 0 || direct_) return;
  const int flags = ::fcntl(fd_, F_GETFL);
  if (flags < 0 || ::fcntl(fd_, F_SETFL, flags | O_DIRECT) != 0) return;
  void* buffer = nullptr;
  if (::posix_memalign(&buffer, kDirectAlignment, kDirectBufferSize) != 0) {
    ::fcntl(fd_, F_SETFL, flags);
    return;
  }
  direct_ = {static_cast<char*>(buffer), std::free};
}

void AtomicFile::Write(const void* data, size_t size) {
  const char* bytes = static_cast<const char*>(data);
  if (!direct_) {
    WriteThrough(bytes, size);
    return;
  }
  while (size > 0) {
    const size_t take = std::min(size, kDirectBufferSize - direct_used_);
    std::memcpy(direct_.get() + direct_used_, bytes, take);
    direct_used_ += take;
    bytes += take;
    size -= take;
    if (direct_used_ == kDirectBufferSize) FlushDirect(false);
  }
}

// Writes the buffer directly; the last one padded to a whole block, which Commit() cuts off
// again. Where a direct write is refused (EINVAL: a file system without O_DIRECT, or a short
// write that left the offset unaligned), the rest goes through the page cache.
void AtomicFile::FlushDirect(bool last) {
  const size_t size = std::exchange(direct_used_, 0);
  size_t padded = size;
  if (last) {
    padded = (size + kDirectAlignment - 1) / kDirectAlignment * kDirectAlignment;
    std::memset(direct_.get() + size, 0, padded - size);
  }
  size_t done = 0;
  while (done < size) {
    const ssize_t n = ::write(fd_, direct_.get() + done, padded - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno == EINVAL) break;
    if (n <= 0) Fail("cannot write", n < 0 ? errno : ENOSPC);
    done += static_cast<size_t>(n);
    if (done % kDirectAlignment != 0) break;
  }
  done = std::min(done, size);
  written_ += done;
  written_back_ = written_;
  if (done < size) {
    ::fcntl(fd_, F_SETFL, ::fcntl(fd_, F_GETFL) & ~O_DIRECT);
    if (::lseek(fd_, static_cast<off_t>(written_), SEEK_SET) < 0) Fail("cannot write", errno);
    const auto buffer = std::move(direct_);
    WriteThrough(buffer.get() + done, size - done);
  }
}

void AtomicFile::WriteThrough(const char* bytes, size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd_, bytes, std::min<size_t>(size, kWriteBackWindow));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) Fail("cannot write", n < 0 ? errno : ENOSPC);
    bytes += n;
    size -= static_cast<size_t>(n);
    written_ += static_cast<uint64_t>(n);
    WriteBack();
  }
}

void AtomicFile::Overwrite(uint64_t offset, const void* data, size_t size) {
  const uint64_t end = offset + size;
  if (end < offset || end > written_ + direct_used_)
    throw std::logic_error("AtomicFile::Overwrite past what was written");
  const char* bytes = static_cast<const char*>(data);
  if (end > written_) {  // the part still in the direct buffer
    const uint64_t from = std::max(offset, written_);
    std::memcpy(direct_.get() + (from - written_), bytes + (from - offset), end - from);
    size = static_cast<size_t>(from - offset);
  }
  if (size == 0) return;
  std::unique_ptr<char, void (*)(void*)> aligned{nullptr, std::free};
  if (direct_) {
    if (offset % kDirectAlignment != 0 || size % kDirectAlignment != 0)
      throw std::logic_error("AtomicFile::Overwrite of a part of a block on the disk");
    void* buffer = nullptr;
    if (::posix_memalign(&buffer, kDirectAlignment, size) != 0) Fail("cannot write", ENOMEM);
    aligned.reset(static_cast<char*>(buffer));
    std::memcpy(aligned.get(), bytes, size);
    bytes = aligned.get();
  }
  for (size_t done = 0; done < size;) {
    const ssize_t n = ::pwrite(fd_, bytes + done, size - done, static_cast<off_t>(offset + done));
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) Fail("cannot write", n < 0 ? errno : ENOSPC);
    done += static_cast<size_t>(n);
  }
}

void AtomicFile::CopyFrom(int source_fd, uint64_t size) {
  if (direct_) throw std::logic_error("AtomicFile::CopyFrom after BypassPageCache()");
  loff_t offset = 0;
  while (static_cast<uint64_t>(offset) < size) {
    const size_t chunk = static_cast<size_t>(std::min<uint64_t>(size - offset, kWriteBackWindow));
    const ssize_t n = ::copy_file_range(source_fd, &offset, fd_, nullptr, chunk, 0);
    if (n > 0) {
      written_ += static_cast<uint64_t>(n);
      WriteBack();
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    // Not between these files (EXDEV across file systems, EINVAL, ENOSYS, EOPNOTSUPP), or the
    // source ended early: copy the rest through a buffer, which reports the real error.
    break;
  }
  std::vector<char> buffer;
  while (static_cast<uint64_t>(offset) < size) {
    if (buffer.empty()) buffer.resize(size_t{1} << 20);
    const size_t chunk = static_cast<size_t>(std::min<uint64_t>(size - offset, buffer.size()));
    const ssize_t n = ::pread(source_fd, buffer.data(), chunk, offset);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) Fail("cannot read the content to copy", errno);
    if (n == 0) Fail("cannot copy the previous content", EIO);  // the source shrank
    Write(buffer.data(), static_cast<size_t>(n));
    offset += n;
  }
}

int AtomicFile::OpenForReading() const {
  if (direct_) throw std::logic_error("AtomicFile::OpenForReading after BypassPageCache()");
  // An unnamed file opens again through its /proc link, as Commit() links it.
  const std::string name =
      temp_path_.empty() ? "/proc/self/fd/" + std::to_string(fd_) : temp_path_.string();
  const int fd = ::open(name.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) Fail("cannot open the temporary file again", errno);
  return fd;
}

void AtomicFile::Sync() {
  if (::fdatasync(fd_) != 0) Fail("cannot sync to disk", errno);
}

void AtomicFile::Commit() {
  if (direct_) {
    FlushDirect(true);
    if (::ftruncate(fd_, static_cast<off_t>(written_)) != 0) Fail("cannot write", errno);
  }
  // fsync also reports write errors the kernel deferred (a full disk on NFS, EIO).
  if (::fsync(fd_) != 0) Fail("cannot sync to disk", errno);
  if (temp_path_.empty()) {
    // Unnamed: a new destination gets the file directly; an existing one is replaced through a
    // name that exists only between the link and the rename.
    if (LinkUnnamedFile(fd_, path_) != 0) {
      if (errno != EEXIST) Fail("cannot link the temporary file into place", errno);
      std::filesystem::path named;
      for (int attempt = 0;; ++attempt) {
        static std::atomic<uint64_t> counter{0};
        named = path_.parent_path() /
                (TempPrefix(path_) + std::to_string(::getpid()) + "-u" + std::to_string(counter++));
        if (LinkUnnamedFile(fd_, named) == 0) break;
        if (errno != EEXIST || attempt >= 100)
          Fail("cannot link the temporary file into place", errno);
      }
      temp_path_ = named;
    }
  }
  if (::close(std::exchange(fd_, -1)) != 0) Fail("cannot write", errno);
  if (!temp_path_.empty() && ::rename(temp_path_.c_str(), path_.c_str()) != 0) {
    const int error_number = errno;
    Fail("cannot rename " + temp_path_.filename().string() + " into place", error_number);
  }
  temp_path_.clear();
  // The rename is durable once the directory is: sync it too.
  const std::filesystem::path dir = path_.has_parent_path() ? path_.parent_path() : ".";
  const int dir_fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir_fd < 0) Fail("cannot open its directory to sync it", errno);
  const int rc = ::fsync(dir_fd);
  const int error_number = errno;
  ::close(dir_fd);
  // EINVAL: a file system that cannot sync directories; nothing more can be done there.
  if (rc != 0 && error_number != EINVAL) Fail("cannot sync its directory", error_number);
}

void AtomicFile::Fail(std::string_view what, int error_number) const {
  std::string message = path_.string();
  message += ": ";
  message += what;
  message += ": " + std::generic_category().message(error_number);
  throw InputError(message);
}

AtomicFileWriter::AtomicFileWriter(std::filesystem::path path)
    : file_(std::move(path)), buffer_(std::make_unique_for_overwrite<char[]>(kBufferSize)) {}

void AtomicFileWriter::Append(const void* data, size_t size) {
  if (kBufferSize - used_ < size) Flush();
  if (size > kBufferSize) {
    file_.Write(data, size);  // rare: larger than the whole buffer
    return;
  }
  std::memcpy(buffer_.get() + used_, data, size);
  used_ += size;
}

void AtomicFileWriter::Flush() {
  file_.Write(buffer_.get(), used_);
  used_ = 0;
}

void AtomicFileWriter::Commit() {
  Flush();
  file_.Commit();
}

}  // namespace cwloc
