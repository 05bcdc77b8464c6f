// cwloc-index: builds, inspects and verifies cwloc index files.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "base/error.h"
#include "base/stopwatch.h"
#include "cwloc/version.h"
#include "delta/apply_delta.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "format/xxhash64.h"
#include "indexer/build_option_table.h"
#include "indexer/index_build_flags.h"
#include "indexer/index_builder.h"
#include "indexer/index_extract.h"
#include "indexer/index_update.h"

namespace cwloc {
namespace {

nlohmann::ordered_json ParseManifest(const Index& index) {
  auto manifest =
      nlohmann::ordered_json::parse(index.manifest_json(), nullptr, /*allow_exceptions=*/false);
  if (manifest.is_discarded())
    throw InputError(index.file().path().string() + ": section 'MANI' is not valid JSON");
  return manifest;
}

// One line on where the model lies, and how well the positions fit.
void PrintGeoreference(const nlohmann::ordered_json& georeference) {
  const auto& origin = georeference["origin"];
  std::printf("  georeferenced (%s): ENU origin %.8f, %.8f, %.3f m; scale %.6g m per unit",
              georeference["source"].get<std::string>().c_str(),
              origin["latitude_deg"].get<double>(), origin["longitude_deg"].get<double>(),
              origin["height_m"].get<double>(), georeference["scale"].get<double>());
  if (georeference.contains("fit")) {
    const auto& fit = georeference["fit"];
    std::printf("; %s of %s positions fit, rms %.3f m, %zu outliers", fit["inliers"].dump().c_str(),
                fit["observations"].dump().c_str(), fit["rms_residual_m"].get<double>(),
                fit["outliers"].size());
  }
  std::printf("\n");
}

int RunBuild(const IndexBuildOptions& options, bool json) {
  const IndexBuildReport report = BuildIndex(options);
  if (json) {
    std::cout << BuildReportJson(options, report).dump(2) << "\n";
    return kExitOk;
  }
  std::printf(
      "wrote %s: %zu images, %zu points, %zu views, %zu clusters, %zu co-visibility edges\n",
      options.output_path.c_str(), report.num_images, report.num_points, report.num_views,
      report.num_clusters, report.num_covisibility_edges);
  std::printf(
      "%.1f MB, %.1f bytes per view; %.2f s (read %.2f, co-visibility %.2f, clustering %.2f, "
      "covariance calibration %.2f, codes %.2f, v_NN %.2f, kd-forest %.2f, write %.2f)\n",
      report.file_bytes / 1e6, double(report.file_bytes) / double(report.num_views),
      report.seconds_total, report.seconds_read, report.seconds_covisibility,
      report.seconds_clustering, report.seconds_calibration, report.seconds_point_codes,
      report.seconds_neighbor_distances, report.seconds_kd_forest, report.seconds_write);
  if (!report.georeference.is_null()) PrintGeoreference(report.georeference);
  return kExitOk;
}

int RunUpdate(const IndexUpdateOptions& options, bool json) {
  const IndexUpdateReport report = UpdateIndex(options);
  if (json) {
    std::cout << UpdateReportJson(options, report).dump(2) << "\n";
    return kExitOk;
  }
  if (report.rebuilt) {
    std::printf("rebuilt %s from the model (%zu images, %zu views, %.2f s): %s\n",
                options.output_path.c_str(), report.num_images, report.num_views,
                report.seconds_total, report.rebuild_reason.c_str());
    if (!options.delta_path.empty())
      std::printf("no delta written: devices need the whole index\n");
    return kExitOk;
  }
  std::printf(
      "wrote %s: %zu images (+%zu, -%zu, %zu changed), %zu points (+%zu, -%zu, %zu moved, %zu "
      "re-coded), %zu views (+%zu, -%zu)\n",
      options.output_path.c_str(), report.num_images, report.images_added, report.images_removed,
      report.images_changed, report.num_points, report.points_added, report.points_removed,
      report.points_moved, report.points_recoded, report.num_views, report.views_added,
      report.views_removed);
  std::printf("descriptors read from the database for %zu of %zu images (%s)\n", report.images_read,
              report.num_images,
              report.coded ? "those that see a point coded anew"
                           : "new and changed ones; the others' come from the index");
  std::printf("%.1f MB; v_NN of %zu clusters recomputed (%zu old %s changed); kd-forest %s\n",
              report.file_bytes / 1e6, report.clusters_recomputed,
              report.neighbor_distances_changed, report.coded ? "points" : "views",
              report.forest_rebuilt ? "rebuilt (balance bound)" : "updated by insertion");
  if (!options.delta_path.empty()) {
    std::printf("delta %s: %.3f MB (%.2f %% of the index)\n", options.delta_path.c_str(),
                report.delta_bytes / 1e6,
                100.0 * double(report.delta_bytes) / double(report.file_bytes));
  }
  std::printf(
      "%.2f s (read %.2f, compare %.2f, v_NN %.2f, tracks, co-visibility and kd-forest %.2f, "
      "write %.2f)\n",
      report.seconds_total, report.seconds_read, report.seconds_compare,
      report.seconds_neighbor_distances, report.seconds_apply, report.seconds_write);
  return kExitOk;
}

int RunApply(const std::filesystem::path& index, const std::filesystem::path& delta,
             const std::filesystem::path& output, int threads, bool json) {
  const ApplyDeltaReport report = ApplyDelta(index, delta, output, threads);
  if (json) {
    const nlohmann::ordered_json out = {
        {"output", output.string()},           {"file_bytes", report.file_bytes},
        {"parent_views", report.parent_views}, {"views", report.child_views},
        {"images", report.child_images},       {"seconds", report.seconds}};
    std::cout << out.dump(2) << "\n";
    return kExitOk;
  }
  std::printf(
      "wrote %s: %zu images, %zu views (the parent had %zu); %.1f MB, checksum as the "
      "delta names it; %.2f s\n",
      output.c_str(), report.child_images, report.child_views, report.parent_views,
      report.file_bytes / 1e6, report.seconds);
  return kExitOk;
}

int RunExtract(const IndexExtractOptions& options, bool json) {
  const IndexExtractReport report = ExtractIndex(options);
  if (json) {
    nlohmann::ordered_json out = {
        {"output", options.output_path.string()},
        {"file_bytes", report.file_bytes},
        {"bytes_per_view", double(report.file_bytes) / double(report.num_views)},
        {"counts",
         {{"cameras", report.num_cameras},
          {"images", report.num_images},
          {"points", report.num_points},
          {"views", report.num_views},
          {"clusters", report.num_clusters},
          {"covisibility_edges", report.num_covisibility_edges}}},
        {"parent", {{"images", report.parent_images}, {"views", report.parent_views}}},
        {"seconds", report.seconds_total}};
    if (!options.delta_path.empty()) {
      out["delta"] = {{"path", options.delta_path.string()},
                      {"bytes", report.delta_bytes},
                      {"parent_tile", options.parent_tile_path.string()},
                      {"forest_rebuilt", report.forest_rebuilt}};
    }
    std::cout << out.dump(2) << "\n";
    return kExitOk;
  }
  std::printf("wrote %s: %zu of %zu images (%zu clusters), %zu points, %zu of %zu views\n",
              options.output_path.c_str(), report.num_images, report.parent_images,
              report.num_clusters, report.num_points, report.num_views, report.parent_views);
  std::printf("%.1f MB, %.1f bytes per view; %.2f s\n", report.file_bytes / 1e6,
              double(report.file_bytes) / double(report.num_views), report.seconds_total);
  if (!options.delta_path.empty()) {
    std::printf("delta %s: %.3f MB (%.2f %% of the tile) from %s (%zu views); kd-forest %s\n",
                options.delta_path.c_str(), report.delta_bytes / 1e6,
                100.0 * double(report.delta_bytes) / double(report.file_bytes),
                options.parent_tile_path.c_str(), report.parent_tile_views,
                report.forest_rebuilt ? "rebuilt (balance bound)" : "updated by insertion");
  }
  return kExitOk;
}

// One line on the index a tile was cut from, and the region.
void PrintExtracted(const nlohmann::ordered_json& extracted) {
  const auto& from = extracted["from"];
  const auto& region = extracted["region"];
  std::string where;
  if (region.contains("near")) {
    const auto& near = region["near"];
    where = "cameras within " + near["radius_m"].dump() + " m of " + near["latitude_deg"].dump() +
            ", " + near["longitude_deg"].dump();
  } else {
    where = "the clusters of the images in " + region["images"].get<std::string>();
  }
  std::printf("  a tile of %s (%s images): %s\n", from["path"].get<std::string>().c_str(),
              from["counts"]["images"].dump().c_str(), where.c_str());
}

// What `info` says about how the descriptors are stored.
std::string DescriptorStorage(const Index& index) {
  if (!index.coded()) return "one 128-byte SIFT descriptor per view";
  char text[160];
  std::snprintf(text, sizeof(text),
                "one %u-byte product-quantization code per 3D point (%.2f views per point)",
                index.codes().code_bytes,
                double(index.num_views()) / double(std::max<size_t>(index.num_points(), 1)));
  return text;
}

int RunInfo(const std::string& path, bool json) {
  const Stopwatch open_time;
  const Index index = Index::Open(path);
  const double open_ms = open_time.Seconds() * 1e3;
  const nlohmann::ordered_json manifest = ParseManifest(index);
  const FileHeader& header = index.file().header();
  if (json) {
    nlohmann::ordered_json out;
    out["path"] = path;
    out["file_bytes"] = header.file_size;
    out["format_version"] =
        std::to_string(header.format_major) + "." + std::to_string(header.format_minor);
    out["bytes_per_view"] = double(header.file_size) / double(index.num_views());
    out["descriptors"] = DescriptorStorage(index);
    out["sections"] = nlohmann::ordered_json::array();
    for (const SectionEntry& entry : index.file().sections()) {
      out["sections"].push_back({{"tag", SectionTagName(entry.tag)},
                                 {"offset", entry.offset},
                                 {"bytes", entry.size},
                                 {"count", entry.count},
                                 {"element_bytes", entry.element_size},
                                 {"required", (entry.flags & kSectionRequired) != 0},
                                 {"checksum", "xxh64:" + HashHex(entry.checksum)}});
    }
    out["manifest"] = manifest;
    std::cout << out.dump(2) << "\n";
    return kExitOk;
  }
  std::printf("%s: cwloc index format %u.%u, %.1f MB, opened in %.3f ms\n", path.c_str(),
              header.format_major, header.format_minor, header.file_size / 1e6, open_ms);
  const auto& counts = manifest["counts"];
  std::printf("  %s images, %s points, %s views, %s clusters (%s), %s co-visibility edges\n",
              counts["images"].dump().c_str(), counts["points"].dump().c_str(),
              counts["views"].dump().c_str(), counts["clusters"].dump().c_str(),
              manifest["build_parameters"]["clustering"]["method"].get<std::string>().c_str(),
              counts["covisibility_edges"].dump().c_str());
  std::printf("  built by %s %s from %s\n", manifest["tool"].get<std::string>().c_str(),
              manifest["tool_version"].get<std::string>().c_str(),
              manifest["source"]["model"]["path"].get<std::string>().c_str());
  if (manifest.contains("extracted")) PrintExtracted(manifest["extracted"]);
  if (manifest.contains("update")) {
    const auto& update = manifest["update"];
    std::printf("  updated %s times since its last full build: +%s, -%s images\n",
                update["updates"].dump().c_str(), update["images_added"].dump().c_str(),
                update["images_removed"].dump().c_str());
  }
  if (manifest.contains("georeference") && manifest["georeference"].is_object())
    PrintGeoreference(manifest["georeference"]);
  std::printf("  descriptors: %s\n", DescriptorStorage(index).c_str());
  std::printf("  %-6s %12s %14s %12s  %s\n", "tag", "offset", "bytes", "count", "bytes/view");
  const double views = static_cast<double>(index.num_views());
  for (const SectionEntry& entry : index.file().sections()) {
    std::printf("  %-6s %12llu %14llu %12llu  %8.2f\n", SectionTagName(entry.tag).c_str(),
                static_cast<unsigned long long>(entry.offset),
                static_cast<unsigned long long>(entry.size),
                static_cast<unsigned long long>(entry.count), double(entry.size) / views);
  }
  std::printf("  total %.2f bytes per view\n", double(header.file_size) / views);
  return kExitOk;
}

int RunVerify(const std::string& path) {
  const Stopwatch stopwatch;
  // Checksums first: a flipped byte is named as one even where Index::Open checks the value.
  IndexFile::Open(path).VerifyChecksums();
  const Index index = Index::Open(path);
  index.Validate();
  ParseManifest(index);
  const double seconds = stopwatch.Seconds();
  std::printf("%s: OK: %zu section checksums and every stored index verified in %.2f s\n",
              path.c_str(), index.file().sections().size(), seconds);
  return kExitOk;
}

// `cwloc-index build`'s flags, one per line of the build option table
// (indexer/build_option_table.inc), with the defaults of IndexBuildOptions and IndexBuildFlags.
class BuildFlags {
 public:
  void AddTo(CLI::App* build) {
    const IndexBuildOptions options;
    const IndexBuildFlags flags;
    const std::span<const BuildOptionSpec> table = BuildOptionTable();
    texts_.resize(table.size());
    switches_ = std::make_unique<bool[]>(table.size());
    for (size_t i = 0; i < table.size(); ++i) {
      const BuildOptionSpec& spec = table[i];
      const std::optional<OptionValue> value = spec.get(options, flags);
      const std::string flag = "--" + std::string(spec.flag);
      if (IsSwitch(spec)) {
        options_.push_back(build->add_flag(flag, switches_[i], spec.help));
        continue;
      }
      CLI::Option* option =
          build->add_option(flag, texts_[i], spec.help)->type_name(TypeName(spec));
      // Numbers show their default; an unset optional, an empty path or name has none.
      if (value && !std::holds_alternative<std::string>(*value) &&
          !std::holds_alternative<std::filesystem::path>(*value))
        option->default_str(FormatOptionValue(*value));
      options_.push_back(option);
    }
  }

