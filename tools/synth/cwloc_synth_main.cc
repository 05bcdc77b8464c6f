// cwloc-synth: generates a city with globally repeated structure and writes it as real COLMAP
// data (model, database, queries with ground truth). See docs/synth.md.
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>

#include "base/error.h"
#include "base/stopwatch.h"
#include "camera/camera_models.h"
#include "cwloc/version.h"
#include "exe/tool_main.h"
#include "tools/synth/city_geo.h"
#include "tools/synth/city_scene.h"
#include "tools/synth/scene_writer.h"
#include "tools/synth/synth_options.h"

namespace cwloc::synth {
namespace {

uint64_t PeakMemoryBytes() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return uint64_t(usage.ru_maxrss) * 1024;  // kilobytes on Linux
}

std::string CommandLine(int argc, char** argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    std::string arg = i == 0 ? "cwloc-synth" : argv[i];
    if (arg.find_first_of(" \t'\"$") != std::string::npos) arg = "'" + arg + "'";
    line += (i ? " " : "") + arg;
  }
  return line;
}

// A one-line progress bar on stderr, only when stderr is a terminal.
class ProgressBar {
 public:
  ProgressBar() : enabled_(::isatty(STDERR_FILENO) == 1) {}
  ~ProgressBar() { Clear(); }
  CityScene::Progress Callback() {
    if (!enabled_) return {};
    return [this](std::string_view stage, double fraction) { Show(stage, fraction); };
  }
  void Clear() {
    std::lock_guard lock(mutex_);
    if (shown_) std::fprintf(stderr, "\r%60s\r", "");
    shown_ = false;
  }

 private:
  void Show(std::string_view stage, double fraction) {
    std::lock_guard lock(mutex_);
    if (shown_ && stage == stage_ && fraction < 1 && since_shown_.Seconds() < 0.1) return;
    since_shown_.Restart();
    stage_ = stage;
    const int filled = int(30 * std::clamp(fraction, 0.0, 1.0));
    std::fprintf(stderr, "\r%-16.*s [%s%s] %3d%%", int(stage.size()), stage.data(),
                 std::string(size_t(filled), '#').c_str(),
                 std::string(size_t(30 - filled), ' ').c_str(), int(100 * fraction));
    std::fflush(stderr);
    shown_ = true;
  }
  bool enabled_;
  bool shown_ = false;
  std::string stage_;
  Stopwatch since_shown_;
  std::mutex mutex_;
};

