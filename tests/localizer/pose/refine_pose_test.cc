#include "localizer/pose/refine_pose.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <numbers>
#include <numeric>
#include <optional>

#include "base/angles.h"
#include "robust/local_optimization.h"
#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

std::vector<uint32_t> AllIndices(size_t n) {
  std::vector<uint32_t> indices(n);
  std::iota(indices.begin(), indices.end(), 0u);
  return indices;
}

CameraPose Perturb(const CameraPose& pose, double angle_rad, double shift, std::mt19937_64& rng) {
  const Eigen::Vector3d axis = Eigen::Vector3d(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1),
                                               test::Uniform(rng, -1, 1))
                                   .normalized();
  const Eigen::Vector3d dir = Eigen::Vector3d(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1),
                                              test::Uniform(rng, -1, 1))
                                  .normalized();
  return CameraPose(Eigen::Quaterniond(Eigen::AngleAxisd(angle_rad, axis)) * pose.rotation,
                    pose.translation + shift * dir);
}

// A gravity constraint for a camera with rotation `truth`: a random world gravity, the camera's
// off by error_deg in a random direction, the weight of sigma_deg for the pixel noise that the
// Cauchy scale assumes.
GravityConstraint RandomGravity(const CameraPose& truth, double error_deg, double sigma_deg,
                                double loss_scale_px, SplitMix64& rng) {
  GravityPrior prior;
  prior.in_world = test::RandomUnitVector(rng);
  const Eigen::Vector3d in_camera = truth.rotation * prior.in_world;
  const Eigen::Vector3d axis = in_camera.cross(test::RandomUnitVector(rng)).normalized();
  prior.in_camera = Eigen::AngleAxisd(error_deg * kDegree, axis) * in_camera;
  prior.sigma_deg = sigma_deg;
  return GravityWeight(prior, CauchyScaleNoise(loss_scale_px));
}

double GravityAngleDeg(const CameraPose& pose, const GravityConstraint& gravity) {
  return GravityAngle(pose.RotationMatrix(), gravity.in_world, gravity.in_camera) / kDegree;
}

test::SyntheticPoseOptions Clean() {
  test::SyntheticPoseOptions options;
  options.num_points = 100;
  options.outlier_ratio = 0.0;
  options.noise_px = 0.0;
  return options;
}

// Every refiner this build has runs the same tests; each must solve the problems alone.
class RefinerTest : public testing::TestWithParam<PoseRefiner> {
 protected:
  PoseRefinementOptions Options() const {
    PoseRefinementOptions options;
    options.refiner = GetParam();
    return options;
  }
};

std::vector<PoseRefiner> AvailableRefiners() {
  std::vector<PoseRefiner> refiners;
  for (const PoseRefiner refiner : {PoseRefiner::kCeres, PoseRefiner::kBuiltin}) {
    if (PoseRefinerAvailable(refiner)) refiners.push_back(refiner);
  }
  return refiners;
}

}  // namespace

// For CTest's test names; found by argument-dependent lookup in PoseRefiner's namespace.
void PrintTo(PoseRefiner refiner, std::ostream* out) { *out << PoseRefinerName(refiner); }

namespace {

std::string RefinerName(const testing::TestParamInfo<PoseRefiner>& param) {
  return std::string(PoseRefinerName(param.param));
}

INSTANTIATE_TEST_SUITE_P(Refiners, RefinerTest, testing::ValuesIn(AvailableRefiners()),
                         RefinerName);

TEST_P(RefinerTest, ConvergesFromAPerturbedPose) {
  auto& rng = test::Rng();
  for (int trial = 0; trial < 10; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    CameraPose pose = Perturb(problem.pose, 0.02, 0.3, rng);
    double f = problem.focal_px;
    PoseRefinementSummary summary;
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                           Options(), &pose, &f, &summary));
    EXPECT_TRUE(summary.usable);
    EXPECT_LT(summary.final_cost, summary.initial_cost);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
    EXPECT_LT((pose.Center() - problem.pose.Center()).norm(), 1e-6);
    EXPECT_EQ(f, problem.focal_px);  // held constant
  }
}