  // The flags given, by name, as values of their types (range-checked).
  std::vector<std::pair<std::string, OptionValue>> Given() const {
    std::vector<std::pair<std::string, OptionValue>> given;
    const std::span<const BuildOptionSpec> table = BuildOptionTable();
    for (size_t i = 0; i < table.size(); ++i) {
      if (options_[i]->count() == 0) continue;
      const BuildOptionSpec& spec = table[i];
      given.emplace_back(std::string(spec.flag), IsSwitch(spec)
                                                     ? OptionValue(switches_[i])
                                                     : ParseBuildOption(spec, texts_[i]));
    }
    return given;
  }

  // Every flag given, through the table; ValidateBuildOptions checks the ranges.
  void Apply(IndexBuildOptions* options, IndexBuildFlags* flags) const {
    const std::span<const BuildOptionSpec> table = BuildOptionTable();
    for (size_t i = 0; i < table.size(); ++i) {
      if (options_[i]->count() == 0) continue;
      const BuildOptionSpec& spec = table[i];
      spec.set(IsSwitch(spec) ? OptionValue(switches_[i]) : ParseBuildOption(spec, texts_[i]),
               options, flags);
    }
  }

 private:
  static bool IsSwitch(const BuildOptionSpec& spec) { return spec.type == OptionTypeIndex<bool>(); }
  static std::string TypeName(const BuildOptionSpec& spec) {
    switch (spec.type) {
      case OptionTypeIndex<int32_t>():
        return "INT";
      case OptionTypeIndex<double>():
        return "FLOAT";
      case OptionTypeIndex<std::string>():
      case OptionTypeIndex<std::filesystem::path>():
        return "TEXT";
      default:
        return "UINT";
    }
  }

