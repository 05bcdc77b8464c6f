// cwloc-localize: opens a cwloc index read-only and estimates query camera poses.
#include <signal.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <mutex>
#include <new>
#include <nlohmann/json.hpp>
#include <span>
#include <sstream>
#include <thread>
#include <unordered_map>
#include <unordered_set>
#include <variant>

#include "app/camera_spec.h"
#include "app/motion_file.h"
#include "app/option_table.h"
#include "app/photo_query.h"
#include "app/query_assembly.h"
#include "app/query_list.h"
#include "app/query_priors.h"
#include "app/rig_input.h"
#include "app/trajectory_file.h"
#include "base/error.h"
#include "base/option_value.h"
#include "base/progress.h"
#include "cwloc/version.h"
#include "exe/localize/localize_cli.h"
#include "exe/localize/localize_rigs.h"
#include "exe/localize/result_sink.h"
#include "exe/localize/table_flags.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "localizer/localizer.h"
#include "localizer/tracker.h"
#ifdef CWLOC_WITH_VIDEO
#include "photo/video/frames_ahead.h"
#include "photo/video/video_frames.h"
#endif
#ifdef CWLOC_WITH_COLMAP_DB
#include "app/database/database_queries.h"
#endif

namespace cwloc {
namespace {

std::vector<QuerySource> CollectQueries(const CliOptions& cli) {
  using Kind = QuerySource::Kind;
  std::vector<QuerySource> sources;
  for (const std::string& name : cli.query_names)
    sources.push_back({name, Kind::kDatabase, {}, {}, {}});
  for (const std::string& file : cli.feature_files) {
    sources.push_back(
        {std::filesystem::path(file).filename().string(), Kind::kTextFeatures, file, {}, {}});
  }
  for (const std::string& image : cli.images) {
    sources.push_back(
        {std::filesystem::path(image).filename().string(), Kind::kPhoto, image, {}, {}});
  }
  if (!cli.query_list.empty()) {
    const std::filesystem::path base = std::filesystem::path(cli.query_list).parent_path();
    const Kind kind = cli.database_path.empty() ? Kind::kTextFeatures : Kind::kDatabase;
    for (const auto& [name, camera] : ReadQueryList(cli.query_list)) {
      sources.push_back(
          {name, kind, kind == Kind::kTextFeatures ? base / name : "", camera, cli.query_list});
    }
  }
  if (!cli.image_list.empty()) {
    // hloc's lists name images relative to an image folder: --image-dir, else the list's own.
    const std::filesystem::path base = cli.image_dir.empty()
                                           ? std::filesystem::path(cli.image_list).parent_path()
                                           : std::filesystem::path(cli.image_dir);
    for (const auto& [name, camera] : ReadQueryList(cli.image_list))
      sources.push_back({name, Kind::kPhoto, base / name, camera, cli.image_list});
  }
  if (!cli.video_path.empty() && !sources.empty())
    throw InputError("--video takes no other queries (its frames are the sequence)");
  if (sources.empty() && cli.video_path.empty()) {
    throw InputError(
        "no queries: give --image, --image-list, --query, --query-list, --features or --video");
  }
  return sources;
}

// Reads each query from its source and assembles it as libcwloc does (QueryAssembler).
class QueryLoader {
 public:
  QueryLoader(const CliOptions& cli, const QueryOptions& options)
      : options_(options), assembler_(options, Cameras(cli), Priors(cli)) {
#ifdef CWLOC_WITH_COLMAP_DB
    if (!cli.database_path.empty())
      database_ = std::make_unique<DatabaseQueries>(cli.database_path);
#endif
  }

  Query Load(const QuerySource& source) const {
    Query query = source.kind == QuerySource::Kind::kDatabase ? LoadFromDatabase(source)
                                                              : assembler_.Read(source);
    assembler_.Complete(source, &query);
    return query;
  }