TEST_P(RefinerTest, RefinesFocalLength) {
  auto& rng = test::Rng();
  const auto problem = test::MakeSyntheticProblem(Clean(), rng);
  CameraPose pose = Perturb(problem.pose, 0.01, 0.1, rng);
  double f = 1.05 * problem.focal_px;
  PoseRefinementOptions options = Options();
  options.refine_focal_length = true;
  ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                         options, &pose, &f));
  EXPECT_NEAR(f, problem.focal_px, 1e-6 * problem.focal_px);
  EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
}

TEST_P(RefinerTest, RecoversFocalAndRadialDistortion) {
  auto& rng = test::Rng();
  for (const double k : {-0.15, 0.0, 0.1}) {
    test::SyntheticPoseOptions synth = Clean();
    synth.radial_k = k;
    const auto problem = test::MakeSyntheticProblem(synth, rng);
    CameraPose pose = Perturb(problem.pose, 0.01, 0.1, rng);
    RadialCamera camera{0.95 * problem.focal_px, 0.0};
    PoseRefinementOptions options = Options();
    options.refine_focal_length = true;
    options.refine_radial_distortion = true;
    ASSERT_TRUE(RefinePoseAndCamera(problem.pixels, problem.points3D,
                                    AllIndices(problem.pixels.size()), options, &pose, &camera));
    EXPECT_NEAR(camera.focal_length_px, problem.focal_px, 1e-6 * problem.focal_px) << k;
    EXPECT_NEAR(camera.k, k, 1e-8);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
    // The residual it minimised is RadialCamera::Project's.
    for (size_t i = 0; i < problem.pixels.size(); ++i) {
      EXPECT_LT((camera.Project(pose.Apply(problem.points3D[i])) - problem.pixels[i]).norm(), 1e-6);
    }
  }
}

TEST_P(RefinerTest, HoldsWhatItIsNotAskedToRefine) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions synth = Clean();
  synth.radial_k = -0.1;
  const auto problem = test::MakeSyntheticProblem(synth, rng);
  CameraPose pose = problem.pose;
  RadialCamera camera{problem.focal_px, 0.0};
  PoseRefinementOptions options = Options();
  options.refine_focal_length = true;  // k stays 0: the focal length absorbs what it can
  ASSERT_TRUE(RefinePoseAndCamera(problem.pixels, problem.points3D,
                                  AllIndices(problem.pixels.size()), options, &pose, &camera));
  EXPECT_EQ(camera.k, 0.0);
  EXPECT_NE(camera.focal_length_px, problem.focal_px);
  options.refine_focal_length = false;
  options.refine_radial_distortion = true;
  camera = {1.02 * problem.focal_px, 0.0};
  ASSERT_TRUE(RefinePoseAndCamera(problem.pixels, problem.points3D,
                                  AllIndices(problem.pixels.size()), options, &pose, &camera));
  EXPECT_EQ(camera.focal_length_px, 1.02 * problem.focal_px);
  EXPECT_NE(camera.k, 0.0);
  // Too few correspondences for pose, focal length and k: nothing changes.
  options.refine_focal_length = true;
  const std::vector<uint32_t> five = {0, 1, 2, 3, 4};
  const RadialCamera before = camera;
  EXPECT_FALSE(
      RefinePoseAndCamera(problem.pixels, problem.points3D, five, options, &pose, &camera));
  EXPECT_EQ(camera.focal_length_px, before.focal_length_px);
  EXPECT_EQ(camera.k, before.k);
}

TEST_P(RefinerTest, QuaternionOrderRoundTrips) {
  // A rotation whose w, x, y, z are all different: a w/x swap would be caught.
  auto& rng = test::Rng();
  auto problem = test::MakeSyntheticProblem(Clean(), rng);
  const Eigen::Quaterniond q = Eigen::Quaterniond(0.9, 0.3, -0.2, 0.1).normalized();
  for (size_t i = 0; i < problem.points3D.size(); ++i) {
    const Eigen::Vector3d cam = problem.pose.Apply(problem.points3D[i]);
    problem.points3D[i] = q.conjugate() * (cam - problem.pose.translation);
  }
  CameraPose pose(q, problem.pose.translation);
  double f = problem.focal_px;
  ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                         Options(), &pose, &f));
  EXPECT_LT(pose.rotation.angularDistance(q), 1e-9);
}