  std::vector<std::string> texts_;
  std::unique_ptr<bool[]> switches_;  // CLI11 sets bools, and vector<bool> has none to point at
  std::vector<CLI::Option*> options_;
};

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{
      "cwloc-index: build a cwloc index from a COLMAP model and database, update it for a grown "
      "model, apply a delta, extract a region of one, inspect or verify it"};
  app.set_version_flag("--version", std::string("cwloc-index ") + cwloc::kToolVersion);
  app.require_subcommand(1);

  cwloc::IndexBuildOptions options;
  cwloc::IndexBuildFlags flags;
  bool json = false;
  auto* build =
      app.add_subcommand("build", "Build an index from a COLMAP sparse model and its database");
  build->add_option("--model", options.model_dir, "COLMAP sparse model directory (binary or text)")
      ->required();
  build
      ->add_option("--database", options.database_path,
                   "COLMAP database.db with the model's descriptors (read only)")
      ->required();
  build->add_option("-o,--output", options.output_path, "Index file to write (atomically)")
      ->required();
  cwloc::BuildFlags build_flags;
  build_flags.AddTo(build);
  build->get_option("--clusters")->excludes(build->get_option("--cluster-file"));
  build->add_flag("--json", json, "Print the build report as JSON");

  cwloc::IndexExtractOptions extract_options;
  std::string near;
  auto* extract = app.add_subcommand(
      "extract",
      "Write the part of an index near a position, or around listed images, as an index");
  extract->add_option("--index", extract_options.index_path, "Index file to extract from")
      ->required();
  auto* near_option = extract->add_option(
      "--near", near,
      "'LAT LON [HEIGHT] RADIUS_M': the clusters with a camera within RADIUS_M of this WGS84 "
      "position (horizontally without HEIGHT), as --prior-position selects them");
  extract
      ->add_option("--images", extract_options.images_file,
                   "File of image names, one per line: the clusters that hold them")
      ->excludes(near_option);
  extract
      ->add_option("-o,--output", extract_options.output_path, "Index file to write (atomically)")
      ->required();
  extract->add_option("--threads", extract_options.threads, "Worker threads (0 = all cores)")
      ->capture_default_str();
  extract->add_option("--parent-tile", extract_options.parent_tile_path,
                      "The same region's tile of the index this one was updated from: write the "
                      "tile as it changed by a delta (--delta), which devices apply to it; "
                      "without --near or --images, the parent tile's region");
  extract->add_option("--delta", extract_options.delta_path,
                      "With --parent-tile: the delta file to write (cwloc-index apply)");
  extract->add_flag("--json", json, "Print the report as JSON");

