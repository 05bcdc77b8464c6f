// cwloc-eval: compares localization results (cwloc-localize JSON lines or a poses file) with
// ground-truth query poses and prints recall and error statistics. See docs/eval.md.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>

#include "cwloc/version.h"
#include "format/error.h"
#include "format/tool_main.h"
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
                 "cwloc-localize JSON lines or a poses file (NAME QW QX QY QZ TX TY TZ); repeat to compare runs")
      ->required();
  app.add_option("--label", labels, "name of each run in the table, in --results order (default: file name)");
  app.add_option("--gt", gt_path, "ground-truth poses: NAME QW QX QY QZ TX TY TZ [CAMERA...], COLMAP world-to-camera")
      ->required();
  app.add_option("--scale", scale_path, "scale_to_metres.txt ('scale S' line) to report metres instead of model units");
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
                              std::to_string(results_paths.size()) + " --results; give one per run or none");
    }
    EvalReport report;
    report.ground_truth_path = gt_path;
    const std::vector<NamedPose> ground_truth = ReadGroundTruth(gt_path);
    report.queries = int(ground_truth.size());
    if (!scale_path.empty()) {
      report.scale_path = scale_path;
      report.scale = ReadScale(scale_path);
    }
    for (size_t i = 0; i < results_paths.size(); ++i) {
      const RunResults run = ReadResults(results_paths[i]);
      const std::string label =
          labels.empty() ? std::filesystem::path(results_paths[i]).filename().string() : labels[i];
      report.runs.push_back(EvaluateRun(ground_truth, run, report.scale, label));
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
