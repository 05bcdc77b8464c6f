// cwloc-plot as a program: figures from reports the real cwloc-eval writes, the growth exponent
// of `scale`, and the messages for bad input.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "cwloc/version.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

namespace fs = std::filesystem;

using cwloc::test::Quote;

// stdout and stderr together.
int Plot(const std::string& args, std::string* output) {
  return test::RunCommand(Quote(test::ToolPath("cwloc-plot")) + " " + args, output);
}

// stdout into *out, stderr into *err.
int PlotSplit(const std::string& args, const test::TempDir& dir, std::string* out,
              std::string* err) {
  // RunCommand sends the command's stderr to the pipe; the group's stdout goes to the file.
  const int code = test::RunCommand("{ " + Quote(test::ToolPath("cwloc-plot")) + " " + args +
                                        " > " + Quote(dir / "stdout.txt") + "; }",
                                    err);
  std::ifstream in(dir / "stdout.txt");
  std::stringstream text;
  text << in.rdbuf();
  *out = text.str();
  fs::remove(dir / "stdout.txt");
  return code;
}

// Width and height from a PNG's IHDR chunk, or nullopt if the file is not a PNG.
std::optional<std::pair<uint32_t, uint32_t>> PngSize(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::array<unsigned char, 24> head{};
  if (!in.read(reinterpret_cast<char*>(head.data()), head.size())) return std::nullopt;
  const std::array<unsigned char, 8> signature = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (!std::equal(signature.begin(), signature.end(), head.begin())) return std::nullopt;
  if (std::string(head.begin() + 12, head.begin() + 16) != "IHDR") return std::nullopt;
  const auto big_endian = [&](size_t at) {
    return uint32_t(head[at]) << 24 | uint32_t(head[at + 1]) << 16 | uint32_t(head[at + 2]) << 8 |
           uint32_t(head[at + 3]);
  };
  return std::make_pair(big_endian(16), big_endian(20));
}

// Every file in dir whose name starts with ".cwloc-plot-" (temporary figures left behind).
std::vector<std::string> TempFiles(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().filename().string().starts_with(".cwloc-plot-"))
      names.push_back(entry.path().filename());
  }
  return names;
}

// Five ground-truth queries q0..q4 at the origin with identity rotation. A result for query i
// with camera centre (e, 0, 0) has position error e and rotation error 0.
constexpr int kQueries = 5;

void WriteGroundTruth(const fs::path& path) {
  std::ofstream out(path);
  for (int i = 0; i < kQueries; ++i) out << "q" << i << ".jpg 1 0 0 0 0 0 0\n";
}

// One result per entry: (position error or a negative number for "not localized", total ms).
// The stages split the total 50 / 1 / 10 / 20 / 10 %.
void WriteRun(const fs::path& path, const std::vector<std::pair<double, double>>& results) {
  std::ofstream out(path);
  for (size_t i = 0; i < results.size(); ++i) {
    const auto [error, total] = results[i];
    std::string name = "q";  // appending sidesteps a GCC 12 -Wrestrict false positive
    name += std::to_string(i) + ".jpg";
    nlohmann::json record = {{"name", name}, {"success", error >= 0}};
    if (error >= 0) record["pose"] = {{"qvec", {1, 0, 0, 0}}, {"tvec", {-error, 0, 0}}};
    record["times_ms"] = {{"forward_knn", 0.5 * total}, {"ratio_test", 0.01 * total},
                          {"query_tree", 0.1 * total},  {"back_matching", 0.2 * total},
                          {"pose", 0.1 * total},        {"total", total}};
    out << record.dump() << "\n";
  }
}

// Runs the real cwloc-eval --json on (label, results file) runs; extra arguments go last.
void Evaluate(const test::TempDir& dir, const fs::path& report,
              const std::vector<std::pair<std::string, fs::path>>& runs,
              const std::string& extra = "") {
  std::string args = "--gt " + Quote(dir / "gt.txt");
  for (const auto& [label, path] : runs) args += " --results " + Quote(path) + " --label " + label;
  std::string output;
  ASSERT_EQ(test::RunCommand(Quote(test::ToolPath("cwloc-eval")) + " " + args + " --json " + extra +
                                 " > " + Quote(report),
                             &output),
            0)
      << output;
}

