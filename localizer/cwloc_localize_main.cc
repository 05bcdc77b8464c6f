// cwloc-localize: opens a cwloc index read-only and estimates query camera poses.
#include <signal.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <new>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "cwloc/version.h"
#include "format/base/checkpointed_file.h"
#include "format/base/error.h"
#include "format/base/progress.h"
#include "format/base/tool_main.h"
#include "format/index/index.h"
#include "localizer/io/camera_spec.h"
#include "localizer/io/feature_file.h"
#include "localizer/io/photo_query.h"
#include "localizer/io/query_list.h"
#include "localizer/io/query_priors.h"
#include "localizer/io/result_json.h"
#include "localizer/localizer.h"
#ifdef CWLOC_WITH_COLMAP_DB
#include "localizer/io/database/database_queries.h"
#endif

namespace cwloc {
namespace {

// One query to run: a database image name, a feature file or a photo, with an optional camera
// from its list line.
struct QuerySource {
  enum class Kind { kDatabase, kFeatureFile, kPhoto };
  std::string name;
  Kind kind = Kind::kDatabase;
  std::filesystem::path path;  // the feature file or photo
  std::string camera_spec;     // "MODEL W H PARAMS" from a list line, if any
  std::string list;            // the list file that line came from
};

// How an error names the query: its file, or its name in the database.
std::string SourceLabel(const QuerySource& source) {
  return source.path.empty() ? "query '" + source.name + "'" : source.path.string();
}

struct CliOptions {
  std::string index_path;
  std::string database_path;
  std::vector<std::string> query_names;
  std::string query_list;
  std::vector<std::string> feature_files;
  std::vector<std::string> images;
  std::string image_list;
  std::string image_dir;
  std::string camera_spec;
  std::string image_size;
  double focal = 0.0;
  bool unknown_focal = false;
  std::string prior_position;  // --prior-position, for every query
  std::string prior_gravity;   // --prior-gravity, for every query
  std::string priors_path;     // --priors: per query
  bool use_exif_gps = false;
  double exif_gps_radius_m = kDefaultExifGpsRadiusM;
  PhotoOptions photo;
  std::string output_path;
  std::string poses_path;
  int threads = 1;
  bool verify = false;
  bool quiet = false;
};

std::vector<QuerySource> CollectQueries(const CliOptions& cli) {
  using Kind = QuerySource::Kind;
  std::vector<QuerySource> sources;
  for (const std::string& name : cli.query_names)
    sources.push_back({name, Kind::kDatabase, {}, {}, {}});
  for (const std::string& file : cli.feature_files) {
    sources.push_back(
        {std::filesystem::path(file).filename().string(), Kind::kFeatureFile, file, {}, {}});
  }
  for (const std::string& image : cli.images) {
    sources.push_back(
        {std::filesystem::path(image).filename().string(), Kind::kPhoto, image, {}, {}});
  }
  if (!cli.query_list.empty()) {
    const std::filesystem::path base = std::filesystem::path(cli.query_list).parent_path();
    const Kind kind = cli.database_path.empty() ? Kind::kFeatureFile : Kind::kDatabase;
    for (const auto& [name, camera] : ReadQueryList(cli.query_list)) {
      sources.push_back(
          {name, kind, kind == Kind::kFeatureFile ? base / name : "", camera, cli.query_list});
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
  if (sources.empty()) {
    throw InputError("no queries: give --image, --image-list, --query, --query-list or --features");
  }
  return sources;
}

class QueryLoader {
 public:
  explicit QueryLoader(const CliOptions& cli) : cli_(cli) {
    if (!cli.camera_spec.empty()) camera_option_ = ParseCameraSpec(cli.camera_spec, "--camera");
    if (!cli.image_size.empty())
      image_size_option_ = ParseImageSize(cli.image_size, "--image-size");
    if (cli.focal != 0.0 && !(std::isfinite(cli.focal) && cli.focal > 0.0))
      throw InputError("--focal must be a positive number of pixels");
    ValidatePhotoOptions(cli.photo);
    if (!cli.prior_position.empty())
      position_option_ = ParsePositionPrior(cli.prior_position, "--prior-position");
    if (!cli.prior_gravity.empty())
      gravity_option_ = ParseGravityPrior(cli.prior_gravity, "--prior-gravity");
    if (!cli.priors_path.empty()) priors_ = ReadPriorsFile(cli.priors_path);
    ValidateExifGpsRadius(cli.exif_gps_radius_m);
#ifdef CWLOC_WITH_COLMAP_DB
    if (!cli.database_path.empty())
      database_ = std::make_unique<DatabaseQueries>(cli.database_path);
#endif
  }

  // Reads the query's features, then picks its camera once. The Localizer checks the query.
  Query Load(const QuerySource& source) const {
    Query query;
    switch (source.kind) {
      case QuerySource::Kind::kPhoto:
        query = LoadPhotoQuery(source.path, source.name, cli_.photo);
        break;
      case QuerySource::Kind::kFeatureFile:
        query = LoadFeatureFile(source);
        break;
      case QuerySource::Kind::kDatabase:
        query = LoadFromDatabase(source);
        break;
    }
    query.camera = ChooseCamera(source, query);
    if (cli_.unknown_focal) query.camera = WithUnknownFocal(query.camera);
    AddPriors(&query);
    return query;
  }

 private:
  // A list line's camera wins, then --camera, then --focal, then --image-size; a query's own
  // camera (a photo's EXIF or size, the database's camera) comes last.
  QueryCamera ChooseCamera(const QuerySource& source, const Query& query) const {
    const QueryCamera& own = query.camera;  // width 0 for feature files
    const bool photo = source.kind == QuerySource::Kind::kPhoto;
    QueryCamera camera = own;
    if (!source.camera_spec.empty()) {
      camera = ParseCameraSpec(source.camera_spec, source.list + " (" + source.name + ")");
      camera.source = IntrinsicsSource::kQueryList;
    } else if (camera_option_) {
      camera = *camera_option_;
    } else if (cli_.focal > 0.0) {
      const QueryCamera& sized = own.width > 0 || !image_size_option_ ? own : *image_size_option_;
      if (sized.width == 0) {
        throw InputError(query.Source() +
                         ": --focal needs the image size: give --image-size \"W H\"");
      }
      camera =
          FocalPriorCamera(cli_.focal, sized.width, sized.height, IntrinsicsSource::kFocalOption);
    } else if (image_size_option_ && !photo) {
      camera = *image_size_option_;
    }
    if (camera.width == 0) {
      throw InputError(query.Source() +
                       ": no camera: give --camera \"MODEL W H PARAMS\", --image-size \"W H\", or "
                       "a camera in the query list");
    }
    if (photo && (camera.width != own.width || camera.height != own.height)) {
      throw InputError(query.Source() + ": the camera is " + std::to_string(camera.width) + " x " +
                       std::to_string(camera.height) + " but the photo is " +
                       std::to_string(own.width) + " x " + std::to_string(own.height));
    }
    return camera;
  }

  // The priors file's line for this query wins, then --prior-*, then the photo's EXIF GPS.
  void AddPriors(Query* query) const {
    const auto listed = priors_.find(query->name);
    const QueryPriors* own = listed == priors_.end() ? nullptr : &listed->second;
    query->position_prior = own && own->position ? own->position : position_option_;
    if (!query->position_prior && cli_.use_exif_gps)
      query->position_prior = ExifPositionPrior(*query, cli_.exif_gps_radius_m);
    query->gravity = own && own->gravity ? own->gravity : gravity_option_;
  }

  static Query LoadFeatureFile(const QuerySource& source) {
    Query query;
    ReadFeatureFile(source.path, &query);
    query.name = source.name;
    query.source = source.path.string();
    return query;
  }

  Query LoadFromDatabase(const QuerySource& source) const {
#ifdef CWLOC_WITH_COLMAP_DB
    if (!database_) throw InputError(SourceLabel(source) + ": give --database to read it from");
    return database_->Load(source.name);
#else
    throw InputError(SourceLabel(source) +
                     ": this cwloc-localize was built without COLMAP database input");
#endif
  }

  const CliOptions& cli_;
  std::optional<QueryCamera> camera_option_;
  std::optional<QueryCamera> image_size_option_;
  std::optional<PositionPrior> position_option_;
  std::optional<std::array<double, 3>> gravity_option_;
  std::unordered_map<std::string, QueryPriors> priors_;
#ifdef CWLOC_WITH_COLMAP_DB
  std::unique_ptr<DatabaseQueries> database_;
#endif
};

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
  }

  void Write(const LocalizationResult& result, const LocalizerOptions& options) {
    std::lock_guard lock(mutex_);
    EmitJsonLine(ResultToJson(result, options).dump());
    // With the JSON in a file, stdout gets a readable line per query.
    if (json_file_ && !cli_.quiet) {
      if (result.success) {
        std::printf("%s: localized, %u inliers / %u correspondences, %.1f ms\n",
                    result.name.c_str(), result.num_inliers, result.correspondences,
                    result.times.total * 1e3);
      } else {
        std::printf("%s: not localized: %s\n", result.name.c_str(), result.failure_reason.c_str());
      }
      std::fflush(stdout);
    }
    if (poses_file_ && result.success) Append(*poses_file_, PoseLine(result));
  }

  void WriteError(const std::string& name, const std::string& error) {
    std::lock_guard lock(mutex_);
    EmitJsonLine(ErrorToJson(name, error).dump());
    std::fprintf(stderr, "cwloc-localize: error: %s\n", error.c_str());
  }

  bool failed() const { return failed_; }

  // Puts every record in place; throws the first write error.
  void Close() {
    std::lock_guard lock(mutex_);
    for (CheckpointedFile* file : {json_file_.get(), poses_file_.get()}) {
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
  std::mutex mutex_;
  std::atomic<bool> failed_{false};
  std::string error_;
};

// The signal that asked the batch to stop (SIGINT or SIGTERM), else 0; lock-free, so a signal
// handler may set it.
std::atomic<int> stop_signal{0};
static_assert(std::atomic<int>::is_always_lock_free);

void RequestStop(int signal_number) { stop_signal = signal_number; }

// Ctrl-C or a plain kill lets the running queries finish and puts every finished record in
// place; a second one ends the process at once (SA_RESETHAND).
void StopOnInterrupt() {
  struct sigaction action {};
  action.sa_handler = RequestStop;
  sigemptyset(&action.sa_mask);
  action.sa_flags = SA_RESETHAND;
  for (const int signal_number : {SIGINT, SIGTERM}) sigaction(signal_number, &action, nullptr);
}

int Run(const CliOptions& cli, const LocalizerOptions& options) {
  ValidateLocalizerOptions(options);
  if (cli.threads < 1 || cli.threads > 1024)
    throw InputError("--threads must be between 1 and 1024");
  const Index index = Index::Open(cli.index_path);
  if (cli.verify) {
    index.file().VerifyChecksums();
    index.Validate();
  }
  const std::vector<QuerySource> sources = CollectQueries(cli);
  const QueryLoader loader(cli);
  ResultSink sink(cli);
  const Localizer localizer(index);

  std::atomic<size_t> next{0};
  std::atomic<int> localized{0}, failed{0}, errors{0}, internal_errors{0};
  std::vector<double> times(sources.size(), -1);
  Progress progress("localizing", sources.size());
  auto worker = [&] {
    for (size_t i = next++; i < sources.size() && !sink.failed() && stop_signal == 0; i = next++) {
      try {
        const Query query = loader.Load(sources[i]);
        const LocalizationResult result = localizer.Localize(query, options);
        times[i] = result.times.total;
        (result.success ? localized : failed)++;
        sink.Write(result, options);
      } catch (const InputError& e) {
        ++errors;
        sink.WriteError(sources[i].name, e.what());
      } catch (const std::bad_alloc&) {
        // A query too big for the memory left (a huge photo on a small device) must not end
        // the batch: its buffers are freed by now.
        ++internal_errors;
        sink.WriteError(sources[i].name, SourceLabel(sources[i]) + ": out of memory");
      } catch (const std::exception& e) {
        ++internal_errors;
        sink.WriteError(sources[i].name, SourceLabel(sources[i]) + ": internal error: " + e.what());
      }
      progress.Advance();
    }
  };
  StopOnInterrupt();
  std::vector<std::thread> pool;
  const int threads = std::min<int>(cli.threads, static_cast<int>(sources.size()));
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& thread : pool) thread.join();
  progress.Finish();
  sink.Close();
  if (const int signal_number = stop_signal) {
    std::fprintf(stderr, "cwloc-localize: interrupted by %s after %d of %zu queries\n",
                 signal_number == SIGINT ? "SIGINT" : "SIGTERM",
                 localized + failed + errors + internal_errors, sources.size());
    return 128 + signal_number;  // the shell's code for a process a signal ended
  }

  std::vector<double> finished;
  for (double t : times) {
    if (t >= 0) finished.push_back(t);
  }
  std::sort(finished.begin(), finished.end());
  if (!cli.quiet) {
    std::fprintf(stderr, "cwloc-localize: localized %d of %zu queries", localized.load(),
                 sources.size());
    if (errors > 0) std::fprintf(stderr, " (%d bad input)", errors.load());
    if (internal_errors > 0)
      std::fprintf(stderr, " (%d out of memory or internal error)", internal_errors.load());
    if (!finished.empty())
      std::fprintf(stderr, ", median %.1f ms per query", finished[finished.size() / 2] * 1e3);
    std::fprintf(stderr, "\n");
  }
  if (internal_errors > 0) return kExitInternalError;
  if (errors > 0) return kExitBadInput;
  return failed > 0 ? kExitNotLocalized : kExitOk;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{"cwloc-localize: 6-DoF camera poses of query images against a cwloc index"};
  app.set_version_flag("--version", std::string("cwloc-localize ") + cwloc::kToolVersion);
  cwloc::CliOptions cli;
  cwloc::LocalizerOptions options;

  app.add_option("--index", cli.index_path, "Index file built by cwloc-index")->required();
#ifdef CWLOC_WITH_COLMAP_DB
  app.add_option("--database", cli.database_path,
                 "COLMAP database holding the queries' keypoints and descriptors");
#endif
  app.add_option("--image", cli.images,
                 "Query photo, JPEG or PNG (repeatable): SIFT is extracted as colmap "
                 "feature_extractor does");
  app.add_option("--image-list", cli.image_list,
                 "File of query photos, one per line, optionally followed by 'MODEL W H PARAMS' "
                 "(hloc's queries_with_intrinsics.txt)");
  app.add_option("--image-dir", cli.image_dir,
                 "Folder the --image-list names are relative to (default: the list's folder)");
  app.add_option("--max-image-size", cli.photo.max_image_size,
                 "Photos are shrunk so that their longer side is at most this before SIFT "
                 "(COLMAP's --SiftExtraction.max_image_size)")
      ->capture_default_str();
  app.add_option("--max-features", cli.photo.sift.max_num_features,
                 "SIFT keeps whole scale levels, coarse first, until their count exceeds this "
                 "(COLMAP's --SiftExtraction.max_num_features)")
      ->capture_default_str();
  app.add_option("--max-image-pixels", cli.photo.max_image_pixels,
                 "Photos with more pixels are refused before decoding")
      ->capture_default_str();
  app.add_option("--query", cli.query_names, "Query image name in --database (repeatable)");
  app.add_option("--query-list", cli.query_list,
                 "File of queries, one per line: a name in --database (or a feature file), "
                 "optionally followed by "
                 "'MODEL W H PARAMS' (hloc's queries_with_intrinsics.txt)");
  app.add_option("--features", cli.feature_files,
                 "COLMAP text feature file ('N 128', then 'x y scale orientation d1..d128' lines; "
                 "repeatable)");
  auto* camera = app.add_option("--camera", cli.camera_spec,
                                "Query camera 'MODEL W H PARAMS...' (known focal)");
  app.add_option("--image-size", cli.image_size,
                 "Query image size 'W H' when the focal length is unknown (P4Pf)")
      ->excludes(camera);
  app.add_option("--focal", cli.focal,
                 "Query focal length in pixels, a prior: refined with a radial distortion term "
                 "(principal point at the image centre)")
      ->excludes(camera);
  app.add_flag(
      "--unknown-focal", cli.unknown_focal,
      "Withhold the focal length: P4Pf estimates it, then focal and radial distortion are refined");
  app.add_option("--prior-position", cli.prior_position,
                 "GPS prior 'LAT LON [HEIGHT] RADIUS_M' (WGS84): only model cameras within the "
                 "radius are matched; needs a georeferenced index");
  app.add_option(
      "--prior-gravity", cli.prior_gravity,
      "Gravity direction 'GX GY GZ' in the camera frame (x right, y down, z forward), as "
      "an IMU gives it; needs a georeferenced index");
  app.add_option("--prior-gravity-sigma", options.prior_gravity_sigma_deg,
                 "Standard deviation of --prior-gravity, degrees")
      ->capture_default_str();
  app.add_option("--priors", cli.priors_path,
                 "Per-query priors: lines 'NAME position LAT LON HEIGHT|- RADIUS_M' and 'NAME "
                 "gravity GX GY GZ'");
  app.add_flag("--use-exif-gps", cli.use_exif_gps,
               "Use a photo's EXIF GPS as a position prior (horizontal, --exif-gps-radius)");
  app.add_option("--exif-gps-radius", cli.exif_gps_radius_m, "Radius of the EXIF GPS prior, metres")
      ->capture_default_str();
  app.add_option("-o,--output", cli.output_path,
                 "JSON lines output (default: stdout). A file keeps its previous content until "
                 "this run's first records replace it, about a second in, and only ever holds "
                 "whole lines, saved about once a second");
  app.add_option("--poses", cli.poses_path,
                 "Also write 'NAME QW QX QY QZ TX TY TZ' lines of localized queries (saved as -o "
                 "is)");
  app.add_option("--threads", cli.threads, "Queries localized in parallel")->capture_default_str();
  app.add_flag("--verify", cli.verify,
               "Verify the index's checksums and stored indices before localizing");
  app.add_flag("-q,--quiet", cli.quiet, "No summary or readable lines");

  std::string matcher = "cluster-wise";
  app.add_option(
         "--matcher", matcher,
         "cluster-wise (the paper), global-ratio (diagnostic baseline) or cluster-exhaustive (the "
         "paper's brute-force gold standard; slow)")
      ->check(CLI::IsMember(
          std::vector<std::string>(cwloc::kMatcherNames.begin(), cwloc::kMatcherNames.end())))
      ->capture_default_str();
  app.add_option("--k", options.k, "Nearest neighbours per query feature (k; k+1 are searched)")
      ->capture_default_str();
  app.add_option("--checks", options.checks, "kd-forest leaf checks per search")
      ->capture_default_str();
  app.add_option("--ratio", options.ratio, "Ratio test threshold tau")->capture_default_str();
  app.add_option("--nf", options.forward_matches, "N_F: forward matches passing both ratio tests")
      ->capture_default_str();
  app.add_option("--nb", options.back_matches, "N_B: back-matches to collect")
      ->capture_default_str();
  app.add_option("--max-back-images", options.max_back_images, "Clusters to back-match at most")
      ->capture_default_str();
  app.add_option("--min-vote-matches", options.min_matches_to_vote,
                 "Back-matches a cluster needs to cast co-visibility votes")
      ->capture_default_str();
  app.add_option("--query-checks", options.query_tree_checks,
                 "Leaf checks in the query features' kd-forest")
      ->capture_default_str();
  app.add_option("--min-inliers", options.pose.min_inliers, "Inliers needed for success")
      ->capture_default_str();
  app.add_option("--max-error", options.pose.max_error_px,
                 "Inlier reprojection error threshold, pixels")
      ->capture_default_str();
  app.add_option("--min-ransac-iterations", options.pose.ransac.min_iterations,
                 "RANSAC samples at least this many hypotheses (COLMAP's min_num_trials)")
      ->capture_default_str();
  app.add_option("--max-ransac-iterations", options.pose.ransac.max_iterations,
                 "RANSAC iteration cap")
      ->capture_default_str();
  app.add_option("--ransac-confidence", options.pose.ransac.confidence,
                 "RANSAC stops once an all-inlier sample was drawn with this probability")
      ->capture_default_str();
  app.add_option("--seed", options.seed, "Seed of the feature order and RANSAC")
      ->capture_default_str();
  app.add_flag("!--no-refine", options.pose.refine, "Skip the final refinement");
  std::string refiner(cwloc::PoseRefinerName(options.pose.refiner));
  app.add_option("--refiner", refiner,
                 "Solver of the final refinement: ceres (Ceres' Levenberg-Marquardt, in builds "
                 "with Ceres) or builtin (ours, the same steps and poses without Ceres)")
      ->check(CLI::IsMember(std::vector<std::string>(cwloc::kPoseRefinerNames.begin(),
                                                     cwloc::kPoseRefinerNames.end())))
      ->capture_default_str();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? cwloc::kExitOk : cwloc::kExitBadInput;
  }
  options.matcher = *cwloc::ParseMatcher(matcher);
  options.pose.refiner = *cwloc::ParsePoseRefiner(refiner);
  return cwloc::RunTool("cwloc-localize", [&] { return cwloc::Run(cli, options); });
}