nlohmann::ordered_json Summary(const std::filesystem::path& output, const SynthKnobs& knobs,
                               const GeoOptions& geo, const CityScene& scene, bool text,
                               double scene_seconds, const WriteTimings& write,
                               double total_seconds) {
  const SceneOptions& o = scene.options();
  const SceneCounts& c = scene.counts();
  auto share = [](size_t part, size_t whole) { return whole ? double(part) / double(whole) : 0.0; };
  size_t min_features = SIZE_MAX, max_features = 0;
  for (const SceneImage& image : scene.images()) {
    if (image.query) continue;
    min_features = std::min(min_features, image.features.size());
    max_features = std::max(max_features, image.features.size());
  }
  if (c.mapping_images == 0) min_features = 0;
  nlohmann::ordered_json camera = {{"model", std::string(CameraModelName(o.camera.model_id))},
                                   {"width", o.camera.width},
                                   {"height", o.camera.height},
                                   {"params", o.camera.params}};
  nlohmann::ordered_json json;
  json["tool"] = "cwloc-synth";
  json["version"] = kToolVersion;
  json["output"] = output.string();
  json["seed"] = o.seed;
  json["knobs"] = {{"preset", knobs.preset},
                   {"views_target", knobs.views ? nlohmann::ordered_json(*knobs.views) : nullptr},
                   {"blocks_x", o.layout.blocks_x},
                   {"blocks_y", o.layout.blocks_y},
                   {"queries", o.queries},
                   {"path_step", o.path_step > 0 ? nlohmann::ordered_json(o.path_step) : nullptr},
                   {"rig_cameras", o.rig_cameras},
                   {"features_per_image", o.features_per_image},
                   {"clutter_fraction", o.clutter_fraction},
                   {"repetition", o.repetition},
                   {"motifs", o.motifs},
                   {"instance_noise", o.instance_noise},
                   {"camera", camera},
                   {"camera_spacing", o.layout.camera_spacing},
                   {"keypoint_noise", o.keypoint_noise},
                   {"point_noise", o.point_noise},
                   {"threads", o.threads},
                   {"text", text}};
  json["counts"] = {{"mapping_images", c.mapping_images},
                    {"queries", c.queries},
                    {"facades", c.facades},
                    {"scene_points", c.scene_points},
                    {"points3D", c.model_points},
                    {"views", c.views},
                    {"mean_track_length", share(c.views, c.model_points)},
                    {"features", c.features},
                    {"features_per_mapping_image",
                     {{"min", min_features},
                      {"mean", share(c.mapping_features, c.mapping_images)},
                      {"max", max_features}}},
                    {"clutter_features", c.clutter_features},
                    {"clutter_share", share(c.clutter_features, c.features)},
                    {"single_view_features", c.single_view_features},
                    {"distinct_motifs", c.distinct_motifs},
                    {"repeated_points", c.motif_model_points},
                    {"repeated_share", share(c.motif_model_points, c.model_points)},
                    {"repeated_view_share", share(c.motif_views, c.views)},
                    {"query_model_observations", c.query_model_observations},
                    {"min_query_model_points", c.min_query_model_points}};
  if (geo.origin) {
    const ModelFrame frame = MakeModelFrame(scene, geo);
    Eigen::Quaterniond q(frame.rotation);
    if (q.w() < 0) q.coeffs() *= -1;
    json["geo"] = {
        {"origin",
         {{"latitude_deg", geo.origin->latitude_deg},
          {"longitude_deg", geo.origin->longitude_deg},
          {"height_m", geo.origin->height_m}}},
        {"gps_noise_m", geo.gps_noise},
        {"gps_outliers", geo.gps_outliers},
        {"gps_outlier_images", NumGpsOutliers(geo, c.mapping_images)},
        {"prior_position_error_m", geo.prior_position_error},
        {"prior_radius_m", geo.prior_radius},
        {"prior_gravity_error_deg", geo.prior_gravity_error_deg},
        {"model_from_enu",
         {{"scale", frame.scale},
          {"rotation_wxyz", {q.w(), q.x(), q.y(), q.z()}},
          {"translation", {frame.translation.x(), frame.translation.y(), frame.translation.z()}}}}};
  }
  json["timings"] = {{"scene_seconds", scene_seconds},
                     {"model_seconds", write.model_seconds},
                     {"database_seconds", write.database_seconds},
                     {"files_seconds", write.files_seconds},
                     {"total_seconds", total_seconds}};
  json["peak_memory_bytes"] = PeakMemoryBytes();
  return json;
}