TEST(PlotCli, MatplotlibIsInstalled) {
  std::string output;
  ASSERT_EQ(test::RunCommand("/usr/bin/python3 -c 'import matplotlib'", &output), 0)
      << "cwloc-plot needs matplotlib for /usr/bin/python3: install Debian's python3-matplotlib "
         "(tools/install-deps.sh)\n"
      << output;
}

TEST(PlotCli, HelpAndVersion) {
  std::string output;
  EXPECT_EQ(Plot("--help", &output), 0) << output;
  for (const char* word : {"errors", "anytime", "scale", "Exit codes"}) {
    EXPECT_NE(output.find(word), std::string::npos) << word << "\n" << output;
  }
  EXPECT_EQ(Plot("errors --help", &output), 0);
  for (const char* word : {"--report", "--max-error", "--x-scale", "--output", "--title", "--size",
                           "ALL ground-truth"}) {
    EXPECT_NE(output.find(word), std::string::npos) << word << "\n" << output;
  }
  EXPECT_EQ(Plot("anytime --help", &output), 0);
  for (const char* word : {"--report", "--series", "--stage", "median time per query"}) {
    EXPECT_NE(output.find(word), std::string::npos) << word << "\n" << output;
  }
  EXPECT_EQ(Plot("scale --help", &output), 0);
  for (const char* word :
       {"--point", "VIEWS:JSON", "--run", "--series-label", "growth exponent", "p90"}) {
    EXPECT_NE(output.find(word), std::string::npos) << word << "\n" << output;
  }
  EXPECT_EQ(Plot("--version", &output), 0);
  EXPECT_EQ(output, std::string("cwloc-plot ") + kToolVersion + "\n");
  EXPECT_EQ(Plot("", &output), 2);
  EXPECT_EQ(output,
            "cwloc-plot: error: the following arguments are required: COMMAND\n"
            "Run 'cwloc-plot --help' for usage.\n");
  EXPECT_EQ(Plot("errors --report x.json", &output), 2);
  EXPECT_EQ(output,
            "cwloc-plot: error: the following arguments are required: -o/--output\n"
            "Run 'cwloc-plot errors --help' for usage.\n");
}

TEST(PlotCli, ErrorsDrawsOneCurvePerRun) {
  test::TempDir dir;
  WriteGroundTruth(dir / "gt.txt");
  WriteRun(dir / "a.jsonl", {{0.1, 10}, {0.3, 20}, {1.0, 30}, {6.0, 40}});  // q4 missing
  WriteRun(dir / "b.jsonl", {{0.05, 5}, {0.2, 6}, {-1, 7}, {2.0, 8}, {8.0, 9}});
  // The ground truth against itself: zero errors, which a log axis cannot show (left edge).
  Evaluate(dir, dir / "r1.json",
           {{"cwr", dir / "a.jsonl"}, {"global", dir / "b.jsonl"}, {"exact", dir / "gt.txt"}});
  Evaluate(dir, dir / "r2.json", {{"cwr", dir / "b.jsonl"}});  // a label r1.json has too
  std::string output;
  ASSERT_EQ(Plot("errors --report " + Quote(dir / "r1.json") + " --report " +
                     Quote(dir / "r2.json") + " -o " + Quote(dir / "cdf.png"),
                 &output),
            0)
      << output;
  EXPECT_EQ(output, "cwloc-plot: wrote " + (dir / "cdf.png").string() + " (4 curves)\n");
  EXPECT_EQ(PngSize(dir / "cdf.png"), std::make_pair(960u, 600u));

  // Options; an existing figure is replaced, and no temporary file is left behind.
  std::ofstream(dir / "cdf2.png") << "old";
  ASSERT_EQ(Plot("errors --report " + Quote(dir / "r1.json") + " -o " + Quote(dir / "cdf2.png") +
                     " --title 'Demo city' --max-error 10 --size 640x400 --x-scale linear",
                 &output),
            0)
      << output;
  EXPECT_EQ(PngSize(dir / "cdf2.png"), std::make_pair(640u, 400u));
  EXPECT_EQ(fs::status(dir / "cdf2.png").permissions() & fs::perms::others_read,
            fs::perms::others_read);
  EXPECT_TRUE(TempFiles(dir.path()).empty());

  // Metres and model units do not share an axis.
  std::ofstream(dir / "scale.txt") << "scale 2\n";
  Evaluate(dir, dir / "metres.json", {{"cwr", dir / "a.jsonl"}},
           "--scale " + Quote(dir / "scale.txt"));
  EXPECT_EQ(Plot("errors --report " + Quote(dir / "r1.json") + " --report " +
                     Quote(dir / "metres.json") + " -o " + Quote(dir / "mixed.png"),
                 &output),
            2);
  EXPECT_EQ(output, "cwloc-plot: error: reports differ in unit (" + (dir / "r1.json").string() +
                        " in model units, " + (dir / "metres.json").string() +
                        " in m); evaluate all with --scale or all without\n");
  EXPECT_FALSE(fs::exists(dir / "mixed.png"));
}

