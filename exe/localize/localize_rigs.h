#pragma once

#include <atomic>
#include <functional>
#include <vector>

#include "app/rig_input.h"
#include "exe/localize/localize_cli.h"
#include "exe/localize/result_sink.h"
#include "localizer/localizer.h"
#include "localizer/query.h"

namespace cwloc {

// How a run of rig frames went, for the summary and the exit code.
struct RigRunCounts {
  int localized = 0, failed = 0, errors = 0, internal_errors = 0;
  std::vector<double> seconds;  // each processed frame's total
};

// The frames of --rig (COLMAP's rig_config.json and --image-list) or --frames, as the command
// line names them; refused with InputError before any work (docs/cli.md).
std::vector<RigFrameInput> CollectRigFrames(const CliOptions& cli);

// Localizes each frame as one rig (rig_localizer.h), --threads frames at a time, and writes its
// record; a frame that cannot be read or processed gets an error record. Stops between frames
// once `stop` is set or the sink failed.
// `load` reads an image's query (features, camera, priors).
RigRunCounts RunRigFrames(const CliOptions& cli, const std::vector<RigFrameInput>& frames,
                          const Localizer& localizer,
                          const std::function<Query(const RigFrameImage&)>& load, ResultSink& sink,
                          const std::atomic<int>& stop);

}  // namespace cwloc