TEST_P(RefinerTest, CauchyLossResistsOutliersAmongIndices) {
  auto& rng = test::Rng();
  test::SyntheticPoseOptions options = Clean();
  options.noise_px = 0.5;
  PoseRefinementOptions cauchy = Options();
  cauchy.loss_scale_px = 1.0;
  PoseRefinementOptions squared = Options();
  squared.loss_scale_px = 0.0;
  // Summed over problems: one problem's noise can favour either.
  double robust_error = 0.0, plain_error = 0.0;
  for (int trial = 0; trial < 20; ++trial) {
    auto problem = test::MakeSyntheticProblem(options, rng);
    // 15% gross errors of 5.5 px (under a 6 px threshold, so they survive as inliers).
    for (int i = 0; i < 15; ++i) {
      const double angle = test::Uniform(rng, 0.0, 2.0 * std::numbers::pi);
      problem.pixels[i] += 5.5 * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    const auto error = [&](const CameraPose& pose) {
      return test::RotationErrorDeg(pose, problem.pose) / 0.01 +
             (pose.Center() - problem.pose.Center()).norm() / 0.01;
    };
    CameraPose robust = problem.pose, plain = problem.pose;
    double f1 = problem.focal_px, f2 = problem.focal_px;
    const auto all = AllIndices(problem.pixels.size());
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, cauchy, &robust, &f1));
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, squared, &plain, &f2));
    robust_error += error(robust);
    plain_error += error(plain);
  }
  EXPECT_LT(robust_error, 0.75 * plain_error);
}

TEST_P(RefinerTest, GravityPriorWeighsAgainstThePoints) {
  auto& rng = test::Rng();
  SplitMix64 gravity_rng = test::SplitMixFrom(rng);
  for (int trial = 0; trial < 10; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    const CameraPose start = Perturb(problem.pose, 0.02, 0.3, rng);
    const auto all = AllIndices(problem.pixels.size());
    PoseRefinementOptions options = Options();
    options.loss_scale_px = 2.0;
    double f = problem.focal_px;
    // An exact prior: the same minimum.
    options.gravity = RandomGravity(problem.pose, 0.0, 1.0, 2.0, gravity_rng);
    CameraPose pose = start;
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, options, &pose, &f));
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
    EXPECT_LT((pose.Center() - problem.pose.Center()).norm(), 1e-6);
    // A prior 2 degrees off: with sigma 1 degree, 100 exact points outweigh it (their
    // information on the tilt is ~1e8 px^2 / rad^2, the prior's (0.84 / 0.0175)^2 = 2300).
    options.gravity = RandomGravity(problem.pose, 2.0, 1.0, 2.0, gravity_rng);
    pose = start;
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, options, &pose, &f));
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 0.01);
    // With sigma 1e-4 degrees (weight^2 = 2.3e11) the prior wins.
    options.gravity = RandomGravity(problem.pose, 2.0, 1e-4, 2.0, gravity_rng);
    pose = start;
    ASSERT_TRUE(RefinePose(problem.pixels, problem.points3D, all, options, &pose, &f));
    EXPECT_LT(GravityAngleDeg(pose, *options.gravity), 0.01);
    EXPECT_GT(test::RotationErrorDeg(pose, problem.pose), 1.9);
  }
}

TEST_P(RefinerTest, TooFewPoints) {
  CameraPose pose;
  double f = 1000.0;
  const std::vector<Eigen::Vector2d> pixels(3, Eigen::Vector2d::Zero());
  const std::vector<Eigen::Vector3d> points(3, Eigen::Vector3d(0, 0, 5));
  EXPECT_FALSE(RefinePose(pixels, points, AllIndices(3), Options(), &pose, &f));
}