void PrintSummary(const nlohmann::ordered_json& s) {
  const auto& c = s["counts"];
  const auto& k = s["knobs"];
  const auto& t = s["timings"];
  std::printf("cwloc-synth: wrote %s (seed %llu)\n", s["output"].get<std::string>().c_str(),
              static_cast<unsigned long long>(s["seed"].get<uint64_t>()));
  std::printf("  city:     %d x %d blocks, %zu facades\n", k["blocks_x"].get<int>(),
              k["blocks_y"].get<int>(), c["facades"].get<size_t>());
  std::printf("  images:   %zu mapping, %zu queries", c["mapping_images"].get<size_t>(),
              c["queries"].get<size_t>());
  if (k["rig_cameras"].get<int>() > 1) {
    std::printf(" (%d frames of a %d-camera rig)", k["queries"].get<int>(),
                k["rig_cameras"].get<int>());
  }
  std::printf("\n");
  std::printf("  model:    %zu 3D points, %zu views (mean track %.2f)\n",
              c["points3D"].get<size_t>(), c["views"].get<size_t>(),
              c["mean_track_length"].get<double>());
  std::printf("  features: %zu, clutter %.1f%%\n", c["features"].get<size_t>(),
              100 * c["clutter_share"].get<double>());
  std::printf("  repeated: %zu distinct motifs; %.1f%% of 3D points, %.1f%% of views\n",
              c["distinct_motifs"].get<size_t>(), 100 * c["repeated_share"].get<double>(),
              100 * c["repeated_view_share"].get<double>());
  if (s.contains("geo")) {
    const auto& g = s["geo"];
    std::printf("  globe:    centre at %.8f %.8f %.2f m; %zu GPS outliers\n",
                g["origin"]["latitude_deg"].get<double>(),
                g["origin"]["longitude_deg"].get<double>(), g["origin"]["height_m"].get<double>(),
                g["gps_outlier_images"].get<size_t>());
  }
  std::printf(
      "  time:     %.2f s (scene %.2f, model %.2f, database %.2f, files %.2f); peak memory %.0f "
      "MB\n",
      t["total_seconds"].get<double>(), t["scene_seconds"].get<double>(),
      t["model_seconds"].get<double>(), t["database_seconds"].get<double>(),
      t["files_seconds"].get<double>(), double(s["peak_memory_bytes"].get<uint64_t>()) / 1e6);
}

}  // namespace
}  // namespace cwloc::synth

