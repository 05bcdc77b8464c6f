// cwloc-eval: compares localization results (cwloc-localize JSON lines or a poses file) with
// ground-truth query poses and prints recall and error statistics. See docs/eval.md.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <iostream>
#include <unordered_map>

#include "base/error.h"
#include "cwloc/version.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "geo/index_georeference.h"
#include "tools/eval/ground_truth.h"
#include "tools/eval/report.h"
#include "tools/eval/result_reader.h"

int main(int argc, char** argv) {
  CLI::App app{"cwloc-eval: evaluate localization results against ground-truth query poses"};
  app.set_version_flag("--version", std::string("cwloc-eval ") + cwloc::kToolVersion);
  std::vector<std::string> results_paths;
  std::vector<std::string> labels;
  std::string gt_path;
  std::string scale_path;
  bool json = false;
  app.add_option("--results", results_paths,
                 "cwloc-localize JSON lines or a poses file (NAME QW QX QY QZ TX TY TZ); repeat to "
                 "compare runs")
      ->required();
  app.add_option("--label", labels,
                 "name of each run in the table, in --results order (default: file name)");
  app.add_option(
         "--gt", gt_path,
         "ground-truth poses: NAME QW QX QY QZ TX TY TZ [CAMERA...], COLMAP world-to-camera")
      ->required();
  auto* scale_option = app.add_option(
      "--scale", scale_path,
      "scale_to_metres.txt ('scale S' line) to report metres instead of model units");
  std::string index_path, gt_geo_path;
  app.add_option("--index", index_path,
                 "georeferenced cwloc index of the model: metres through its georeference, and "
                 "ground and height errors in its east-north-up frame")
      ->excludes(scale_option);
  app.add_option("--gt-geo", gt_geo_path,
                 "the queries' true positions, NAME LAT LON HEIGHT (WGS84 degrees, metres above "
                 "the ellipsoid; cwloc-synth's queries_geo.txt): compare the results' \"geo\"");
  std::string model_dir, gt_points, gt_model;
  int min_shared = 12;
  app.add_option(
      "--model", model_dir,
      "mapping model (COLMAP sparse dir): score the ranked images (location recognition)");
  auto* points_option =
      app.add_option("--gt-points", gt_points,
                     "with --model: 'NAME POINT3D_ID...' lines, the 3D points each query sees "
                     "(cwloc-synth's queries_gt_points.txt)");
  app.add_option("--gt-model", gt_model,
                 "with --model: a COLMAP model containing the queries (e.g. full_model); its "
                 "points are what each "
                 "query sees")
      ->excludes(points_option);
  app.add_option("--min-shared", min_shared,
                 "3D points a ranked image must share with the query to be right")
      ->capture_default_str();
  app.add_flag("--json", json, "print the report as JSON (schemas/eval-report.schema.json)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? cwloc::kExitOk : cwloc::kExitBadInput;
  }

  return cwloc::RunTool("cwloc-eval", [&]() -> int {
    using namespace cwloc::eval;
    if (!labels.empty() && labels.size() != results_paths.size()) {
      throw cwloc::InputError("got " + std::to_string(labels.size()) + " --label for " +
                              std::to_string(results_paths.size()) +
                              " --results; give one per run or none");
    }
    EvalReport report;
    report.ground_truth_path = gt_path;
    const std::vector<NamedPose> ground_truth = ReadGroundTruth(gt_path);
    report.queries = int(ground_truth.size());
    if (!scale_path.empty()) {
      report.scale_path = scale_path;
      report.scale = ReadScale(scale_path);
    }
    if (!index_path.empty()) {
      const cwloc::Index index = cwloc::Index::Open(index_path);
      if (index.georeference() == nullptr) {
        throw cwloc::InputError(index_path +
                                ": the index is not georeferenced (no GEOR section); --index "
                                "needs one built with --georef, --georef-images or --model-frame");
      }
      report.index_path = index_path;
      report.georeference = cwloc::GeoreferenceOfSection(*index.georeference());
      report.scale = report.georeference->scale;
    }
    std::unordered_map<std::string, cwloc::Geodetic> true_positions;
    if (!gt_geo_path.empty()) {
      const std::vector<NamedGeodetic> positions = ReadGeoGroundTruth(gt_geo_path);
      true_positions = TruePositionsOfQueries(ground_truth, positions, gt_geo_path);
      report.geo_truth_path = gt_geo_path;
      report.geo_truth_positions = int(positions.size());
    }
    GeoTruth geo_truth;
    if (report.georeference) geo_truth.georeference = &*report.georeference;
    if (report.geo_truth_path) geo_truth.true_positions = &true_positions;
    std::optional<RecognitionTruth> recognition;
    std::vector<std::string> query_names;
    for (const NamedPose& query : ground_truth) query_names.push_back(query.name);
    if (!model_dir.empty()) {
      if (gt_points.empty() && gt_model.empty()) {
        throw cwloc::InputError(
            "--model needs --gt-points or --gt-model to know what each query sees");
      }
      if (min_shared < 1) throw cwloc::InputError("--min-shared must be at least 1");
      const auto points = gt_points.empty() ? QueryPointsFromModel(gt_model, query_names)
                                            : ReadQueryPoints(gt_points);
      recognition = MakeRecognitionTruth(model_dir, points, min_shared);
      report.recognition_min_shared = min_shared;
    }
    for (size_t i = 0; i < results_paths.size(); ++i) {
      const RunResults run = ReadResults(results_paths[i]);
      const std::string label =
          labels.empty() ? std::filesystem::path(results_paths[i]).filename().string() : labels[i];
      report.runs.push_back(EvaluateRun(ground_truth, run, report.scale, label, geo_truth));
      if (recognition)
        report.runs.back().recognition = ScoreRecognition(run, query_names, *recognition);
    }
    if (json) {
      std::cout << ReportToJson(report).dump(2) << "\n";
    } else {
      std::cout << FormatTable(report);
    }
    std::cout.flush();
    return cwloc::kExitOk;
  });
}