  // A rig frame's image: as Load, with the rig config's camera model and parameters, which the
  // photo's size completes, when its list line has no camera.
  Query LoadRigImage(const RigFrameImage& image) const {
    QuerySource source = image.source;
    if (source.kind == QuerySource::Kind::kDatabase) return Load(source);
    Query query = assembler_.Read(source);
    if (source.camera_spec.empty() && !image.model_name.empty()) {
      if (query.camera.width == 0) {
        throw InputError(source.Label() +
                         ": the rig config's camera needs the image size: give 'MODEL W H "
                         "PARAMS' after the image's name in the list");
      }
      std::string spec = image.model_name + " " + std::to_string(query.camera.width) + " " +
                         std::to_string(query.camera.height);
      for (const double p : image.params) spec += " " + NumberText(p);
      source.camera_spec = spec;
    }
    assembler_.Complete(source, &query);
    return query;
  }

  // A video frame: the camera from --camera or --focal, else only its size; then its SIFT.
  Query LoadFrame(const std::string& name, GreyImage image) const {
    Query query;
    query.name = name;
    query.source = name;
    query.camera.width = image.width;
    query.camera.height = image.height;
    query.camera.calibration = Calibration::kUnknown;
    query.camera.source = IntrinsicsSource::kNone;
    assembler_.Complete({name, QuerySource::Kind::kImage}, &query);
    ExtractPhotoFeatures(std::move(image), options_.photo, &query);
    return query;
  }

 private:
  static CameraInputs Cameras(const CliOptions& cli) {
    CameraInputs cameras;
    if (!cli.camera_spec.empty()) cameras.camera = ParseCameraSpec(cli.camera_spec, "--camera");
    if (!cli.image_size.empty())
      cameras.image_size = ParseImageSize(cli.image_size, "--image-size");
    cameras.focal_px = cli.focal;
    cameras.unknown_focal = cli.unknown_focal;
    return cameras;
  }

  static PriorInputs Priors(const CliOptions& cli) {
    PriorInputs priors;
    if (!cli.prior_position.empty())
      priors.position = ParsePositionPrior(cli.prior_position, "--prior-position");
    if (!cli.prior_gravity.empty())
      priors.gravity = ParseGravityPrior(cli.prior_gravity, "--prior-gravity");
    if (!cli.priors_path.empty()) priors.per_query = ReadPriorsFile(cli.priors_path);
    return priors;
  }

  Query LoadFromDatabase(const QuerySource& source) const {
#ifdef CWLOC_WITH_COLMAP_DB
    if (!database_) throw InputError(source.Label() + ": give --database to read it from");
    return database_->Load(source.name);
#else
    throw InputError(source.Label() +
                     ": this cwloc-localize was built without COLMAP database input");
#endif
  }