int main(int argc, char** argv) {
  using namespace cwloc::synth;
  CLI::App app{
      "cwloc-synth: generate a city with globally repeated structure, written as a COLMAP model, "
      "database and held-out queries with ground truth"};
  app.set_version_flag("--version", std::string("cwloc-synth ") + cwloc::kToolVersion);
  std::string output;
  SynthKnobs knobs;
  bool text = false, overwrite = false, json = false;
  app.add_option("-o,--output", output,
                 "Output directory (must not exist or be empty, see --overwrite)")
      ->required();
  app.add_option("--preset", knobs.preset,
                 "Preset: 'demo' (a small city in a few seconds); knobs override it");
  app.add_option("--seed", knobs.seed, "Seed; the same seed and knobs give byte-identical output")
      ->capture_default_str();
  app.add_option(
      "--views", knobs.views,
      "Approximate number of model views (observations); sets the number of blocks [200000]");
  app.add_option("--blocks", knobs.blocks, "Number of city blocks (overrides --views)");
  app.add_option("--queries", knobs.queries,
                 "Query images (in the database, not in the model) [100]");
  app.add_option("--features-per-image", knobs.features_per_image,
                 "Keypoints per image, clutter included [1500]");
  app.add_option("--clutter-fraction", knobs.clutter_fraction,
                 "Share of each image's features that belong to no 3D point, in [0, 1) [0.33]");
  app.add_option(
      "--repetition", knobs.repetition,
      "Share of facade points that are instances of globally repeated motifs, in [0, 1] [0.3]");
  app.add_option("--motifs", knobs.motifs, "Size of the global motif pool [256]");
  app.add_option("--instance-noise", knobs.instance_noise,
                 "How much two instances of one motif differ, in [0, 1] [0.3]");
  app.add_option("--camera-model", knobs.camera_model,
                 "SIMPLE_PINHOLE, PINHOLE, SIMPLE_RADIAL or RADIAL [SIMPLE_RADIAL]");
  app.add_option("--width", knobs.width, "Image width in pixels [1024]");
  app.add_option("--height", knobs.height, "Image height in pixels [768]");
  app.add_option("--focal", knobs.focal, "Focal length in pixels [900]");
  app.add_option("--radial", knobs.radial,
                 "Radial distortion k of SIMPLE_RADIAL / k1 of RADIAL [-0.01]");
  app.add_option("--camera-spacing", knobs.camera_spacing,
                 "Metres between mapping camera stations [3]");
  app.add_option("--path-step", knobs.path_step,
                 "The queries are the frames of one walk down a street, this many metres apart, "
                 "in order (for cwloc-localize --sequence); unset: independent cameras");
  app.add_option("--rig-cameras", knobs.rig_cameras,
                 "Cameras per query frame, in [1, 6]: 2 or more make every query a frame of a "
                 "rig turning all around (cam0/, cam1/, ...; rig_config.json) [1]");
  app.add_option("--keypoint-noise", knobs.keypoint_noise,
                 "Keypoint noise, pixels (sigma per axis) [0.7]");
  app.add_option(
      "--point-noise", knobs.point_noise,
      "Noise of the model's 3D points, metres (sigma at 20 m from the nearest camera) [0.01]");
  auto with_default = [](const std::string& help, double value) {
    std::ostringstream out;
    out << help << " [" << value << "]";
    return out.str();
  };
  app.add_option("--geo", knobs.geo,
                 "\"LAT LON HEIGHT\": put the city centre at this WGS84 position (ellipsoidal "
                 "height), write the model in a random SfM-like frame and add georef.txt, "
                 "georef_outliers.txt, queries_geo.txt and query_priors.txt");
  app.add_option("--gps-noise", knobs.gps_noise,
                 with_default("GPS noise of georef.txt, metres (sigma per axis; needs --geo)",
                              kDefaultGpsNoise));
  app.add_option("--gps-outliers", knobs.gps_outliers,
                 with_default("Share of mapping images with a wildly wrong GPS position "
                              "(100-1000 m off), in [0, 0.5] (needs --geo)",
                              kDefaultGpsOutliers));
  app.add_option("--prior-position-error", knobs.prior_position_error,
                 with_default("Query position priors lie exactly this many metres off the true "
                              "centre, horizontally (needs --geo)",
                              kDefaultPriorPositionError));
  app.add_option("--prior-radius", knobs.prior_radius,
                 with_default("Radius of the query position priors, metres (needs --geo)",
                              kDefaultPriorRadius));
  app.add_option("--prior-gravity-error", knobs.prior_gravity_error,
                 with_default("Query gravity priors are turned exactly this many degrees off "
                              "the true gravity (needs --geo)",
                              kDefaultPriorGravityErrorDeg));
  app.add_option("--threads", knobs.threads,
                 "Worker threads (0 = all cores); never changes the output")
      ->capture_default_str();
  app.add_flag("--text", text, "Also write mapping_model/txt");
  app.add_flag("--overwrite", overwrite, "Replace an existing non-empty output directory");
  app.add_flag("--json", json, "Print the summary as JSON (schemas/synth-summary.schema.json)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? cwloc::kExitOk : cwloc::kExitBadInput;
  }
  return cwloc::RunTool("cwloc-synth", [&]() -> int {
    const cwloc::Stopwatch total;
    const SceneOptions options = MakeSceneOptions(knobs);
    const GeoOptions geo = MakeGeoOptions(knobs);
    SceneWriter writer(output, overwrite);  // checks the output path before the long work
    ProgressBar bar;
    const CityScene scene = CityScene::Generate(options, bar.Callback());
    const double scene_seconds = total.Seconds();
    WriteOptions write_options;
    write_options.text = text;
    write_options.threads = options.threads;
    write_options.command_line = CommandLine(argc, argv);
    write_options.geo = geo;
    const WriteTimings timings = writer.Write(scene, write_options, bar.Callback());
    bar.Clear();
    const nlohmann::ordered_json summary = Summary(writer.output_dir(), knobs, geo, scene, text,
                                                   scene_seconds, timings, total.Seconds());
    writer.Commit(summary.dump(1) + "\n");
    if (json) {
      std::cout << summary.dump(2) << "\n";
    } else {
      PrintSummary(summary);
    }
    return cwloc::kExitOk;
  });
}