TEST(PlotCli, AnytimeDrawsOneSeriesPerReport) {
  test::TempDir dir;
  WriteGroundTruth(dir / "gt.txt");
  // A sweep: more time, more localized queries.
  WriteRun(dir / "nf50.jsonl", {{0.1, 10}, {0.2, 10}, {0.3, 10}, {-1, 10}, {-1, 10}});
  WriteRun(dir / "nf100.jsonl", {{0.1, 20}, {0.2, 20}, {0.3, 20}, {0.4, 20}, {-1, 20}});
  WriteRun(dir / "nf200.jsonl", {{0.1, 40}, {0.2, 40}, {0.3, 40}, {0.4, 40}, {0.5, 40}});
  Evaluate(dir, dir / "sweep.json",
           {{"N_F=50", dir / "nf50.jsonl"},
            {"N_F=100", dir / "nf100.jsonl"},
            {"N_F=200", dir / "nf200.jsonl"}});
  Evaluate(dir, dir / "baseline.json",
           {{"N_F=50", dir / "nf100.jsonl"}, {"N_F=200", dir / "nf200.jsonl"}});
  std::string output;
  ASSERT_EQ(Plot("anytime --report " + Quote(dir / "sweep.json") +
                     " --series cluster-wise --report " + Quote(dir / "baseline.json") +
                     " --series global-ratio -o " + Quote(dir / "anytime.png"),
                 &output),
            0)
      << output;
  EXPECT_EQ(output, "cwloc-plot: wrote " + (dir / "anytime.png").string() + " (2 series)\n");
  EXPECT_EQ(PngSize(dir / "anytime.png"), std::make_pair(960u, 600u));
  ASSERT_EQ(
      Plot("anytime --report " + Quote(dir / "sweep.json") +
               " --stage forward_knn --x-scale log --size 800x800 -o " + Quote(dir / "knn.png"),
           &output),
      0)
      << output;
  EXPECT_EQ(PngSize(dir / "knn.png"), std::make_pair(800u, 800u));

  EXPECT_EQ(Plot("anytime --report " + Quote(dir / "sweep.json") + " --report " +
                     Quote(dir / "baseline.json") + " --series one -o " + Quote(dir / "x.png"),
                 &output),
            2);
  EXPECT_EQ(output,
            "cwloc-plot: error: got 1 --series for 2 --report; give one per report or none\n");
  EXPECT_EQ(Plot("anytime --report " + Quote(dir / "sweep.json") + " --stage nope -o " +
                     Quote(dir / "x.png"),
                 &output),
            2);
  EXPECT_NE(output.find("cwloc-plot: error: argument --stage: invalid choice: 'nope'"),
            std::string::npos)
      << output;
  EXPECT_TRUE(TempFiles(dir.path()).empty());
}

