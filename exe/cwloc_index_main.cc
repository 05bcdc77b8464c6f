// cwloc-index: builds, inspects and verifies cwloc index files.
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <variant>
#include <vector>

#include "base/error.h"
#include "base/stopwatch.h"
#include "cwloc/version.h"
#include "delta/apply_delta.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "format/index_section_table.h"
#include "format/xxhash64.h"
#include "indexer/build_option_table.h"
#include "indexer/index_build_flags.h"
#include "indexer/index_builder.h"
#include "indexer/index_command_flags.h"
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

int RunApply(const IndexApplyOptions& options, bool json) {
  const std::filesystem::path& output = options.output_path;
  const ApplyDeltaReport report =
      ApplyDelta(options.index_path, options.delta_path, output, options.threads);
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

// What a section holds, as the section table says, with the format that introduced it; a
// section this cwloc does not know is one Index::Open skipped (a required one it refuses).
std::string SectionContents(uint32_t tag) {
  const IndexSectionSpec* spec = FindIndexSection(tag);
  if (spec == nullptr) return "unknown to this cwloc (optional: skipped)";
  std::string note = spec->optional() ? "optional" : "";
  if (spec->minor > 0)
    note += (note.empty() ? "" : ", ") + std::string("format 1.") + std::to_string(spec->minor);
  return std::string(spec->help) + (note.empty() ? "" : " (" + note + ")");
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
                                 {"checksum", "xxh64:" + HashHex(entry.checksum)},
                                 {"contents", SectionContents(entry.tag)}});
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
  std::printf("  %-6s %12s %14s %12s  %s  %s\n", "tag", "offset", "bytes", "count", "bytes/view",
              "contents");
  const double views = static_cast<double>(index.num_views());
  for (const SectionEntry& entry : index.file().sections()) {
    std::printf("  %-6s %12llu %14llu %12llu  %8.2f    %s\n", SectionTagName(entry.tag).c_str(),
                static_cast<unsigned long long>(entry.offset),
                static_cast<unsigned long long>(entry.size),
                static_cast<unsigned long long>(entry.count), double(entry.size) / views,
                SectionContents(entry.tag).c_str());
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
  for (const SectionEntry& entry : index.file().sections()) {
    if (FindIndexSection(entry.tag) == nullptr) {
      std::printf(
          "  section '%s' is unknown to this cwloc: its checksum verified, not its contents\n",
          SectionTagName(entry.tag).c_str());
    }
  }
  return kExitOk;
}

