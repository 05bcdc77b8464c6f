#pragma once

#include <atomic>
#include <iostream>
#include <memory>
#include <mutex>
#include <string>

#include "app/result_json.h"
#include "app/trajectory_file.h"
#include "base/checkpointed_file.h"
#include "base/error.h"
#include "exe/localize/localize_cli.h"
#include "localizer/rig_localizer.h"
#include "results/localization_result.h"

namespace cwloc {

// Writes each finished query's record: JSON lines to --output (stdout by default), a pose line
// to --poses, a readable line to stdout when the JSON goes to a file. Files get whole records
// only and keep their previous content until the first checkpoint (CheckpointedFile). The first
// error writing them stops the run: failed() tells the workers, Close() throws it.
class ResultSink {
 public:
  explicit ResultSink(const CliOptions& cli) : cli_(cli) {
    if (!cli.output_path.empty() && cli.output_path != "-")
      json_file_ = std::make_unique<CheckpointedFile>(cli.output_path);
    if (!cli.poses_path.empty()) poses_file_ = std::make_unique<CheckpointedFile>(cli.poses_path);
    if (!cli.trajectory_path.empty()) {
      trajectory_file_ = std::make_unique<CheckpointedFile>(cli.trajectory_path);
      trajectory_format_ = TrajectoryFormatNamed(cli.trajectory_format);
      const std::string header = TrajectoryHeader(trajectory_format_);
      if (!header.empty()) Guard([&] { trajectory_file_->Append(header); });
    }
  }

  // `stamp`: a sequence frame's, for --trajectory.
  void Write(const LocalizationResult& result, const QueryOptions& options, FrameStamp stamp);
  // A rig frame: its record, each posed image's line to --poses, a readable line.
  void WriteRig(const RigResult& result, const QueryOptions& options);

  void WriteError(const std::string& name, const std::string& error) {
    std::lock_guard lock(mutex_);
    if (closed_) return;
    EmitJsonLine(ErrorToJson(name, error).dump());
    std::fprintf(stderr, "cwloc-localize: error: %s\n", error.c_str());
  }

  bool failed() const { return failed_; }

  // Puts every record in place; throws the first write error.
  void Close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    for (CheckpointedFile* file : {json_file_.get(), poses_file_.get(), trajectory_file_.get()}) {
      if (file && !failed_) Guard([&] { file->Close(); });
    }
    if (failed_) throw InputError(error_);
  }

 private:
  // One record per line to --output, or stdout without it; the caller holds mutex_.
  void EmitJsonLine(const std::string& json) {
    if (json_file_) {
      Append(*json_file_, json);
      return;
    }
    // A record and its newline in one write, flushed at once: a reader of the pipe sees each
    // query as it finishes.
    const std::string line = json + '\n';
    std::cout.write(line.data(), static_cast<std::streamsize>(line.size()));
    std::cout.flush();
  }

  void Append(CheckpointedFile& file, std::string line) {
    line += '\n';
    Guard([&] { file.Append(line); });
  }

  // Runs a file operation unless one failed already, keeping the first error.
  template <typename Operation>
  void Guard(Operation operation) {
    if (failed_) return;
    try {
      operation();
    } catch (const InputError& e) {
      error_ = e.what();
      failed_ = true;
    }
  }

  const CliOptions& cli_;
  std::unique_ptr<CheckpointedFile> json_file_;
  std::unique_ptr<CheckpointedFile> poses_file_;
  std::unique_ptr<CheckpointedFile> trajectory_file_;
  TrajectoryFormat trajectory_format_ = TrajectoryFormat::kTum;
  std::mutex mutex_;
  std::atomic<bool> failed_{false};
  bool closed_ = false;
  std::string error_;
};
}  // namespace cwloc