  const QueryOptions& options_;
  QueryAssembler assembler_;
#ifdef CWLOC_WITH_COLMAP_DB
  std::unique_ptr<DatabaseQueries> database_;
#endif
};

// The signal that asked the batch to stop (SIGINT or SIGTERM), else 0; lock-free, so a signal
// handler may set it.
std::atomic<int> stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

void RequestStop(int signal_number) { stop_signal = signal_number; }

// How long a stopped batch waits for its running queries (a large photo's SIFT takes seconds).
constexpr std::chrono::seconds kStopGrace{1};

// Ctrl-C or a plain kill lets the running queries finish, for up to kStopGrace, and puts every
// finished record in place; a second one ends the process at once (SA_RESETHAND).
void StopOnInterrupt() {
  struct sigaction action {};
  action.sa_handler = RequestStop;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (const int signal_number : {SIGINT, SIGTERM}) sigaction(signal_number, &action, nullptr);
}

// --rig or --frames: every frame localized as one rig.
int RunRigs(const CliOptions& cli, const Index& index) {
  const std::vector<RigFrameInput> frames = CollectRigFrames(cli);
#ifdef __GLIBC__
  // A frame holds all its images' features at once, megabytes that glibc would hand back to the
  // system after every frame and fault in again for the next (5-9 ms a frame of four 8k-feature
  // images, measured): keep up to 64 MB of them.
  mallopt(M_MMAP_THRESHOLD, 64 << 20);
  mallopt(M_TRIM_THRESHOLD, 64 << 20);
#endif
  QueryOptions query_options = cli.options;
  const int threads = std::max(1, std::min<int>(cli.threads, static_cast<int>(frames.size())));
  query_options.photo.sift.num_threads = std::max(1, cli.threads / threads);
  const QueryLoader loader(cli, query_options);
  ResultSink sink(cli);
  const Localizer localizer(index);
  RigRunCounts counts = RunRigFrames(
      cli, frames, localizer,
      [&](const RigFrameImage& image) { return loader.LoadRigImage(image); }, sink, stop_signal);
  sink.Close();
  if (const int signal_number = stop_signal) {
    std::fprintf(stderr, "cwloc-localize: interrupted by %s\n",
                 signal_number == SIGINT ? "SIGINT" : "SIGTERM");
    return 128 + signal_number;
  }
  std::sort(counts.seconds.begin(), counts.seconds.end());
  if (!cli.quiet) {
    std::fprintf(stderr, "cwloc-localize: localized %d of %zu rig frames", counts.localized,
                 frames.size());
    if (counts.errors > 0) std::fprintf(stderr, " (%d bad input)", counts.errors);
    if (counts.internal_errors > 0)
      std::fprintf(stderr, " (%d out of memory or internal error)", counts.internal_errors);
    if (!counts.seconds.empty()) {
      std::fprintf(stderr, ", median %.1f ms per frame",
                   counts.seconds[counts.seconds.size() / 2] * 1e3);
    }
    std::fprintf(stderr, "\n");
  }
  if (counts.internal_errors > 0) return kExitInternalError;
  if (counts.errors > 0) return kExitBadInput;
  return counts.failed > 0 ? kExitNotLocalized : kExitOk;
}

// Refuses, before any work, options that do not go together.
void CheckRunOptions(const CliOptions& cli, bool sequence) {
  if (cli.threads < 1 || cli.threads > 1024)
    throw InputError("--threads must be between 1 and 1024");
  if (!cli.motion_path.empty() && !sequence)
    throw InputError("--motion needs --sequence or --video (a motion is between frames)");
  if (!cli.trajectory_path.empty() && !sequence)
    throw InputError("--trajectory needs --sequence (a trajectory is a sequence's frames)");
  TrajectoryFormatNamed(cli.trajectory_format);
#ifndef CWLOC_WITH_VIDEO
  if (!cli.video_path.empty())
    throw InputError("--video: this cwloc-localize was built without FFmpeg (CWLOC_WITH_VIDEO)");
#endif
}

Index OpenIndex(const CliOptions& cli) {
  Index index = Index::Open(cli.index_path);
  if (cli.verify) {
    index.file().VerifyChecksums();
    index.Validate();
  }
  return index;
}

// --motion's lines by frame name; every line names a frame: a query of the sequence, or
// VIDEO#INDEX for a video's.
std::unordered_map<std::string, MotionLine> ReadMotions(const CliOptions& cli,
                                                        const std::vector<QuerySource>& sources) {
  if (cli.motion_path.empty()) return {};
  std::unordered_map<std::string, MotionLine> motions = ReadMotionFile(cli.motion_path);
  std::unordered_set<std::string> names;
  for (const QuerySource& source : sources) names.insert(source.name);
  const std::string video_prefix = cli.video_path + "#";
  for (const auto& [name, motion] : motions) {
    const bool video_frame =
        !cli.video_path.empty() && name.rfind(video_prefix, 0) == 0 &&
        name.size() > video_prefix.size() &&
        name.find_first_not_of("0123456789", video_prefix.size()) == std::string::npos;
    if (!names.count(name) && !video_frame) {
      throw InputError(cli.motion_path + ":" + std::to_string(motion.line) + ": frame '" + name +
                       "' is not in the sequence");
    }
  }
  return motions;
}

// A batch's outcomes so far, counted by its workers.
struct BatchCounts {
  std::atomic<int> localized{0}, failed{0}, errors{0}, internal_errors{0};
  std::atomic<int> modes[EnumNames<TrackingMode>::names.size()] = {};  // of tracked frames