#ifdef CWLOC_WITH_CERES
// Both refiners on the same inputs. The builtin one follows Ceres' trust-region rules, so the
// two take the same steps and stop at the same minimum, not merely near it. Measured over these
// cases: the same iteration counts, and at most 4.2e-15 apart (rotation in rad, centre in mean
// depths, focal length relative), k within 1.1e-13 (telephoto, where k is weakly observed).
struct AgreementCase {
  const char* name;
  bool radial = false;  // RefinePoseAndCamera, else RefinePose
  bool refine_focal = false;
  bool refine_k = false;
  double true_k = 0.0;
  double loss_scale_px = 0.0;  // 0: plain least squares
  double start_angle_rad = 0.02;
  double start_shift = 0.02;  // times the mean depth
  int max_iterations = 50;
  double min_depth = 5.0;  // of the points; the images are 1600 x 1200
  double max_depth = 50.0;
  double focal_px = 1000.0;
  double outlier_ratio = 0.0;  // random matches at least 20 px off
  // > 0: a gravity prior with this sigma, the camera's gravity gravity_error_deg off.
  double gravity_sigma_deg = 0.0;
  double gravity_error_deg = 0.0;
};

struct Refined {
  bool ok = false;
  CameraPose pose;
  RadialCamera camera;
  PoseRefinementSummary summary;
};

Refined RefineWith(PoseRefiner refiner, const AgreementCase& c,
                   const test::SyntheticPoseProblem& problem, const CameraPose& start,
                   const RadialCamera& start_camera,
                   const std::optional<GravityConstraint>& gravity) {
  PoseRefinementOptions options;
  options.gravity = gravity;
  options.refiner = refiner;
  options.loss_scale_px = c.loss_scale_px;
  options.refine_focal_length = c.refine_focal;
  options.refine_radial_distortion = c.refine_k;
  options.max_iterations = c.max_iterations;
  Refined out{false, start, start_camera, {}};
  const auto all = AllIndices(problem.pixels.size());
  if (c.radial) {
    out.ok = RefinePoseAndCamera(problem.pixels, problem.points3D, all, options, &out.pose,
                                 &out.camera, &out.summary);
  } else {
    out.ok = RefinePose(problem.pixels, problem.points3D, all, options, &out.pose,
                        &out.camera.focal_length_px, &out.summary);
  }
  return out;
}

// The case's name in CTest's test names.
void PrintTo(const AgreementCase& c, std::ostream* out) { *out << c.name; }

class RefinerAgreementTest : public testing::TestWithParam<AgreementCase> {};

