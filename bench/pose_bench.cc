// Google Benchmark of the robust absolute pose module: the minimal solvers (P3P, P4Pf, the
// gravity P2P) on random noise-free problems, and a full LO-RANSAC + refinement run on 300
// correspondences with 70% outliers and 1 px noise (the localizer's last stage), with known and
// unknown focal; and the final refinement alone with each solver (Ceres, builtin).

#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "localizer/pose/absolute_pose.h"
#include "localizer/pose/refine_pose.h"
#include "solvers/gravity_p2p.h"
#include "solvers/p3p.h"
#include "solvers/p4pf.h"
#include "tests/support/synthetic_pose.h"

namespace cwloc {
namespace {

constexpr int kNumProblems = 256;

void BM_P3P(benchmark::State& state) {
  std::mt19937_64 rng(1);
  std::vector<std::array<Eigen::Vector3d, 3>> bearings(kNumProblems), points(kNumProblems);
  for (int p = 0; p < kNumProblems; ++p) {
    const CameraPose pose = test::RandomPose(rng);
    for (int i = 0; i < 3; ++i) {
      const Eigen::Vector3d x(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1), 1.0);
      const Eigen::Vector3d cam = test::Uniform(rng, 2, 20) * x;
      bearings[p][i] = cam.normalized();
      points[p][i] = pose.rotation.conjugate() * (cam - pose.translation);
    }
  }
  std::vector<CameraPose> poses;
  size_t k = 0, solutions = 0;
  for (auto _ : state) {
    const size_t p = k++ % kNumProblems;
    solutions += P3P(bearings[p], points[p], &poses);
    benchmark::DoNotOptimize(poses.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["solutions"] = static_cast<double>(solutions) / state.iterations();
}
BENCHMARK(BM_P3P);

void BM_GravityP2P(benchmark::State& state) {
  SplitMix64 rng(5);
  struct Problem {
    std::array<Eigen::Vector3d, 2> bearings, points;
    Eigen::Vector3d gravity_in_camera, gravity_in_world;
  };
  std::vector<Problem> problems(kNumProblems);
  for (Problem& problem : problems) {
    const CameraPose pose = test::RandomPose(rng);
    problem.gravity_in_world =
        Eigen::Vector3d(test::Gaussian(rng), test::Gaussian(rng), test::Gaussian(rng)).normalized();
    problem.gravity_in_camera = pose.rotation * problem.gravity_in_world;
    for (int i = 0; i < 2; ++i) {
      const Eigen::Vector3d x(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1), 1.0);
      const Eigen::Vector3d cam = test::Uniform(rng, 2, 20) * x;
      problem.bearings[i] = cam.normalized();
      problem.points[i] = pose.rotation.conjugate() * (cam - pose.translation);
    }
  }
  std::vector<CameraPose> poses;
  size_t k = 0, solutions = 0;
  for (auto _ : state) {
    const Problem& p = problems[k++ % kNumProblems];
    solutions += GravityP2P(p.bearings, p.points, p.gravity_in_camera, p.gravity_in_world, &poses);
    benchmark::DoNotOptimize(poses.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["solutions"] = static_cast<double>(solutions) / state.iterations();
}
BENCHMARK(BM_GravityP2P);

void BM_P4Pf(benchmark::State& state) {
  std::mt19937_64 rng(2);
  std::vector<std::array<Eigen::Vector2d, 4>> pixels(kNumProblems);
  std::vector<std::array<Eigen::Vector3d, 4>> points(kNumProblems);
  for (int p = 0; p < kNumProblems; ++p) {
    const CameraPose pose = test::RandomPose(rng);
    const double f = test::Uniform(rng, 500, 2500);
    for (int i = 0; i < 4; ++i) {
      const Eigen::Vector2d px(test::Uniform(rng, -800, 800), test::Uniform(rng, -600, 600));
      const Eigen::Vector3d cam = test::Uniform(rng, 2, 20) * (px / f).homogeneous();
      pixels[p][i] = px;
      points[p][i] = pose.rotation.conjugate() * (cam - pose.translation);
    }
  }
  std::vector<CameraPose> poses;
  std::vector<double> focals;
  size_t k = 0, solutions = 0;
  for (auto _ : state) {
    const size_t p = k++ % kNumProblems;
    solutions += P4Pf(pixels[p], points[p], &poses, &focals);
    benchmark::DoNotOptimize(poses.data());
  }
  state.SetItemsProcessed(state.iterations());
  state.counters["solutions"] = static_cast<double>(solutions) / state.iterations();
}
BENCHMARK(BM_P4Pf);

std::vector<test::SyntheticPoseProblem> RansacProblems(double outlier_ratio) {
  std::mt19937_64 rng(3);
  test::SyntheticPoseOptions options;
  options.num_points = 300;
  options.outlier_ratio = outlier_ratio;
  options.noise_px = 1.0;
  std::vector<test::SyntheticPoseProblem> problems;
  for (int i = 0; i < 16; ++i) problems.push_back(test::MakeSyntheticProblem(options, rng));
  return problems;
}

// Arg 0: outlier percentage; arg 1: final refinement on/off.
void BM_RansacKnownFocal(benchmark::State& state) {
  const auto problems = RansacProblems(state.range(0) / 100.0);
  AbsolutePoseOptions options;
  options.refine = state.range(1) != 0;
  size_t k = 0, iterations = 0, successes = 0;
  for (auto _ : state) {
    const auto& p = problems[k++ % problems.size()];
    const AbsolutePoseResult r =
        EstimateAbsolutePose(p.normalized, p.points3D, p.focal_px, options);
    iterations += r.stats.iterations;
    successes += r.success;
  }
  state.counters["ransac_iters"] = static_cast<double>(iterations) / state.iterations();
  state.counters["success"] = static_cast<double>(successes) / state.iterations();
}
BENCHMARK(BM_RansacKnownFocal)
    ->Args({70, 1})
    ->Args({70, 0})
    ->Args({50, 1})
    ->Args({80, 1})
    ->Unit(benchmark::kMillisecond);

void BM_RansacUnknownFocal(benchmark::State& state) {
  const auto problems = RansacProblems(state.range(0) / 100.0);
  AbsolutePoseOptions options;
  options.refine = state.range(1) != 0;
  size_t k = 0, iterations = 0, successes = 0;
  for (auto _ : state) {
    const auto& p = problems[k++ % problems.size()];
    const AbsolutePoseResult r = EstimateAbsolutePoseUnknownFocal(p.pixels, p.points3D, options);
    iterations += r.stats.iterations;
    successes += r.success;
  }
  state.counters["ransac_iters"] = static_cast<double>(iterations) / state.iterations();
  state.counters["success"] = static_cast<double>(successes) / state.iterations();
}
BENCHMARK(BM_RansacUnknownFocal)
    ->Args({70, 1})
    ->Args({70, 0})
    ->Args({50, 1})
    ->Args({80, 1})
    ->Unit(benchmark::kMillisecond);

// The final refinement alone, per solver. Arg 0: the problem (0: pose, known focal length; 1:
// pose, f and k of a SIMPLE_RADIAL camera); arg 1: the correspondences. 1 px noise, every 7th point
// 3 to 5.5 px off (damped by the 2 px Cauchy loss), starts 0.02 rad and 2% of the depth off, 7% off
// in f.
void BM_Refine(benchmark::State& state, PoseRefiner refiner) {
  if (!PoseRefinerAvailable(refiner)) {
    state.SkipWithError("this build has no Ceres");
    return;
  }
  const bool radial = state.range(0) != 0;
  std::mt19937_64 rng(4);
  test::SyntheticPoseOptions synth;
  synth.num_points = static_cast<int>(state.range(1));
  synth.outlier_ratio = 0.0;
  synth.radial_k = radial ? -0.05 : 0.0;
  struct Start {
    test::SyntheticPoseProblem problem;
    CameraPose pose;
    double focal = 0.0;
  };
  std::vector<Start> starts;
  for (int i = 0; i < 16; ++i) {
    Start start{test::MakeSyntheticProblem(synth, rng), {}, 0.0};
    auto& pixels = start.problem.pixels;
    for (size_t j = 0; j < pixels.size(); j += 7) {
      const double angle = test::Uniform(rng, 0.0, 2.0 * std::numbers::pi);
      pixels[j] += test::Uniform(rng, 3.0, 5.5) * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    const auto random_unit = [&] {
      return Eigen::Vector3d(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1),
                             test::Uniform(rng, -1, 1))
          .normalized();
    };
    start.pose = start.problem.pose;
    start.pose.rotation = Eigen::AngleAxisd(0.02, random_unit()) * start.pose.rotation;
    start.pose.translation += 0.02 * start.problem.mean_depth * random_unit();
    start.focal = (radial ? 1.07 : 1.0) * start.problem.focal_px;
    starts.push_back(start);
  }
  std::vector<uint32_t> all(synth.num_points);
  for (size_t i = 0; i < all.size(); ++i) all[i] = static_cast<uint32_t>(i);
  PoseRefinementOptions options;
  options.refiner = refiner;
  options.loss_scale_px = 2.0;  // AbsolutePoseOptions' default
  options.refine_focal_length = radial;
  options.refine_radial_distortion = radial;
  size_t k = 0, iterations = 0;
  for (auto _ : state) {
    const Start& start = starts[k++ % starts.size()];
    CameraPose pose = start.pose;
    RadialCamera camera{start.focal, 0.0};
    PoseRefinementSummary summary;
    if (radial) {
      RefinePoseAndCamera(start.problem.pixels, start.problem.points3D, all, options, &pose,
                          &camera, &summary);
    } else {
      RefinePose(start.problem.pixels, start.problem.points3D, all, options, &pose,
                 &camera.focal_length_px, &summary);
    }
    iterations += summary.iterations;
    benchmark::DoNotOptimize(pose);
  }
  state.counters["iterations"] = static_cast<double>(iterations) / state.iterations();
}
BENCHMARK_CAPTURE(BM_Refine, ceres, PoseRefiner::kCeres)
    ->ArgNames({"radial", "points"})
    ->ArgsProduct({{0, 1}, {300, 2500}})
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Refine, builtin, PoseRefiner::kBuiltin)
    ->ArgNames({"radial", "points"})
    ->ArgsProduct({{0, 1}, {300, 2500}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace cwloc

BENCHMARK_MAIN();