  int Done() const { return localized + failed + errors + internal_errors; }
  int ExitCode() const {
    if (internal_errors > 0) return kExitInternalError;
    if (errors > 0) return kExitBadInput;
    return failed > 0 ? kExitNotLocalized : kExitOk;
  }
};

// One query: read, localized or tracked, written; its seconds, or -1 when it was an error.
using ProcessQuery = std::function<double(const std::string& name, const std::string& label,
                                          const std::function<Query()>& load, FrameStamp stamp)>;

// After SIGINT or SIGTERM: how far the batch got, and the shell's code for a process a signal
// ended. With queries still running (`abandoned`), whose threads use the caller's objects, the
// process ends here, without unwinding.
int ReportInterrupted(int signal_number, const BatchCounts& counts, size_t total, int abandoned) {
  std::fprintf(stderr, "cwloc-localize: interrupted by %s after %d of %zu queries",
               signal_number == SIGINT ? "SIGINT" : "SIGTERM", counts.Done(), total);
  if (abandoned > 0) {
    std::fprintf(stderr, "; %d running %s abandoned\n", abandoned,
                 abandoned == 1 ? "query" : "queries");
    std::cout.flush();
    std::fflush(nullptr);
    std::_Exit(128 + signal_number);
  }
  std::fprintf(stderr, "\n");
  return 128 + signal_number;
}

#ifdef CWLOC_WITH_VIDEO
// --video: the frames as they are decoded, on this thread, or with `decode_ahead` on a thread
// of their own, the next frame while this one is tracked; each frame's seconds appended to
// `times`. A stream that breaks ends the run once the frames before the break are written.
void RunVideo(const CliOptions& cli, const QueryOptions& query_options, bool decode_ahead,
              const QueryLoader& loader, const ProcessQuery& process, ResultSink& sink,
              std::vector<double>* times) {
  VideoFrames video(cli.video_path, query_options.photo.max_image_pixels);
  std::optional<FramesDecodedAhead> ahead;
  if (decode_ahead) ahead.emplace(video, cli.video_step);
  Progress progress("tracking", std::max<uint64_t>(video.estimated_frames() / cli.video_step, 1));
  std::string broken;
  while (!sink.failed() && stop_signal == 0) {
    std::optional<VideoFrame> frame;
    try {
      frame = ahead ? ahead->Next() : video.Next(cli.video_step);
    } catch (const InputError& e) {
      broken = e.what();
      break;
    }
    if (!frame) break;
    const std::string name = cli.video_path + "#" + std::to_string(frame->index);
    times->push_back(process(
        name, name, [&] { return loader.LoadFrame(name, std::move(frame->image)); },
        FrameStamp{frame->seconds, true}));
    progress.Advance();
  }
  progress.Finish();
  if (!broken.empty()) {
    sink.Close();
    throw InputError(broken);
  }
}
#endif

// The listed queries on `threads` threads of their own, each query's seconds in `times`. This
// thread waits for them to finish or for a stop, after which the running queries get
// kStopGrace to finish; past it, they are abandoned and the process ends.
void RunListed(const std::vector<QuerySource>& sources, int threads, const QueryLoader& loader,
               const ProcessQuery& process, ResultSink& sink, const BatchCounts& counts,
               std::vector<double>* times) {
  std::atomic<size_t> next{0};
  Progress progress("localizing", sources.size());
  auto worker = [&] {
    for (size_t i = next++; i < sources.size() && !sink.failed() && stop_signal == 0; i = next++) {
      (*times)[i] = process(
          sources[i].name, sources[i].Label(), [&] { return loader.Load(sources[i]); },
          FrameStamp{double(i), false});  // a list's frames: their place
      progress.Advance();
    }
  };
  std::mutex done_mutex;
  std::condition_variable done;
  int running = threads;
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    pool.emplace_back([&] {
      worker();
      const std::lock_guard lock(done_mutex);
      --running;
      done.notify_all();
    });
  }
  int abandoned = 0;
  {
    std::unique_lock lock(done_mutex);
    while (running > 0 && stop_signal == 0) done.wait_for(lock, std::chrono::milliseconds(50));
    done.wait_for(lock, kStopGrace, [&] { return running == 0; });
    abandoned = running;
  }
  for (auto& thread : pool) abandoned > 0 ? thread.detach() : thread.join();
  progress.Finish();
  if (abandoned > 0) {
    // Only a stop abandons queries; their threads use this function's objects.
    sink.Close();
    ReportInterrupted(stop_signal, counts, sources.size(), abandoned);
  }
}

// The batch's summary line on stderr: counts, and the median seconds of the finished queries.
void PrintSummary(const BatchCounts& counts, const std::vector<double>& times, bool tracked) {
  std::vector<double> finished;
  for (double t : times) {
    if (t >= 0) finished.push_back(t);
  }
  std::sort(finished.begin(), finished.end());
  std::fprintf(stderr, "cwloc-localize: localized %d of %zu queries", counts.localized.load(),
               times.size());
  if (counts.errors > 0) std::fprintf(stderr, " (%d bad input)", counts.errors.load());
  if (counts.internal_errors > 0) {
    std::fprintf(stderr, " (%d out of memory or internal error)", counts.internal_errors.load());
  }
  if (tracked) {
    std::fprintf(stderr, " (%d tracked, %d relocalized, %d lost)", counts.modes[0].load(),
                 counts.modes[1].load(), counts.modes[2].load());
  }
  if (!finished.empty())
    std::fprintf(stderr, ", median %.1f ms per query", finished[finished.size() / 2] * 1e3);
  std::fprintf(stderr, "\n");
}

int Run(const CliOptions& cli) {
  // First: a signal while the index and queries are read stops the batch before its first query.
  StopOnInterrupt();
  const LocalizerOptions& options = cli.options.localizer;
  const bool sequence = cli.sequence || !cli.video_path.empty();
  CheckRunOptions(cli, sequence);
  const Index index = OpenIndex(cli);
  if (!cli.rig_config_path.empty() || !cli.frames_path.empty()) return RunRigs(cli, index);
  const std::vector<QuerySource> sources = CollectQueries(cli);
  const std::unordered_map<std::string, MotionLine> motions = ReadMotions(cli, sources);
  const auto motion_of = [&](const std::string& name) -> std::optional<FrameMotion> {
    const auto found = motions.find(name);
    if (found == motions.end()) return std::nullopt;
    return found->second.motion;
  };
  // --threads goes to queries first; a photo's SIFT gets the threads no other query uses (one
  // photo and --threads 4: four threads inside it). Its features do not depend on them.
  // A sequence's frames are tracked in order, one after the other; a video's next frame is
  // decoded meanwhile on a thread of its own when there are two.
  const int threads =
      sequence ? 1 : std::max(1, std::min<int>(cli.threads, static_cast<int>(sources.size())));
  const bool decode_ahead = !cli.video_path.empty() && cli.threads > 1;
  QueryOptions query_options = cli.options;
  query_options.photo.sift.num_threads = (cli.threads - decode_ahead) / threads;
  const QueryLoader loader(cli, query_options);
  ResultSink sink(cli);
  const Localizer localizer(index);
  std::optional<Tracker> tracker;
  if (sequence) tracker.emplace(localizer, options, cli.options.tracker);

  BatchCounts counts;
  const ProcessQuery process = [&](const std::string& name, const std::string& label,
                                   const std::function<Query()>& load, FrameStamp stamp) {
    try {
      const Query query = load();
      const LocalizationResult result =
          tracker ? tracker->Track(
                        query, stamp.seconds ? std::optional<double>(stamp.value) : std::nullopt,
                        motion_of(query.name))
                  : localizer.Localize(query, options);
      if (result.tracking) ++counts.modes[static_cast<size_t>(result.tracking->mode)];
      (result.success ? counts.localized : counts.failed)++;
      sink.Write(result, cli.options, stamp);
      return result.times.total;
    } catch (const InputError& e) {
      ++counts.errors;
      sink.WriteError(name, e.what());
    } catch (const std::bad_alloc&) {
      // A query too big for the memory left (a huge photo on a small device) must not end
      // the batch: its buffers are freed by now.
      ++counts.internal_errors;
      sink.WriteError(name, label + ": out of memory");
    } catch (const std::exception& e) {
      ++counts.internal_errors;
      sink.WriteError(name, label + ": internal error: " + e.what());
    }
    return -1.0;
  };
  std::vector<double> times(sources.size(), -1);
  if (!cli.video_path.empty()) {
#ifdef CWLOC_WITH_VIDEO
    RunVideo(cli, query_options, decode_ahead, loader, process, sink, &times);
#endif
  } else {
    RunListed(sources, threads, loader, process, sink, counts, &times);
  }
  sink.Close();
  if (const int signal_number = stop_signal)
    return ReportInterrupted(signal_number, counts, times.size(), 0);
  if (!cli.quiet) PrintSummary(counts, times, tracker.has_value());
  return counts.ExitCode();
}

// cwloc-localize's --help groups.
constexpr const char* kQueries = "Queries";
constexpr const char* kOutput = "Output";

// The flags of the queries' sources, cameras and priors.
void AddQueryFlags(CLI::App* app, CliOptions* cli) {
#ifdef CWLOC_WITH_COLMAP_DB
  app->add_option("--database", cli->database_path,
                  "COLMAP database holding the queries' keypoints and descriptors")
      ->group(kQueries);
#endif
  app->add_option("--image", cli->images,
                  "Query photo, JPEG or PNG (repeatable): SIFT is extracted as colmap "
                  "feature_extractor does")
      ->group(kQueries);
  app->add_option("--image-list", cli->image_list,
                  "File of query photos, one per line, optionally followed by 'MODEL W H PARAMS' "
                  "(hloc's queries_with_intrinsics.txt)")
      ->group(kQueries);
  app->add_option("--image-dir", cli->image_dir,
                  "Folder the --image-list names are relative to (default: the list's folder)")
      ->group(kQueries);
  app->add_option("--query", cli->query_names, "Query image name in --database (repeatable)")
      ->group(kQueries);
  app->add_option("--query-list", cli->query_list,
                  "File of queries, one per line: a name in --database (or a feature file), "
                  "optionally followed by "
                  "'MODEL W H PARAMS' (hloc's queries_with_intrinsics.txt)")
      ->group(kQueries);
  app->add_option("--features", cli->feature_files,
                  "COLMAP text feature file ('N 128', then 'x y scale orientation d1..d128' lines; "
                  "repeatable)")
      ->group(kQueries);
  auto* camera = app->add_option("--camera", cli->camera_spec,
                                 "Query camera 'MODEL W H PARAMS...' (known focal)")
                     ->group(kQueries);
  app->add_option("--image-size", cli->image_size,
                  "Query image size 'W H' when the focal length is unknown (P4Pf)")
      ->excludes(camera)
      ->group(kQueries);
  app->add_option("--focal", cli->focal,
                  "Query focal length in pixels, a prior: refined with a radial distortion term "
                  "(principal point at the image centre)")
      ->excludes(camera)
      ->group(kQueries);
  app->add_flag(
         "--unknown-focal", cli->unknown_focal,
         "Withhold the focal length: P4Pf estimates it, then focal and radial distortion are "
         "refined")
      ->group(kQueries);
  app->add_option("--prior-position", cli->prior_position,
                  "GPS prior 'LAT LON [HEIGHT] RADIUS_M' (WGS84): only model cameras within the "
                  "radius are matched; needs a georeferenced index")
      ->group(kQueries);
  app->add_option(
         "--prior-gravity", cli->prior_gravity,
         "Gravity direction 'GX GY GZ' in the camera frame (x right, y down, z forward), as "
         "an IMU gives it; needs a georeferenced index")
      ->group(kQueries);
  app->add_option("--priors", cli->priors_path,
                  "Per-query priors: lines 'NAME position LAT LON HEIGHT|- RADIUS_M' and 'NAME "
                  "gravity GX GY GZ'")
      ->group(kQueries);
}

void AddOutputFlags(CLI::App* app, CliOptions* cli) {
  app->add_option("-o,--output", cli->output_path,
                  "JSON lines output (default: stdout). A file keeps its previous content until "
                  "this run's first records replace it, about a second in, and only ever holds "
                  "whole lines, saved about once a second")
      ->group(kOutput);
  app->add_option("--poses", cli->poses_path,
                  "Also write 'NAME QW QX QY QZ TX TY TZ' lines of localized queries (saved as -o "
                  "is)")
      ->group(kOutput);
  app->add_option("--trajectory", cli->trajectory_path,
                  "With --sequence: also write the frames' poses as a trajectory in "
                  "--trajectory-format (the timestamp is a video frame's time, else the frame's "
                  "place in the sequence, from 0; saved as -o is)")
      ->group(kOutput);
  app->add_option("--trajectory-format", cli->trajectory_format,
                  "tum: 'TIMESTAMP TX TY TZ QX QY QZ QW', the camera in the world, as evo reads "
                  "it; kapture: its trajectories.txt, 'TIMESTAMP, camera, QW, QX, QY, QZ, TX, TY, "
                  "TZ', the world in the camera; lamar: LaMAR's trajectories.txt, the camera in "
                  "the world and its 6 x 6 covariance (docs/cli.md); kapture and lamar write "
                  "microseconds")
      ->capture_default_str()
      ->group(kOutput);
  app->add_flag("-q,--quiet", cli->quiet, "No summary or readable lines")->group(kOutput);
}

// The flags of a sequence's frames: --video, --motion, --sequence.
void AddSequenceFlags(CLI::App* app, CliOptions* cli) {
  app->add_option("--video", cli->video_path,
                  "A video file (MP4, MOV, MKV, ...; FFmpeg reads it): its frames are a sequence "
                  "(as --sequence), named FILE#FRAME_INDEX, the trajectory's timestamps their "
                  "times; the camera from --camera or --focal, else only the frames' size")
      ->group(kQueries);
  app->add_option("--video-step", cli->video_step, "Every Nth frame of --video")
      ->check(CLI::Range(1u, 1000000u))
      ->capture_default_str()
      ->group(kQueries);
  app->add_option("--motion", cli->motion_path,
                  "With --sequence or --video: each frame's camera motion since the previous "
                  "frame from VIO, lines 'NAME QW QX QY QZ TX TY TZ [SIGMA_ROT_DEG SIGMA_POS]' "
                  "(the frame's camera from the previous one's, metres: model units by a "
                  "georeferenced index's scale, else only the direction counts; optionally its "
                  "standard deviation per axis, which bounds how far the tracked pose may land "
                  "from the prediction); it predicts the frame's pose")
      ->group(kQueries);
  app->add_flag("--sequence", cli->sequence,
                "The queries are frames of one moving camera, in the order given: each is "
                "tracked from the frames before it, or localized from scratch when that fails "
                "(docs/algorithm.md, \"Sequences\"); one frame at a time")
      ->group(kQueries);
}

// The flags of rigs and multi-image frames.
void AddRigFlags(CLI::App* app, CliOptions* cli) {
  app->add_option("--rig", cli->rig_config_path,
                  "COLMAP 3.12's rig_config.json: the --image-list images are cameras of rigs "
                  "(by image_prefix), and images whose names agree after the prefix one frame, "
                  "localized as one generalized camera (docs/cli.md, \"Rigs and multi-frame "
                  "queries\"); translations in model units")
      ->group(kQueries);
  app->add_option("--frames", cli->frames_path,
                  "Multi-image frames, one line per image: 'FRAME_ID IMAGE QW QX QY QZ TX TY TZ "
                  "[MODEL W H PARAMS]', the image's cam_from_rig (its camera from the frame's "
                  "reference), a frame's lines consecutive, its first image the reference; IMAGE "
                  "a photo, or a feature file (.txt), relative to --image-dir or the file's folder")
      ->group(kQueries);
  app->add_option("--frames-scale", cli->frames_scale,
                  "known: cam_from_rig translations are in model units; unknown: up to one scale "
                  "per frame (VIO without a metric map), which the pose estimates")
      ->capture_default_str()
      ->group(kQueries);
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{"cwloc-localize: 6-DoF camera poses of query images against a cwloc index"};
  app.set_version_flag("--version", std::string("cwloc-localize ") + cwloc::kToolVersion);
  cwloc::CliOptions cli;

  app.add_option("--index", cli.index_path, "Index file built by cwloc-index")->required();
  cwloc::AddQueryFlags(&app, &cli);
  cwloc::AddOutputFlags(&app, &cli);
  app.add_option("--threads", cli.threads,
                 "Threads: queries localized in parallel, and a photo's SIFT gets those no other "
                 "query uses (with --video: one decodes the next frame, SIFT gets the rest)")
      ->capture_default_str();
  cwloc::AddSequenceFlags(&app, &cli);
  cwloc::AddRigFlags(&app, &cli);
  app.add_flag("--verify", cli.verify,
               "Verify the index's checksums and stored indices before localizing");
  cwloc::TableFlags table_flags;
  table_flags.AddTo(&app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? cwloc::kExitOk : cwloc::kExitBadInput;
  }
  return cwloc::RunTool("cwloc-localize", [&] {
    table_flags.Apply(&cli.options);
    return cwloc::Run(cli);
  });
}