TEST_P(RefinerAgreementTest, BuiltinStopsWhereCeresStops) {
  const AgreementCase& c = GetParam();
  auto& rng = test::Rng();
  test::SyntheticPoseOptions synth;
  synth.num_points = 200;
  synth.outlier_ratio = c.outlier_ratio;
  synth.min_depth = c.min_depth;
  synth.max_depth = c.max_depth;
  synth.focal_px = c.focal_px;
  synth.noise_px = 1.0;
  synth.radial_k = c.true_k;
  double max_rotation = 0, max_center = 0, max_focal = 0, max_k = 0;
  int refined = 0;
  constexpr int kTrials = 40;
  // Drawn only for the gravity cases, so that the others keep their problems.
  std::optional<SplitMix64> gravity_rng;
  if (c.gravity_sigma_deg > 0.0) gravity_rng = test::SplitMixFrom(rng);
  for (int trial = 0; trial < kTrials; ++trial) {
    SCOPED_TRACE(trial);
    auto problem = test::MakeSyntheticProblem(synth, rng);
    // Every 7th point 3 to 5.5 px off: inliers of a 6 px threshold that the loss damps.
    for (size_t i = 0; i < problem.pixels.size(); i += 7) {
      const double angle = test::Uniform(rng, 0.0, 2.0 * std::numbers::pi);
      problem.pixels[i] +=
          test::Uniform(rng, 3.0, 5.5) * Eigen::Vector2d(std::cos(angle), std::sin(angle));
    }
    const CameraPose start =
        Perturb(problem.pose, c.start_angle_rad, c.start_shift * problem.mean_depth, rng);
    const RadialCamera start_camera{
        c.refine_focal ? test::Uniform(rng, 0.93, 1.07) * problem.focal_px : problem.focal_px, 0.0};
    std::optional<GravityConstraint> gravity;
    if (gravity_rng.has_value()) {
      gravity = RandomGravity(problem.pose, c.gravity_error_deg, c.gravity_sigma_deg,
                              c.loss_scale_px, *gravity_rng);
    }
    const Refined ceres = RefineWith(PoseRefiner::kCeres, c, problem, start, start_camera, gravity);
    const Refined builtin =
        RefineWith(PoseRefiner::kBuiltin, c, problem, start, start_camera, gravity);
    ASSERT_EQ(ceres.ok, builtin.ok);
    EXPECT_EQ(ceres.summary.iterations, builtin.summary.iterations);
    if (!ceres.ok) continue;  // a start with points behind the camera
    ++refined;
    EXPECT_NEAR(ceres.summary.initial_cost, builtin.summary.initial_cost,
                1e-12 * ceres.summary.initial_cost);
    EXPECT_NEAR(ceres.summary.final_cost, builtin.summary.final_cost,
                1e-12 * ceres.summary.final_cost);
    max_rotation =
        std::max(max_rotation, ceres.pose.rotation.angularDistance(builtin.pose.rotation));
    max_center = std::max(
        max_center, (ceres.pose.Center() - builtin.pose.Center()).norm() / problem.mean_depth);
    max_focal = std::max(max_focal,
                         std::abs(ceres.camera.focal_length_px - builtin.camera.focal_length_px) /
                             ceres.camera.focal_length_px);
    max_k = std::max(max_k, std::abs(ceres.camera.k - builtin.camera.k));
  }
  std::cout << c.name << ": " << refined << "/" << kTrials << " refined; largest differences: "
            << "rotation " << max_rotation << " rad, centre " << max_center << " x depth, focal "
            << max_focal << " x f, k " << max_k << "\n";
  EXPECT_GE(refined, kTrials / 2);
  EXPECT_LT(max_rotation, 1e-8);
  EXPECT_LT(max_center, 1e-8);
  EXPECT_LT(max_focal, 1e-8);
  EXPECT_LT(max_k, 1e-8);
}

std::string CaseName(const testing::TestParamInfo<AgreementCase>& param) {
  return param.param.name;
}

