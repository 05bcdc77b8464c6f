#include "exe/localize/localize_rigs.h"

#include <algorithm>
#include <new>
#include <thread>

#include "base/error.h"
#include "base/progress.h"
#include "localizer/rig_localizer.h"

namespace cwloc {

namespace {

// With --database, the frames' images are its images, by name.
std::vector<RigFrameInput> FromDatabase(std::vector<RigFrameInput> frames) {
  for (RigFrameInput& frame : frames) {
    for (RigFrameImage& image : frame.images) {
      image.source.kind = QuerySource::Kind::kDatabase;
      image.source.path.clear();
    }
  }
  return frames;
}

}  // namespace

std::vector<RigFrameInput> CollectRigFrames(const CliOptions& cli) {
  if (!cli.rig_config_path.empty() && !cli.frames_path.empty())
    throw InputError("--rig and --frames exclude each other: a frame's poses come from one");
  if (cli.sequence || !cli.motion_path.empty() || !cli.trajectory_path.empty()) {
    throw InputError(
        "--rig and --frames localize frames one by one: no --sequence, --motion or --trajectory");
  }
  if (cli.frames_scale != "known" && cli.frames_scale != "unknown")
    throw InputError("--frames-scale must be known or unknown, not '" + cli.frames_scale + "'");
  const bool database = !cli.database_path.empty();
  const bool loose_queries = !cli.query_names.empty() || !cli.feature_files.empty() ||
                             !cli.images.empty() || !cli.video_path.empty();
  if (!cli.frames_path.empty()) {
    if (loose_queries || !cli.image_list.empty() || !cli.query_list.empty())
      throw InputError("--frames takes no other queries (its lines are the images)");
    const std::filesystem::path base = cli.image_dir.empty()
                                           ? std::filesystem::path(cli.frames_path).parent_path()
                                           : std::filesystem::path(cli.image_dir);
    std::vector<RigFrameInput> frames = ReadFramesFile(cli.frames_path, base);
    return database ? FromDatabase(std::move(frames)) : frames;
  }
  // --rig: an image list, or with --database a query list of its image names.
  const std::string& list = database && !cli.query_list.empty() ? cli.query_list : cli.image_list;
  if (loose_queries || list.empty() || (!cli.image_list.empty() && !cli.query_list.empty())) {
    throw InputError(
        "--rig needs --image-list (or with --database --query-list): the rig's images, and no "
        "other queries");
  }
  const auto rigs = ReadRigConfig(cli.rig_config_path);
  const std::filesystem::path base = cli.image_dir.empty()
                                         ? std::filesystem::path(list).parent_path()
                                         : std::filesystem::path(cli.image_dir);
  std::vector<RigFrameInput> frames =
      FramesOfRigs(rigs, cli.rig_config_path, ReadQueryList(list), list, base);
  return database && list == cli.query_list ? FromDatabase(std::move(frames)) : frames;
}

RigRunCounts RunRigFrames(const CliOptions& cli, const std::vector<RigFrameInput>& frames,
                          const Localizer& localizer,
                          const std::function<Query(const RigFrameImage&)>& load, ResultSink& sink,
                          const std::atomic<int>& stop) {
  RigRunCounts counts;
  std::mutex counts_mutex;
  const bool unknown_scale = cli.frames_scale == "unknown";
  std::atomic<size_t> next{0};
  Progress progress("localizing rig frames", frames.size());
  const auto worker = [&] {
    for (size_t f = next++; f < frames.size() && !sink.failed() && stop == 0; f = next++) {
      const RigFrameInput& frame = frames[f];
      int* outcome = nullptr;
      double seconds = -1;
      try {
        RigQuery query;
        query.name = frame.name;
        query.unknown_scale = unknown_scale;
        for (const RigFrameImage& image : frame.images)
          query.images.push_back({load(image), image.cam_from_rig});
        const RigResult result = LocalizeRig(localizer, query, cli.options.localizer);
        sink.WriteRig(result, cli.options);
        outcome = result.success ? &counts.localized : &counts.failed;
        seconds = result.times.total;
      } catch (const InputError& e) {
        outcome = &counts.errors;
        sink.WriteError(frame.name, e.what());
      } catch (const std::bad_alloc&) {
        outcome = &counts.internal_errors;
        sink.WriteError(frame.name, "frame '" + frame.name + "': out of memory");
      } catch (const std::exception& e) {
        outcome = &counts.internal_errors;
        sink.WriteError(frame.name, "frame '" + frame.name + "': internal error: " + e.what());
      }
      {
        const std::lock_guard lock(counts_mutex);
        ++*outcome;
        if (seconds >= 0) counts.seconds.push_back(seconds);
      }
      progress.Advance();
    }
  };
  const int threads = std::max(1, std::min<int>(cli.threads, static_cast<int>(frames.size())));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& thread : pool) thread.join();
  progress.Finish();
  return counts;
}

}  // namespace cwloc