TEST(PlotCli, ScalePrintsTheGrowthExponent) {
  test::TempDir dir;
  WriteGroundTruth(dir / "gt.txt");
  // Times double per 4x views, so time ~ views^0.5. Totals {t, t, 2t}: median t, p90 at
  // h = 1.8 is t + 0.8 t = 1.8 t. A second run "slow" takes 3 t throughout.
  const std::vector<std::pair<int, double>> sizes = {
      {1000, 10}, {4000, 20}, {16000, 40}, {64000, 80}};
  std::string points;
  for (auto it = sizes.rbegin(); it != sizes.rend(); ++it) {  // out of order on purpose
    const auto [views, t] = *it;
    const std::string name = "s" + std::to_string(views);
    WriteRun(dir / (name + ".jsonl"), {{0.1, t}, {0.2, t}, {0.3, 2 * t}});
    WriteRun(dir / (name + "_slow.jsonl"), {{0.1, 3 * t}, {0.2, 3 * t}, {0.3, 3 * t}});
    Evaluate(dir, dir / (name + ".json"),
             {{"cw", dir / (name + ".jsonl")}, {"slow", dir / (name + "_slow.jsonl")}});
    points += " --point " + std::to_string(views) + ":" + Quote(dir / (name + ".json"));
  }
  std::string out, err;
  ASSERT_EQ(PlotSplit("scale" + points + " -o " + Quote(dir / "scale.png"), dir, &out, &err), 0)
      << err;
  EXPECT_EQ(out,
            "cwloc-plot scale: cw, time per query by model size\n"
            "  views  median total ms  p90 total ms\n"
            "  1000   10.0             18.0\n"
            "  4000   20.0             36.0\n"
            "  16000  40.0             72.0\n"
            "  64000  80.0             144.0\n"
            "growth exponent: 0.500 (median total time ~ views^0.500; least-squares slope of log "
            "time against log "
            "views over 4 reports)\n");
  EXPECT_EQ(err, "cwloc-plot: wrote " + (dir / "scale.png").string() + " (4 model sizes)\n");
  EXPECT_EQ(PngSize(dir / "scale.png"), std::make_pair(960u, 600u));

  // Another run by label, a series name, a view count written as 1e3, and one model size only.
  ASSERT_EQ(PlotSplit("scale --point 1e3:" + Quote(dir / "s1000.json") +
                          " --run slow --series-label 'CW slow' -o " + Quote(dir / "one.png"),
                      dir, &out, &err),
            0)
      << err;
  EXPECT_EQ(out,
            "cwloc-plot scale: CW slow, time per query by model size\n"
            "  views  median total ms  p90 total ms\n"
            "  1000   30.0             30.0\n"
            "growth exponent: - (needs two or more model sizes and non-zero times)\n");
  EXPECT_EQ(PngSize(dir / "one.png"), std::make_pair(960u, 600u));
  EXPECT_EQ(PlotSplit("scale --point 1000:" + Quote(dir / "s1000.json") + " --run zzz -o " +
                          Quote(dir / "x.png"),
                      dir, &out, &err),
            2);
  EXPECT_EQ(err, "cwloc-plot: error: " + (dir / "s1000.json").string() +
                     ": no run labelled \"zzz\" (runs: cw, slow)\n");
  EXPECT_TRUE(TempFiles(dir.path()).empty());
}