  cwloc::IndexUpdateOptions update_options;
  auto* update = app.add_subcommand(
      "update", "Update an index for a grown COLMAP model; optionally write the delta for devices");
  update->add_option("--index", update_options.index_path, "The index of the model before")
      ->required();
  update->add_option("--model", update_options.model_dir, "The grown COLMAP sparse model")
      ->required();
  update->add_option("--database", update_options.database_path, "Its database.db (read only)")
      ->required();
  update->add_option("-o,--output", update_options.output_path, "Index file to write (atomically)")
      ->required();
  update->add_option("--delta", update_options.delta_path,
                     "Also write the change as a delta file (cwloc-index apply)");
  update->add_option("--remove-images", update_options.remove_images_file,
                     "File of image names, one per line, to take out of the index");
  update->add_flag("--rebuild-if-needed", update_options.rebuild_if_needed,
                   "Build the index afresh when the model was not grown but changed");
  cwloc::BuildFlags update_flags;
  update_flags.AddTo(update);
  update->add_flag("--json", json, "Print the report as JSON");

  std::filesystem::path apply_index, apply_delta, apply_output;
  int apply_threads = 0;
  auto* apply = app.add_subcommand(
      "apply", "Apply a delta of cwloc-index update to the index it was made for");
  apply->add_option("--index", apply_index, "The index the delta was made for")->required();
  apply->add_option("--delta", apply_delta, "The delta (cwloc-index update --delta)")->required();
  apply->add_option("-o,--output", apply_output, "Index file to write (atomically)")->required();
  apply->add_option("--threads", apply_threads, "Worker threads (0 = all cores)")
      ->capture_default_str();
  apply->add_flag("--json", json, "Print the report as JSON");