std::string TypeName(size_t type) {
  switch (type) {
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

bool IsSwitch(size_t type) { return type == OptionTypeIndex<bool>(); }

// One flag as a table line describes it.
struct TableFlag {
  std::string names;  // "--trees", "-o,--output"
  std::string_view flag;
  std::string help;
  ValueRange range;
  size_t type;  // index in OptionValue
  bool required = false;
  std::optional<OptionValue> shown_default;  // what --help shows after the type
};

// Each value is kept as given and, once the command line is parsed, read as the flag's type and
// checked against its range, so that every command refuses a bad value with one message
// ("--FLAG VALUE: expected ...").
class TableFlags {
 public:
  void AddTo(CLI::App* command, std::vector<TableFlag> flags);
  // The flags given, by their place in AddTo's list, as values of their types; InputError for
  // a value out of range.
  std::vector<std::pair<size_t, OptionValue>> Given() const;

 private:
  std::vector<TableFlag> flags_;
  std::vector<std::string> texts_;
  std::unique_ptr<bool[]> switches_;  // CLI11 sets bools, and vector<bool> has none to point at
  std::vector<CLI::Option*> options_;
};

// `cwloc-index build`'s (and update's) option table flags, with the defaults of
// IndexBuildOptions and IndexBuildFlags.
class BuildFlags {
 public:
  void AddTo(CLI::App* command);
  // The flags given, by name, as values of their types (range-checked).
  std::vector<std::pair<std::string, OptionValue>> Given() const;
  // Every flag given, through the table; ValidateBuildOptions checks the ranges.
  void Apply(IndexBuildOptions* options, IndexBuildFlags* flags) const;

 private:
  TableFlags flags_;
};

// A command's lines of the command table, with the defaults of its options.
template <typename Options>
class CommandFlags {
 public:
  void AddTo(CLI::App* command) {
    table_ = CommandFlagTable<Options>();
    const Options defaults;
    std::vector<TableFlag> flags;
    for (const CommandFlagSpec<Options>& spec : table_) {
      flags.push_back({spec.names, spec.flag, spec.help, spec.range, spec.type, spec.required,
                       spec.shown_default(defaults)});
    }
    flags_.AddTo(command, std::move(flags));
  }
  void Apply(Options* options) const {
    for (const auto& [line, value] : flags_.Given()) table_[line].set(value, options);
  }

 private:
  std::span<const CommandFlagSpec<Options>> table_;
  TableFlags flags_;
};

void TableFlags::AddTo(CLI::App* command, std::vector<TableFlag> flags) {
  flags_ = std::move(flags);
  texts_.resize(flags_.size());
  switches_ = std::make_unique<bool[]>(flags_.size());
  for (size_t i = 0; i < flags_.size(); ++i) {
    const TableFlag& flag = flags_[i];
    if (IsSwitch(flag.type)) {
      options_.push_back(command->add_flag(flag.names, switches_[i], flag.help));
      continue;
    }
    CLI::Option* option =
        command->add_option(flag.names, texts_[i], flag.help)->type_name(TypeName(flag.type));
    if (flag.shown_default) option->default_str(FormatOptionValue(*flag.shown_default));
    if (flag.required) option->required();
    options_.push_back(option);
  }
}

std::vector<std::pair<size_t, OptionValue>> TableFlags::Given() const {
  std::vector<std::pair<size_t, OptionValue>> given;
  for (size_t i = 0; i < flags_.size(); ++i) {
    if (options_[i]->count() == 0) continue;
    const TableFlag& flag = flags_[i];
    given.emplace_back(i, IsSwitch(flag.type)
                              ? OptionValue(switches_[i])
                              : ParseOptionValue(flag.flag, flag.range, flag.type, texts_[i]));
  }
  return given;
}

void BuildFlags::AddTo(CLI::App* command) {
  const IndexBuildOptions options;
  const IndexBuildFlags flags;
  std::vector<TableFlag> table_flags;
  for (const BuildOptionSpec& spec : BuildOptionTable()) {
    // Numbers show their default; an unset optional, an empty path or name has none.
    std::optional<OptionValue> value = spec.get(options, flags);
    if (value && (std::holds_alternative<std::string>(*value) ||
                  std::holds_alternative<std::filesystem::path>(*value)))
      value.reset();
    table_flags.push_back(
        {"--" + std::string(spec.flag), spec.flag, spec.help, spec.range, spec.type, false, value});
  }
  flags_.AddTo(command, std::move(table_flags));
}

std::vector<std::pair<std::string, OptionValue>> BuildFlags::Given() const {
  std::vector<std::pair<std::string, OptionValue>> given;
  for (auto& [line, value] : flags_.Given())
    given.emplace_back(std::string(BuildOptionTable()[line].flag), std::move(value));
  return given;
}

void BuildFlags::Apply(IndexBuildOptions* options, IndexBuildFlags* flags) const {
  for (const auto& [line, value] : flags_.Given())
    BuildOptionTable()[line].set(value, options, flags);
}

// A subcommand whose flags come from the command table (indexer/index_command_flags.inc) and,
// with kBuildFlags (build; update, which compares them with the index's), the build option
// table's after them.
template <typename Options, bool kBuildFlags = false>
class TableCommand {
 public:
  bool parsed() const { return command_->parsed(); }

 protected:
  CLI::App* Add(CLI::App* app, const std::string& name, const std::string& description) {
    command_ = app->add_subcommand(name, description);
    flags_.AddTo(command_);
    if constexpr (kBuildFlags) build_flags_.AddTo(command_);
    return command_;
  }
  // `Options` as the command table's flags set them.
  Options Parsed() const {
    Options options;
    flags_.Apply(&options);
    return options;
  }
  const BuildFlags& build_flags() const { return build_flags_; }

 private:
  CLI::App* command_ = nullptr;
  CommandFlags<Options> flags_;
  BuildFlags build_flags_;
};

class BuildCommand : public TableCommand<IndexBuildOptions, /*kBuildFlags=*/true> {
 public:
  CLI::App* AddTo(CLI::App* app) {
    CLI::App* build =
        Add(app, "build", "Build an index from a COLMAP sparse model and its database");
    build->get_option("--clusters")->excludes(build->get_option("--cluster-file"));
    return build;
  }
  int Run(bool json) const {
    IndexBuildOptions options = Parsed();
    IndexBuildFlags flags;
    build_flags().Apply(&options, &flags);
    ValidateBuildOptions(options, flags);
    ApplyBuildFlags(flags, &options);
    return RunBuild(options, json);
  }
};

class ExtractCommand : public TableCommand<IndexExtractOptions> {
 public:
  CLI::App* AddTo(CLI::App* app) {
    CLI::App* extract =
        Add(app, "extract",
            "Write the part of an index near a position, or around listed images, as an index");
    extract->get_option("--images")->excludes(extract->get_option("--near"));
    return extract;
  }
  int Run(bool json) const { return RunExtract(Parsed(), json); }
};

class UpdateCommand : public TableCommand<IndexUpdateOptions, /*kBuildFlags=*/true> {
 public:
  CLI::App* AddTo(CLI::App* app) {
    return Add(app, "update",
               "Update an index for a grown COLMAP model; optionally write the delta for devices");
  }
  int Run(bool json) const {
    IndexUpdateOptions options = Parsed();
    options.build_flags = build_flags().Given();  // each must be the index's, but --threads
    TakeThreadsOfBuildFlags(&options);
    return RunUpdate(options, json);
  }
};

class ApplyCommand : public TableCommand<IndexApplyOptions> {
 public:
  CLI::App* AddTo(CLI::App* app) {
    return Add(app, "apply", "Apply a delta of cwloc-index update to the index it was made for");
  }
  int Run(bool json) const { return RunApply(Parsed(), json); }
};

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{
      "cwloc-index: build a cwloc index from a COLMAP model and database, update it for a grown "
      "model, apply a delta, extract a region of one, inspect or verify it"};
  app.set_version_flag("--version", std::string("cwloc-index ") + cwloc::kToolVersion);
  app.require_subcommand(1);
  bool json = false;
  cwloc::BuildCommand build;
  build.AddTo(&app)->add_flag("--json", json, "Print the build report as JSON");
  cwloc::ExtractCommand extract;
  extract.AddTo(&app)->add_flag("--json", json, "Print the report as JSON");
  cwloc::UpdateCommand update;
  update.AddTo(&app)->add_flag("--json", json, "Print the report as JSON");
  cwloc::ApplyCommand apply;
  apply.AddTo(&app)->add_flag("--json", json, "Print the report as JSON");
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
    if (build.parsed()) return build.Run(json);
    if (extract.parsed()) return extract.Run(json);
    if (update.parsed()) return update.Run(json);
    if (apply.parsed()) return apply.Run(json);
    if (info->parsed()) return cwloc::RunInfo(index_path, json);
    return cwloc::RunVerify(index_path);
  });
}
