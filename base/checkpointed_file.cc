#include "base/checkpointed_file.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <string>
#include <system_error>
#include <utility>

#include "base/error.h"

namespace cwloc {
namespace {

[[noreturn]] void Fail(const std::filesystem::path& path, std::string_view what, int error_number) {
  throw InputError(path.string() + ": " + std::string(what) + ": " +
                   std::generic_category().message(error_number));
}

}  // namespace

CheckpointedFile::CheckpointedFile(std::filesystem::path path, Clock::duration min_interval)
    : path_(std::move(path)), min_interval_(min_interval) {
  struct stat status;
  if (::lstat(path_.c_str(), &status) == 0 && !S_ISREG(status.st_mode)) {
    stream_fd_ = ::open(path_.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (stream_fd_ < 0) Fail(path_, "cannot write", errno);
    return;
  }
  file_ = std::make_unique<AtomicFile>(path_);  // fails now if the folder is not writable
  next_checkpoint_ = Clock::now() + min_interval_;
}

CheckpointedFile::~CheckpointedFile() {
  if (file_ && pending_) {
    try {
      Commit(/*last=*/true);
    } catch (const std::exception&) {  // nothing more to do for records that cannot be saved
    }
  }
  if (committed_fd_ >= 0) ::close(committed_fd_);
  if (stream_fd_ >= 0) ::close(stream_fd_);
}

void CheckpointedFile::Append(std::string_view record) {
  if (stream_fd_ >= 0) {
    Stream(record);
    return;
  }
  ThrowIfSpent();
  try {
    file_->Write(record.data(), record.size());
  } catch (...) {
    file_.reset();  // it may end in a part of the record: never commit it
    throw;
  }
  size_ += record.size();
  pending_ = true;
  if (Clock::now() >= next_checkpoint_) Commit(/*last=*/false);
}

void CheckpointedFile::Checkpoint() {
  if (stream_fd_ >= 0) return;
  ThrowIfSpent();
  if (pending_) Commit(/*last=*/false);
}

void CheckpointedFile::Close() {
  if (closed_) return;
  if (stream_fd_ >= 0) {
    closed_ = true;
    if (::close(std::exchange(stream_fd_, -1)) != 0) Fail(path_, "cannot write", errno);
    return;
  }
  ThrowIfSpent();
  // Even a run without records leaves its (empty) file.
  if (pending_ || checkpoints_ == 0) Commit(/*last=*/true);
  file_.reset();
  closed_ = true;
}

void CheckpointedFile::ThrowIfSpent() const {
  if (closed_) throw InputError(path_.string() + ": written after it was closed");
  if (!file_) throw InputError(path_.string() + ": not written: an earlier write failed");
}

void CheckpointedFile::Commit(bool last) {
  const Clock::time_point start = Clock::now();
  // Any failure leaves file_ null: the object is spent.
  std::unique_ptr<AtomicFile> file = std::move(file_);
  const int committed_fd = last ? -1 : file->OpenForReading();
  try {
    file->Commit();
  } catch (...) {
    if (committed_fd >= 0) ::close(committed_fd);
    throw;
  }
  if (committed_fd_ >= 0) ::close(committed_fd_);
  committed_fd_ = committed_fd;
  pending_ = false;
  ++checkpoints_;
  if (last) return;
  // The next file starts as a copy of the committed one; the records that follow go after it.
  file = std::make_unique<AtomicFile>(path_);
  file->CopyFrom(committed_fd_, size_);
  file_ = std::move(file);
  const Clock::time_point end = Clock::now();
  next_checkpoint_ = end + std::max<Clock::duration>(min_interval_, kCostFactor * (end - start));
}

void CheckpointedFile::Stream(std::string_view record) {
  while (!record.empty()) {
    const ssize_t n = ::write(stream_fd_, record.data(), record.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) Fail(path_, "cannot write", n < 0 ? errno : ENOSPC);
    record.remove_prefix(static_cast<size_t>(n));
  }
}

}  // namespace cwloc