  std::string index_path;
  auto* info = app.add_subcommand("info", "Print an index's counts, sections and build parameters");
  info->add_option("index", index_path, "Index file")->required();
  info->add_flag("--json", json, "Print as JSON (schemas/index-info.schema.json)");
  auto* verify =
      app.add_subcommand("verify", "Check every checksum and stored index of an index file");
  verify->add_option("index", index_path, "Index file")->required();

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? cwloc::kExitOk : cwloc::kExitBadInput;
  }
  return cwloc::RunTool("cwloc-index", [&]() -> int {
    if (build->parsed()) {
      build_flags.Apply(&options, &flags);
      cwloc::ValidateBuildOptions(options, flags);
      cwloc::ApplyBuildFlags(flags, &options);
      return cwloc::RunBuild(options, json);
    }
    if (extract->parsed()) {
      if (!near.empty()) extract_options.near = cwloc::ParseGeoRegion(near, "--near");
      return cwloc::RunExtract(extract_options, json);
    }
    if (update->parsed()) {
      update_options.build_flags = update_flags.Given();
      for (const auto& [flag, value] : update_options.build_flags) {
        if (flag == "threads") update_options.threads = std::get<int32_t>(value);
      }
      return cwloc::RunUpdate(update_options, json);
    }
    if (apply->parsed())
      return cwloc::RunApply(apply_index, apply_delta, apply_output, apply_threads, json);
    if (info->parsed()) return cwloc::RunInfo(index_path, json);
    return cwloc::RunVerify(index_path);
  });
}