TEST(PlotCli, CompactPrintsErrorAndShareByBytesPerView) {
  test::TempDir dir;
  WriteGroundTruth(dir / "gt.txt");
  // Full index: errors 1, 2, 3, 9, 9 (median 3); 32 B: 2, 2, 3 and two lost (median 2); 16 B:
  // 3, 4 and three lost (median 3.5). Ratios are to the data set's largest index.
  WriteRun(dir / "full.jsonl", {{1, 5}, {2, 5}, {3, 5}, {9, 5}, {9, 5}});
  WriteRun(dir / "c32.jsonl", {{2, 5}, {2, 5}, {3, 5}, {-1, 5}, {-1, 5}});
  WriteRun(dir / "c16.jsonl", {{3, 5}, {4, 5}, {-1, 5}, {-1, 5}, {-1, 5}});
  for (const std::string name : {"full", "c32", "c16"})
    Evaluate(dir, dir / (name + ".json"), {{name, dir / (name + ".jsonl")}});
  std::string out, err;
  ASSERT_EQ(PlotSplit("compact --point city:16.5:" + Quote(dir / "c16.json") +
                          " --point city:175:" + Quote(dir / "full.json") + " --point city:27.1:" +
                          Quote(dir / "c32.json") + " -o " + Quote(dir / "compact.png"),
                      dir, &out, &err),
            0)
      << err;
  EXPECT_EQ(out,
            "cwloc-plot compact: median position error and localized share by bytes per view\n"
            "  data set  bytes / view  median error  vs largest  localized %\n"
            "  city      16.5          3.500         1.167       40.0\n"
            "  city      27.1          2.000         0.667       60.0\n"
            "  city      175.0         3.000         1.000       100.0\n");
  EXPECT_EQ(err, "cwloc-plot: wrote " + (dir / "compact.png").string() + " (1 data set)\n");
  EXPECT_EQ(PngSize(dir / "compact.png"), std::make_pair(960u, 600u));
  EXPECT_EQ(
      PlotSplit("compact --point city:x:" + Quote(dir / "c16.json") + " -o " + Quote(dir / "x.png"),
                dir, &out, &err),
      2);
  EXPECT_NE(err.find("expected DATASET:BYTES_PER_VIEW:REPORT"), std::string::npos) << err;
  EXPECT_TRUE(TempFiles(dir.path()).empty());
}

// A sequence of six frames around the origin (four tracked, one relocalized, one lost) over a
// COLMAP model's points3D.txt, with the true path: the frames per mode, and a clear error for a
// localized record without its pose, a folder without points and results without any pose.
TEST(PlotCli, TrajectoryDrawsTheFramesByModeOverTheMap) {
  test::TempDir dir;
  {
    std::ofstream results(dir / "frames.jsonl"), truth(dir / "gt.txt");
    const char* modes[] = {"relocalized", "tracked", "tracked", "lost", "tracked", "tracked"};
    for (int i = 0; i < 6; ++i) {
      const std::string name = "f" + std::to_string(i) + ".jpg";
      const double angle = i * 0.5, x = 3 * std::cos(angle), y = 3 * std::sin(angle);
      nlohmann::json record = {{"name", name}, {"success", std::string(modes[i]) != "lost"}};
      record["tracking"] = {{"mode", modes[i]}};
      // Cameras at height 0 with their y axis down (-z): cam_from_world = [x; -z; y] rotation.
      const double h = std::sqrt(0.5);
      if (record["success"]) record["pose"] = {{"qvec", {h, h, 0, 0}}, {"center", {x, y, 0}}};
      results << record.dump() << "\n";
      truth << name << " " << h << " " << h << " 0 0 " << -x << " 0 " << y << "\n";
    }
    std::ofstream points(dir / "points3D.txt");
    points << "# POINT3D_ID X Y Z R G B ERROR TRACK[]\n1 0 0 0.5 255 0 0 0.1 1 0\n"
              "2 0.5 0.2 0 0 255 0 0.2 1 1\n";
  }
  std::string out, err;
  ASSERT_EQ(PlotSplit("trajectory --results " + Quote(dir / "frames.jsonl") + " --model " +
                          Quote(dir.path()) + " --truth " + Quote(dir / "gt.txt") + " -o " +
                          Quote(dir / "trajectory.png"),
                      dir, &out, &err),
            0)
      << err;
  EXPECT_EQ(out, "cwloc-plot trajectory: " + (dir / "frames.jsonl").string() +
                     "\n"
                     "  frames  with a pose  lost  relocalized  tracked\n"
                     "  6       5            1     1            4\n");
  EXPECT_EQ(err, "cwloc-plot: wrote " + (dir / "trajectory.png").string() + " (6 frames)\n");
  EXPECT_EQ(PngSize(dir / "trajectory.png"), std::make_pair(960u, 600u));

  std::ofstream(dir / "bad.jsonl") << "{\"name\": \"a.jpg\", \"success\": true}\n";
  EXPECT_EQ(Plot("trajectory --results " + Quote(dir / "bad.jsonl") + " -o " + Quote(dir / "x.png"),
                 &err),
            2);
  EXPECT_EQ(err, "cwloc-plot: error: " + (dir / "bad.jsonl").string() +
                     ":1: a localized record without pose.center and pose.qvec\n");
  std::ofstream(dir / "none.jsonl") << "{\"name\": \"a.jpg\", \"success\": false}\n";
  EXPECT_EQ(
      Plot("trajectory --results " + Quote(dir / "none.jsonl") + " -o " + Quote(dir / "x.png"),
           &err),
      2);
  EXPECT_EQ(err, "cwloc-plot: error: " + (dir / "none.jsonl").string() +
                     ": no frame with a pose to draw\n");
  EXPECT_EQ(Plot("trajectory --results " + Quote(dir / "frames.jsonl") + " --model " +
                     Quote(dir / "nowhere") + " -o " + Quote(dir / "x.png"),
                 &err),
            2);
  EXPECT_EQ(err, "cwloc-plot: error: " + (dir / "nowhere").string() +
                     ": no points3D.bin or points3D.txt (expected a COLMAP model folder)\n");
  EXPECT_FALSE(fs::exists(dir / "x.png"));
  EXPECT_TRUE(TempFiles(dir.path()).empty());
}

