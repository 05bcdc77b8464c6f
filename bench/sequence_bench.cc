// cwloc-sequence-bench: the time a Tracker takes per frame against the same frames localized
// alone, in one run on one core (docs/algorithm.md, "Sequences"; issue #40's goals). The frames
// are a query list in time order with each frame's camera, their features from the database.
// Each round localizes every frame alone, then tracks the whole sequence from a fresh Tracker;
// the table gives, per tracking mode, the frames, the median time per frame after features
// over all rounds, the same frames' median alone, and the ratio.
//
//   cwloc-sequence-bench --index fox.cwl --database database.db
//       --query-list queries_with_intrinsics.txt [--rounds 10]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "app/camera_spec.h"
#include "app/database/database_queries.h"
#include "app/query_list.h"
#include "exe/tool_main.h"
#include "format/index.h"
#include "localizer/tracker.h"

namespace cwloc {
namespace {

double Median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

int Run(const std::string& index_path, const std::string& database, const std::string& list,
        int rounds) {
  const Index index = Index::Open(index_path);
  const Localizer localizer(index);
  const DatabaseQueries queries(database);
  std::vector<Query> frames;
  for (const QueryListEntry& entry : ReadQueryList(list)) {
    Query frame = queries.Load(entry.name);
    if (!entry.camera.empty()) frame.camera = ParseCameraSpec(entry.camera, list);
    frames.push_back(std::move(frame));
  }
  const LocalizerOptions options;
  // Per mode: the tracker's seconds on its frames, and the same frames' seconds alone.
  std::vector<double> tracked[3], alone[3];
  std::vector<int> count(3, 0);
  for (int round = 0; round < rounds; ++round) {
    std::vector<double> alone_seconds;
    for (const Query& frame : frames)
      alone_seconds.push_back(localizer.Localize(frame, options).times.total);
    Tracker tracker(localizer, options);
    for (size_t i = 0; i < frames.size(); ++i) {
      const LocalizationResult result = tracker.Track(frames[i]);
      const auto mode = static_cast<size_t>(result.tracking->mode);
      tracked[mode].push_back(result.tracking->seconds);
      alone[mode].push_back(alone_seconds[i]);
      if (round == 0) ++count[mode];
    }
  }
  std::printf("%zu frames, %d rounds; ms per frame after features, median\n", frames.size(),
              rounds);
  std::printf("%-12s %7s %10s %10s %7s\n", "mode", "frames", "tracker", "alone", "ratio");
  for (size_t mode = 0; mode < 3; ++mode) {
    if (count[mode] == 0) continue;
    const double t = Median(tracked[mode]) * 1e3, a = Median(alone[mode]) * 1e3;
    std::printf("%-12s %7d %10.2f %10.2f %7.2f\n", EnumNames<TrackingMode>::names[mode].data(),
                count[mode], t, a, t / a);
  }
  return 0;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) {
  CLI::App app{"Tracker time per frame against the same frames localized alone"};
  std::string index, database, list;
  int rounds = 10;
  app.add_option("--index", index, "Index file")->required();
  app.add_option("--database", database, "COLMAP database with the frames' features")->required();
  app.add_option("--query-list", list, "Frames in time order: 'NAME MODEL W H PARAMS'")->required();
  app.add_option("--rounds", rounds, "Rounds (each: every frame alone, then the sequence)")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  return cwloc::RunTool("cwloc-sequence-bench",
                        [&] { return cwloc::Run(index, database, list, rounds); });
}
