// cwloc-gravity-bench: what a gravity prior does to the known-focal pose stage
// (EstimateAbsolutePose, LO-RANSAC + refinement) on random 2D-3D sets: 100, 300 and 500
// correspondences, 50 to 90% outliers, 1 px noise, f = 1000 px on 1600 x 1200 px, depths 5 to 50,
// each without a prior and with a prior (sigma_deg at its default) whose camera direction is 0, 1
// and 3 degrees off. Prints markdown tables of medians: RANSAC iterations, CPU time, rotation and
// centre error, and the success rate (>= 12 inliers and the pose within 1 degree and 5% of the mean
// depth). Every problem and prior comes from SplitMix64 and --seed: the same tables on every
// platform, but for the times.

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <ctime>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "base/angles.h"
#include "base/split_mix64.h"
#include "localizer/pose/absolute_pose.h"
#include "tests/support/synthetic_pose.h"

namespace cwloc {
namespace {

// CPU seconds of this thread: the machine may be shared, wall time would count other jobs.
double ThreadSeconds() {
  timespec ts;
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

struct Run {
  double iterations = 0.0;
  double ms = 0.0;
  double rotation_deg = 0.0;
  double center = 0.0;  // units of the scene (depths 5 to 50)
  bool success = false;
};

struct Cell {
  std::vector<Run> runs;

  void Add(const Cell& other) { runs.insert(runs.end(), other.runs.begin(), other.runs.end()); }

  template <typename Get>
  double Median(Get get) const {
    std::vector<double> values;
    for (const Run& run : runs) values.push_back(get(run));
    if (values.empty()) return 0.0;
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    return values[values.size() / 2];
  }

  double SuccessRate() const {
    double n = 0;
    for (const Run& run : runs) n += run.success;
    return runs.empty() ? 0.0 : n / static_cast<double>(runs.size());
  }
};

constexpr int kNumConditions = 4;  // no prior; prior 0, 1, 3 degrees off
const double kPriorErrorsDeg[kNumConditions] = {-1.0, 0.0, 1.0, 3.0};

std::string ConditionName(int condition) {
  if (kPriorErrorsDeg[condition] < 0.0) return "none";
  char name[32];
  std::snprintf(name, sizeof(name), "%g deg off", kPriorErrorsDeg[condition]);
  return name;
}

void PrintHeader(const char* first) {
  std::printf(
      "| %s | gravity prior | RANSAC iterations | success | rotation error (deg) | "
      "centre error | time (ms) |\n",
      first);
  std::printf("|---|---|---|---|---|---|---|\n");
}

void PrintRow(const std::string& first, int condition, const Cell& cell) {
  std::printf("| %s | %s | %.0f | %.0f%% | %.3f | %.3f | %.2f |\n", first.c_str(),
              ConditionName(condition).c_str(),
              cell.Median([](const Run& r) { return r.iterations; }), 100.0 * cell.SuccessRate(),
              cell.Median([](const Run& r) { return r.rotation_deg; }),
              cell.Median([](const Run& r) { return r.center; }),
              cell.Median([](const Run& r) { return r.ms; }));
}

int Main(int argc, char** argv) {
  CLI::App app{"cwloc-gravity-bench: the known-focal pose stage with and without a gravity prior"};
  int trials = 100;
  uint64_t seed = 1;
  double sigma_deg = GravityPrior().sigma_deg;
  app.add_option("--trials", trials, "random problems per size and outlier ratio")
      ->check(CLI::PositiveNumber);
  app.add_option("--seed", seed, "SplitMix64 seed of the problems");
  app.add_option("--sigma-deg", sigma_deg, "the prior's sigma_deg")->check(CLI::PositiveNumber);
  CLI11_PARSE(app, argc, argv);

  const int sizes[] = {100, 300, 500};
  const double outlier_ratios[] = {0.5, 0.7, 0.8, 0.9};
  // pooled[outlier ratio][condition] over the sizes
  std::vector<std::vector<Cell>> pooled(4, std::vector<Cell>(kNumConditions));
  std::printf(
      "Every size and outlier ratio, %d problems each (medians; centre error in scene "
      "units, depths 5 to 50):\n\n",
      trials);
  PrintHeader("correspondences, outliers");
  for (const int size : sizes) {
    for (int o = 0; o < 4; ++o) {
      SplitMix64 rng(seed * 1000003 + static_cast<uint64_t>(size) * 10 + o);
      test::SyntheticPoseOptions synth;
      synth.num_points = size;
      synth.outlier_ratio = outlier_ratios[o];
      synth.noise_px = 1.0;
      std::vector<Cell> cells(kNumConditions);
      for (int trial = 0; trial < trials; ++trial) {
        const test::SyntheticPoseProblem problem = test::MakeSyntheticProblem(synth, rng);
        const Eigen::Vector3d in_world = test::RandomUnitVector(rng);
        const Eigen::Vector3d true_in_camera = problem.pose.rotation * in_world;
        const Eigen::Vector3d tilt_axis =
            true_in_camera.cross(test::RandomUnitVector(rng)).normalized();
        const uint64_t ransac_seed = rng.Next();
        for (int condition = 0; condition < kNumConditions; ++condition) {
          PoseContext context;
          context.ransac.seed = ransac_seed;
          if (kPriorErrorsDeg[condition] >= 0.0) {
            GravityPrior prior;
            prior.in_world = in_world;
            prior.in_camera =
                Eigen::AngleAxisd(kPriorErrorsDeg[condition] * kDegree, tilt_axis) * true_in_camera;
            prior.sigma_deg = sigma_deg;
            context.gravity = prior;
          }
          const double start = ThreadSeconds();
          const AbsolutePoseResult result = EstimateAbsolutePose(
              problem.normalized, problem.points3D, problem.focal_px, {}, context);
          Run run;
          run.ms = 1e3 * (ThreadSeconds() - start);
          run.iterations = result.stats.iterations;
          run.rotation_deg = test::RotationErrorDeg(result.pose, problem.pose);
          run.center = (result.pose.Center() - problem.pose.Center()).norm();
          run.success =
              result.success && run.rotation_deg < 1.0 && run.center < 0.05 * problem.mean_depth;
          cells[condition].runs.push_back(run);
        }
      }
      for (int condition = 0; condition < kNumConditions; ++condition) {
        char first[64];
        std::snprintf(first, sizeof(first), "%d, %.0f%%", size, 100.0 * outlier_ratios[o]);
        PrintRow(first, condition, cells[condition]);
        pooled[o][condition].Add(cells[condition]);
      }
    }
  }
  std::printf("\nPooled over 100, 300 and 500 correspondences (%d problems per row):\n\n",
              3 * trials);
  PrintHeader("outliers");
  for (int o = 0; o < 4; ++o) {
    for (int condition = 0; condition < kNumConditions; ++condition) {
      char first[16];
      std::snprintf(first, sizeof(first), "%.0f%%", 100.0 * outlier_ratios[o]);
      PrintRow(first, condition, pooled[o][condition]);
    }
  }
  return 0;
}

}  // namespace
}  // namespace cwloc

int main(int argc, char** argv) { return cwloc::Main(argc, argv); }