TEST(PlotCli, BadInputNamesTheFileAndExits2) {
  test::TempDir dir;
  WriteGroundTruth(dir / "gt.txt");
  WriteRun(dir / "run.jsonl", {{0.1, 10}, {0.3, 20}, {1.0, 30}, {6.0, 40}});
  Evaluate(dir, dir / "report.json", {{"cwr", dir / "run.jsonl"}, {"poses", dir / "gt.txt"}});
  const nlohmann::json report = nlohmann::json::parse(std::ifstream(dir / "report.json"));
  const std::string out = " -o " + Quote(dir / "out.png");
  std::string output;
  const auto expect = [&](const std::string& args, const std::string& message) {
    EXPECT_EQ(Plot(args, &output), 2) << args << "\n" << output;
    EXPECT_EQ(output, "cwloc-plot: error: " + message + "\n") << args;
    EXPECT_EQ(output.find("Traceback"), std::string::npos) << output;
  };

  const fs::path none = dir / "none.json";
  expect("errors --report " + Quote(none) + out,
         none.string() + ": cannot open (No such file or directory)");
  expect("anytime --report " + Quote(none) + out,
         none.string() + ": cannot open (No such file or directory)");
  expect("scale --point 10:" + Quote(none) + out,
         none.string() + ": cannot open (No such file or directory)");
  expect("errors --report " + Quote(dir.path()) + out,
         dir.path().string() + ": is a directory, expected a file");

  std::ofstream(dir / "text.json") << "views 1000\n";
  expect("errors --report " + Quote(dir / "text.json") + out,
         (dir / "text.json").string() + ":1: not valid JSON (Expecting value)");
  std::ofstream(dir / "cut.json") << "{\n  \"tool\": \"cwloc-eval\",\n";
  expect("errors --report " + Quote(dir / "cut.json") + out,
         (dir / "cut.json").string() +
             ":3: not valid JSON (Expecting property name enclosed in double quotes)");
  // cwloc-localize results instead of the report.
  expect("errors --report " + Quote(dir / "run.jsonl") + out,
         (dir / "run.jsonl").string() +
             ":2: a second JSON value; expected one cwloc-eval --json report (JSON lines are "
             "cwloc-localize results: "
             "evaluate them with cwloc-eval --json)");
  std::ofstream(dir / "info.json") << R"({"tool": "cwloc-index", "views": 3})";
  expect("errors --report " + Quote(dir / "info.json") + out,
         (dir / "info.json").string() +
             ": not a cwloc-eval --json report (no \"tool\": \"cwloc-eval\")");

  const auto write_edited = [&](const std::string& name, const auto& edit) {
    nlohmann::json edited = report;
    edit(edited);
    std::ofstream(dir / name) << edited.dump(2);
    return dir / name;
  };
  const fs::path no_per_query =
      write_edited("no_per_query.json", [](nlohmann::json& j) { j["runs"][0].erase("per_query"); });
  expect("errors --report " + Quote(no_per_query) + out,
         no_per_query.string() + ": runs[0].per_query: missing");
  const fs::path bad_error = write_edited("bad_error.json", [](nlohmann::json& j) {
    j["runs"][0]["per_query"][1]["position_error"] = "far";
  });
  expect("errors --report " + Quote(bad_error) + out,
         bad_error.string() +
             ": runs[0].per_query[1].position_error: expected a number, got a string");
  const fs::path no_runs =
      write_edited("no_runs.json", [](nlohmann::json& j) { j["runs"] = nlohmann::json::array(); });
  expect("errors --report " + Quote(no_runs) + out,
         no_runs.string() + ": runs: empty (a report has at least one run)");

  // Times: a poses file has none; a report from before p90 cannot give the p90 line.
  expect("anytime --report " + Quote(dir / "report.json") + out,
         (dir / "report.json").string() +
             ": runs[1].times_ms: null (run \"poses\" has no stage times: it was a poses file; "
             "evaluate "
             "cwloc-localize JSON lines)");
  const fs::path no_times =
      write_edited("no_times.json", [](nlohmann::json& j) { j["runs"][0].erase("times_ms"); });
  expect("scale --point 10:" + Quote(no_times) + out,
         no_times.string() + ": runs[0].times_ms: missing");
  const fs::path old = write_edited("old.json", [](nlohmann::json& j) {
    for (auto& [stage, quantiles] : j["runs"][0]["times_ms"].items()) quantiles.erase("p90");
  });
  expect("scale --point 10:" + Quote(old) + out,
         old.string() +
             ": runs[0].times_ms.total.p90: missing (the report is from a cwloc-eval without p90; "
             "evaluate again)");

  // --point syntax.
  for (const std::string point :
       {"report.json", "x:report.json", "0:report.json", "-4:report.json", "100:", "nan:r"}) {
    EXPECT_EQ(Plot("scale --point=" + point + out, &output), 2) << point;
    EXPECT_EQ(output, "cwloc-plot: error: argument --point: '" + point +
                          "': expected VIEWS:REPORT with VIEWS a positive number of views (e.g. "
                          "100000:eval.json)\n"
                          "Run 'cwloc-plot scale --help' for usage.\n");
  }
  EXPECT_EQ(Plot("errors --report " + Quote(dir / "report.json") + " --size 10x10" + out, &output),
            2);
  EXPECT_NE(output.find("argument --size: '10x10': expected WIDTHxHEIGHT in pixels"),
            std::string::npos)
      << output;
  EXPECT_EQ(Plot("errors --report " + Quote(dir / "report.json") + " --max-error 0" + out, &output),
            2);
  EXPECT_NE(output.find("argument --max-error: '0': expected a positive number"), std::string::npos)
      << output;

  // Where the figure cannot be written.
  expect(
      "errors --report " + Quote(dir / "report.json") + " -o " + Quote(dir / "no_dir" / "out.png"),
      (dir / "no_dir" / "out.png").string() + ": cannot write (No such file or directory)");
  expect("errors --report " + Quote(dir / "report.json") + " -o " + Quote(dir.path()),
         dir.path().string() + ": is a directory, expected a PNG file name");
  EXPECT_FALSE(fs::exists(dir / "out.png"));
  EXPECT_TRUE(TempFiles(dir.path()).empty());
}

}  // namespace
}  // namespace cwloc