INSTANTIATE_TEST_SUITE_P(
    Problems, RefinerAgreementTest,
    testing::Values(
        AgreementCase{"pose", false, false, false, 0.0, 2.0},
        AgreementCase{"pose_cauchy1", false, false, false, 0.0, 1.0},
        AgreementCase{"pose_squared", false, false, false, 0.0, 0.0},
        AgreementCase{"pose_far_start", false, false, false, 0.0, 2.0, 0.3, 0.3},
        // Points as near as 0.5: steps that put some behind the camera are rejected.
        AgreementCase{"pose_near_points", false, false, false, 0.0, 2.0, 0.3, 0.1, 50, 0.5},
        AgreementCase{"pose_random_outliers", false, false, false, 0.0, 2.0, 0.3, 0.3, 50, 5.0,
                      50.0, 1000.0, 0.5},
        AgreementCase{"pose_focal", false, true, false, 0.0, 2.0},
        // A narrow field of view far away: the focal length and the depth nearly trade off.
        AgreementCase{"pose_focal_telephoto", false, true, false, 0.0, 2.0, 0.02, 0.02, 50, 40.0,
                      50.0, 8000.0},
        AgreementCase{"focal_k_barrel", true, true, true, -0.12, 2.0},
        AgreementCase{"focal_k_none", true, true, true, 0.0, 2.0},
        AgreementCase{"focal_k_pincushion", true, true, true, 0.08, 2.0},
        AgreementCase{"focal_k_far_start", true, true, true, -0.05, 2.0, 0.2, 0.2},
        AgreementCase{"focal_k_near_points", true, true, true, -0.1, 2.0, 0.2, 0.1, 50, 0.5},
        AgreementCase{"focal_k_random_outliers", true, true, true, -0.1, 2.0, 0.2, 0.2, 50, 5.0,
                      50.0, 1000.0, 0.5},
        AgreementCase{"focal_k_telephoto", true, true, true, -0.05, 2.0, 0.02, 0.02, 50, 40.0, 50.0,
                      8000.0},
        AgreementCase{"focal_k_3_iterations", true, true, true, -0.05, 2.0, 0.02, 0.02, 3},
        AgreementCase{"radial_focal_only", true, true, false, -0.05, 2.0},
        AgreementCase{"radial_k_only", true, false, true, -0.05, 2.0},
        // A gravity prior: consistent with the points (sigma 1 degree, 0.5 off), and so strong
        // (sigma 0.01 degree, 2 off) that it fights them.
        AgreementCase{.name = "pose_gravity",
                      .loss_scale_px = 2.0,
                      .gravity_sigma_deg = 1.0,
                      .gravity_error_deg = 0.5},
        AgreementCase{.name = "pose_gravity_strong",
                      .loss_scale_px = 2.0,
                      .gravity_sigma_deg = 0.01,
                      .gravity_error_deg = 2.0},
        AgreementCase{.name = "pose_squared_gravity_strong",
                      .loss_scale_px = 0.0,
                      .gravity_sigma_deg = 0.01,
                      .gravity_error_deg = 2.0},
        AgreementCase{.name = "pose_focal_gravity_strong",
                      .refine_focal = true,
                      .loss_scale_px = 2.0,
                      .gravity_sigma_deg = 0.01,
                      .gravity_error_deg = 2.0},
        AgreementCase{.name = "focal_k_gravity",
                      .radial = true,
                      .refine_focal = true,
                      .refine_k = true,
                      .true_k = -0.1,
                      .loss_scale_px = 2.0,
                      .gravity_sigma_deg = 1.0,
                      .gravity_error_deg = 1.0},
        AgreementCase{.name = "focal_k_gravity_strong_far_start",
                      .radial = true,
                      .refine_focal = true,
                      .refine_k = true,
                      .true_k = -0.1,
                      .loss_scale_px = 2.0,
                      .start_angle_rad = 0.2,
                      .start_shift = 0.2,
                      .gravity_sigma_deg = 0.01,
                      .gravity_error_deg = 2.0}),
    CaseName);
#endif  // CWLOC_WITH_CERES

TEST(LocalOptimization, PoseConvergesWithFewIterations) {
  auto& rng = test::Rng();
  for (int trial = 0; trial < 20; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    CameraPose pose = Perturb(problem.pose, 0.02, 0.3, rng);
    LocalOptimizationOptions options;
    options.max_iterations = 20;
    OptimizePose(problem.normalized, problem.points3D, AllIndices(problem.pixels.size()), options,
                 &pose);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-7);
    EXPECT_LT((pose.Center() - problem.pose.Center()).norm(), 1e-7);
  }
}

TEST(LocalOptimization, GravityConstraint) {
  auto& rng = test::Rng();
  SplitMix64 gravity_rng = test::SplitMixFrom(rng);
  for (int trial = 0; trial < 10; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    const auto all = AllIndices(problem.pixels.size());
    const CameraPose start = Perturb(problem.pose, 0.02, 0.3, rng);
    LocalOptimizationOptions options;
    options.max_iterations = 20;
    // Normalised coordinates: sigma_px / f. An exact prior keeps the minimum.
    GravityConstraint gravity = RandomGravity(problem.pose, 0.0, 1.0, 2.0, gravity_rng);
    gravity.weight /= problem.focal_px;
    options.gravity = gravity;
    CameraPose pose = start;
    OptimizePose(problem.normalized, problem.points3D, all, options, &pose);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-7);
    // A prior 2 degrees off with sigma 1e-4 degrees wins over the points; so it does with the
    // focal length free.
    gravity = RandomGravity(problem.pose, 2.0, 1e-4, 2.0, gravity_rng);
    gravity.weight /= problem.focal_px;
    options.gravity = gravity;
    pose = start;
    OptimizePose(problem.normalized, problem.points3D, all, options, &pose);
    EXPECT_LT(GravityAngleDeg(pose, gravity), 0.01);
    options.gravity = RandomGravity(problem.pose, 2.0, 1e-4, 2.0, gravity_rng);
    pose = start;
    double f = problem.focal_px;
    OptimizePoseAndFocal(problem.pixels, problem.points3D, all, options, &pose, &f);
    EXPECT_LT(GravityAngleDeg(pose, *options.gravity), 0.01);
  }
}

