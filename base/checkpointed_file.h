#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string_view>

#include "base/atomic_file.h"

namespace cwloc {

// A file of records appended one by one (JSON lines, pose lines) that readers, even after a
// kill or a crash, see as the previous file or as whole records of this run, never a part of
// one. Records go to an AtomicFile; a checkpoint commits it in place, then starts the next one
// with a kernel-side copy of what was committed (memory does not grow with the records).
//
// Checkpoints cost O(file size), so they are spaced out (kMinInterval, kCostFactor below); a
// kill loses the records since the last one. The destination holds the previous file until the
// first checkpoint. Close() commits the rest, and creates the file even with no record.
// Destroyed without Close() (an exception), it commits pending records and nothing else: a
// failed run leaves what it finished, or the previous file.
//
// A destination that exists and is not a regular file (a symbolic link, a pipe, /dev/null,
// /dev/stdout) is not replaced but written in place as before: each record in one write at once.
// Errors throw InputError naming the file; a destination that cannot be written fails in the
// constructor, and after an error every call fails and the destination keeps the last checkpoint.
class CheckpointedFile {
 public:
  using Clock = std::chrono::steady_clock;

  // A checkpoint waits until kMinInterval has passed since the previous one ended, and
  // kCostFactor times that one's duration: at most 1/kCostFactor of the run goes to rewriting the
  // file. Measured on ext4 (docs/reliability.md): 10 ms for a file up to 1 MB (mostly its fsyncs),
  // 21 ms at 10 MB, 143 ms at 100 MB: a small file costs about 1% of the run, a large one 2%.
  static constexpr Clock::duration kMinInterval = std::chrono::seconds(1);
  static constexpr int kCostFactor = 50;

  // `min_interval`: tests space checkpoints differently.
  explicit CheckpointedFile(std::filesystem::path path,
                            Clock::duration min_interval = kMinInterval);
  ~CheckpointedFile();
  CheckpointedFile(const CheckpointedFile&) = delete;
  CheckpointedFile& operator=(const CheckpointedFile&) = delete;

  const std::filesystem::path& path() const { return path_; }

  // Appends one record, its newline included, then checkpoints if one is due.
  void Append(std::string_view record);
  // Puts every record appended so far in place now.
  void Checkpoint();
  // The last checkpoint; the destination then holds every record. Nothing may follow.
  void Close();

  int checkpoints() const { return checkpoints_; }

 private:
  void Commit(bool last);
  void Stream(std::string_view record);
  void ThrowIfSpent() const;

  std::filesystem::path path_;
  std::unique_ptr<AtomicFile> file_;  // receives the records; null once closed or failed
  bool closed_ = false;
  int committed_fd_ = -1;  // the last committed content, read-only
  uint64_t size_ = 0;      // bytes appended: committed and pending
  bool pending_ = false;
  int checkpoints_ = 0;
  Clock::duration min_interval_;
  Clock::time_point next_checkpoint_;
  int stream_fd_ = -1;  // not a regular file: records go straight there
};

}  // namespace cwloc