TEST(LocalOptimization, PoseAndFocalConverge) {
  auto& rng = test::Rng();
  for (int trial = 0; trial < 20; ++trial) {
    const auto problem = test::MakeSyntheticProblem(Clean(), rng);
    CameraPose pose = Perturb(problem.pose, 0.01, 0.1, rng);
    double f = problem.focal_px * test::Uniform(rng, 0.9, 1.1);
    LocalOptimizationOptions options;
    options.max_iterations = 30;
    options.loss_scale = 2.0;
    OptimizePoseAndFocal(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                         options, &pose, &f);
    EXPECT_NEAR(f, problem.focal_px, 1e-6 * problem.focal_px);
    EXPECT_LT(test::RotationErrorDeg(pose, problem.pose), 1e-6);
  }
}

// Refines pose, f and k on `trials` noisy copies of one scene: the spread of the estimates, and
// what FocalDepthAt predicts at each solution (variances and correlations averaged
// over the trials, so that one trial's residual variance does not decide).
struct Spread {
  int trials = 0;
  double focal_std = 0, depth_std = 0, correlation = 0;
  FocalDepth predicted;
};

Spread MeasureSpread(const test::SyntheticPoseOptions& synth, int trials, std::mt19937_64& rng) {
  test::SyntheticPoseOptions clean = synth;
  clean.noise_px = 0.0;
  const auto truth = test::MakeSyntheticProblem(clean, rng);
  const Eigen::Vector3d axis = truth.pose.rotation.conjugate() * Eigen::Vector3d::UnitZ();
  std::normal_distribution<double> noise(0.0, synth.noise_px);
  PoseRefinementOptions options;
  options.refine_focal_length = true;
  options.refine_radial_distortion = true;
  options.loss_scale_px = 2.0;
  const std::vector<uint32_t> all = AllIndices(truth.pixels.size());
  std::vector<double> focal, depth;
  Spread spread;
  spread.trials = trials;
  double focal_variance = 0, depth_variance = 0, correlation = 0;
  for (int trial = 0; trial < trials; ++trial) {
    std::vector<Eigen::Vector2d> pixels = truth.pixels;
    for (Eigen::Vector2d& pixel : pixels) pixel += Eigen::Vector2d(noise(rng), noise(rng));
    CameraPose pose = truth.pose;
    RadialCamera camera{truth.focal_px, 0.0};
    EXPECT_TRUE(RefinePoseAndCamera(pixels, truth.points3D, all, options, &pose, &camera));
    focal.push_back(camera.focal_length_px);
    depth.push_back(axis.dot(pose.Center()));
    const auto predicted = FocalDepthAt(pixels, truth.points3D, all, options, pose, camera);
    EXPECT_TRUE(predicted.has_value());
    if (!predicted) continue;
    focal_variance += predicted->focal_std_px * predicted->focal_std_px / trials;
    depth_variance += predicted->depth_std * predicted->depth_std / trials;
    correlation += predicted->correlation / trials;
  }
  spread.predicted.focal_std_px = std::sqrt(focal_variance);
  spread.predicted.depth_std = std::sqrt(depth_variance);
  spread.predicted.correlation = correlation;
  const auto mean = [](const std::vector<double>& v) {
    return std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
  };
  const double mf = mean(focal), md = mean(depth);
  double sff = 0, sdd = 0, sfd = 0;
  for (size_t i = 0; i < focal.size(); ++i) {
    sff += (focal[i] - mf) * (focal[i] - mf);
    sdd += (depth[i] - md) * (depth[i] - md);
    sfd += (focal[i] - mf) * (depth[i] - md);
  }
  spread.focal_std = std::sqrt(sff / double(trials - 1));
  spread.depth_std = std::sqrt(sdd / double(trials - 1));
  spread.correlation = sfd / std::sqrt(sff * sdd);
  return spread;
}

// Inliers only, at uniform pixels of a width x height image.
test::SyntheticPoseOptions View(int points, double noise_px, double focal_px, double width_px,
                                double height_px) {
  test::SyntheticPoseOptions synth;
  synth.num_points = points;
  synth.outlier_ratio = 0.0;
  synth.noise_px = noise_px;
  synth.focal_px = focal_px;
  synth.width_px = width_px;
  synth.height_px = height_px;
  return synth;
}

void ExpectPredictedSpread(const Spread& spread) {
  EXPECT_NEAR(spread.predicted.focal_std_px, spread.focal_std, 0.25 * spread.focal_std);
  EXPECT_NEAR(spread.predicted.depth_std, spread.depth_std, 0.25 * spread.depth_std);
  // A sample correlation's standard error is about (1 - rho^2) / sqrt(n): 0.001 for the
  // telephoto's -0.99, 0.05 for a wide view's -0.5.
  const double rho = spread.correlation;
  EXPECT_NEAR(spread.predicted.correlation, rho,
              4.0 * (1.0 - rho * rho) / std::sqrt(double(spread.trials)) + 0.005);
}

TEST(FocalDepthAt, PredictsTheSpreadOfANarrowView) {
  // A telephoto shot: f = 3000 px on a 1000 x 700 image of a scene 40-50 units deep, 60 inliers
  // with 1.5 px of noise.
  test::SyntheticPoseOptions synth = View(60, 1.5, 3000.0, 1000.0, 700.0);
  synth.min_depth = 40.0;
  synth.max_depth = 50.0;
  const Spread spread = MeasureSpread(synth, 300, test::Rng());
  ExpectPredictedSpread(spread);
  // A longer focal length goes with a camera further back: along the axis the centre's
  // coordinate falls.
  EXPECT_LT(spread.predicted.correlation, -0.95);
  EXPECT_TRUE(WeaklyConstrained(spread.predicted, synth.focal_px))
      << spread.predicted.focal_std_px << " px";
}

TEST(FocalDepthAt, AWideDeepViewIsWellConstrained) {
  const test::SyntheticPoseOptions synth = View(150, 1.0, 800.0, 1600.0, 1200.0);
  const Spread spread = MeasureSpread(synth, 300, test::Rng());
  ExpectPredictedSpread(spread);
  EXPECT_LT(spread.predicted.focal_std_px, 0.002 * synth.focal_px);
  EXPECT_FALSE(WeaklyConstrained(spread.predicted, synth.focal_px));
}

TEST(FocalDepthAt, EmptyWhenTheProblemCannotBeEvaluated) {
  auto& rng = test::Rng();
  const auto problem = test::MakeSyntheticProblem(Clean(), rng);
  PoseRefinementOptions options;
  options.refine_focal_length = true;
  options.refine_radial_distortion = true;
  // Every point behind the camera.
  CameraPose behind = problem.pose;
  behind.translation.z() -= 1e3;
  EXPECT_FALSE(FocalDepthAt(problem.pixels, problem.points3D, AllIndices(problem.pixels.size()),
                            options, behind, RadialCamera{problem.focal_px, 0.0}));
  // Fewer residuals than parameters.
  EXPECT_FALSE(FocalDepthAt(problem.pixels, problem.points3D, AllIndices(3), options, problem.pose,
                            RadialCamera{problem.focal_px, 0.0}));
}

}  // namespace
}  // namespace cwloc
