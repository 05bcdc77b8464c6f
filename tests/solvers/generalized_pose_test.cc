#include "solvers/generalized_pose.h"

#include <gtest/gtest.h>

#include <limits>

#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"
#ifdef CWLOC_WITH_OPENGV
#include <opengv/absolute_pose/NoncentralAbsoluteAdapter.hpp>
#include <opengv/absolute_pose/methods.hpp>
#endif

namespace cwloc {
namespace {

// A random rig of `num_cameras` cameras within a metre of its origin, and points in front of
// them: point i is seen by camera camera_of[i].
struct RigProblem {
  CameraPose rig_from_world;
  std::vector<CameraPose> cam_from_rig;
  std::vector<int> camera_of;
  std::vector<Eigen::Vector3d> bearings;  // in the point's camera
  std::vector<Eigen::Vector3d> points;
};

RigProblem RandomRigProblem(SplitMix64& rng, int num_cameras, const std::vector<int>& camera_of,
                            double baseline = 1.0) {
  RigProblem p;
  p.rig_from_world = test::RandomPose(rng);
  for (int c = 0; c < num_cameras; ++c) {
    const Eigen::Quaterniond q = test::RandomRotation(rng);
    const Eigen::Vector3d center =
        baseline * Eigen::Vector3d(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1),
                                   test::Uniform(rng, -1, 1));
    p.cam_from_rig.push_back(CameraPose(q, -(q * center)));
  }
  p.camera_of = camera_of;
  for (const int c : camera_of) {
    const Eigen::Vector2d xy(test::Uniform(rng, -1, 1), test::Uniform(rng, -1, 1));
    const Eigen::Vector3d in_cam = test::Uniform(rng, 2.0, 20.0) * xy.homogeneous();
    p.bearings.push_back(in_cam.normalized());
    const CameraPose& cam = p.cam_from_rig[c];
    const Eigen::Vector3d in_rig = cam.rotation.conjugate() * (in_cam - cam.translation);
    p.points.push_back(p.rig_from_world.rotation.conjugate() *
                       (in_rig - p.rig_from_world.translation));
  }
  return p;
}

RigRay RayOf(const RigProblem& p, int i) {
  const CameraPose& cam = p.cam_from_rig[p.camera_of[i]];
  return {cam.Center(), cam.rotation.conjugate() * p.bearings[i]};
}

// How far point i lies off its ray under `pose`, or infinity behind its origin.
double RayDistance(const RigRay& ray, const CameraPose& pose, const Eigen::Vector3d& point) {
  const Eigen::Vector3d v = pose.Apply(point) - ray.origin;
  if (!(v.dot(ray.direction) > 0.0)) return std::numeric_limits<double>::infinity();
  return (v - v.dot(ray.direction) * ray.direction).norm() / v.norm();
}

// Three rays from three cameras, two cameras, or one (a central camera: P3P).
void ExpectRecovers(const std::vector<int>& camera_of, int num_cameras, int trials) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  int accurate = 0;
  for (int trial = 0; trial < trials; ++trial) {
    const RigProblem p = RandomRigProblem(rng, num_cameras, camera_of);
    const std::array<RigRay, 3> rays = {RayOf(p, 0), RayOf(p, 1), RayOf(p, 2)};
    const int n = GeneralizedP3P(rays, {p.points[0], p.points[1], p.points[2]}, &poses);
    ASSERT_EQ(n, static_cast<int>(poses.size()));
    ASSERT_LE(n, 8);
    double best = std::numeric_limits<double>::infinity();
    for (const CameraPose& pose : poses) {
      ASSERT_TRUE(pose.rotation.coeffs().allFinite() && pose.translation.allFinite());
      // Every solution puts every point on its ray, in front.
      for (int i = 0; i < 3; ++i) EXPECT_LT(RayDistance(rays[i], pose, p.points[i]), 1e-7);
      best = std::min(best, test::PoseError(pose, p.rig_from_world));
    }
    accurate += best < 1e-8;
  }
  // A random problem near a degenerate configuration (the solver's elimination badly
  // conditioned) can miss 1e-8, rarely.
  EXPECT_GE(accurate, trials - trials / 200) << accurate << " of " << trials;
}

TEST(GeneralizedP3P, RecoversRandomRigPosesFromThreeCameras) { ExpectRecovers({0, 1, 2}, 3, 2000); }

TEST(GeneralizedP3P, RecoversRandomRigPosesFromTwoCameras) { ExpectRecovers({0, 0, 1}, 2, 1000); }

TEST(GeneralizedP3P, ACentralCameraGivesP3PsSolutions) { ExpectRecovers({0, 0, 0}, 1, 1000); }

TEST(GeneralizedP3P, DegenerateSamplesGiveNoPose) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  RigProblem p = RandomRigProblem(rng, 3, {0, 1, 2});
  std::vector<CameraPose> poses;
  std::array<RigRay, 3> rays = {RayOf(p, 0), RayOf(p, 1), RayOf(p, 2)};
  // Two equal world points.
  EXPECT_EQ(GeneralizedP3P(rays, {p.points[0], p.points[0], p.points[2]}, &poses), 0);
  EXPECT_TRUE(poses.empty());
  // All three world points equal: no triangle at all.
  EXPECT_EQ(GeneralizedP3P(rays, {p.points[0], p.points[0], p.points[0]}, &poses), 0);
  // Collinear world points seen by three rays: whatever the depths, no unique motion.
  const Eigen::Vector3d a = p.points[0], b = p.points[1];
  EXPECT_EQ(GeneralizedP3P(rays, {a, b, a + 2.0 * (b - a)}, &poses), 0);
  // Non-finite input.
  rays[1].direction = Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 1);
  EXPECT_EQ(GeneralizedP3P(rays, {p.points[0], p.points[1], p.points[2]}, &poses), 0);
}

#ifdef CWLOC_WITH_OPENGV
// OpenGV's gp3p (Kneip, Furgale and Siegwart, ICRA 2013) as the reference: every solution it
// finds that puts the points on their rays in front is one of ours.
TEST(GeneralizedP3P, FindsEverySolutionOpenGVsGp3pFinds) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  int theirs_total = 0, ours_total = 0;
  for (int trial = 0; trial < 500; ++trial) {
    const RigProblem p = RandomRigProblem(rng, 3, {0, 1, 2});
    const std::array<RigRay, 3> rays = {RayOf(p, 0), RayOf(p, 1), RayOf(p, 2)};
    GeneralizedP3P(rays, {p.points[0], p.points[1], p.points[2]}, &poses);
    ours_total += static_cast<int>(poses.size());
    // OpenGV: camera offsets and rotations are the camera's pose in the rig (its centre, and
    // rig_from_cam); a solution is world_from_rig.
    opengv::bearingVectors_t bearings(p.bearings.begin(), p.bearings.end());
    opengv::points_t points(p.points.begin(), p.points.end());
    opengv::translations_t offsets;
    opengv::rotations_t rotations;
    for (const CameraPose& cam : p.cam_from_rig) {
      offsets.push_back(cam.Center());
      rotations.push_back(cam.RotationMatrix().transpose());
    }
    const opengv::absolute_pose::NoncentralAbsoluteAdapter adapter(bearings, p.camera_of, points,
                                                                   offsets, rotations);
    for (const opengv::transformation_t& world_from_rig :
         opengv::absolute_pose::gp3p(adapter, {0, 1, 2})) {
      const Eigen::Matrix3d r = world_from_rig.leftCols<3>().transpose();
      const CameraPose theirs(Eigen::Quaterniond(r).normalized(), -r * world_from_rig.col(3));
      bool valid = true;
      for (int i = 0; i < 3; ++i) valid &= RayDistance(rays[i], theirs, p.points[i]) < 1e-6;
      if (!valid) continue;
      ++theirs_total;
      double nearest = std::numeric_limits<double>::infinity();
      for (const CameraPose& ours : poses)
        nearest = std::min(nearest, test::PoseError(ours, theirs));
      // OpenGV's solutions meet their rays to ~1e-6, ours to 1e-12.
      EXPECT_LT(nearest, 1e-4) << "trial " << trial;
    }
  }
  EXPECT_GE(ours_total, theirs_total);
}
#endif

// Three points in camera 0, the fourth in camera 1; translations scaled by `scale`.
TEST(GeneralizedP3PScale, RecoversPoseAndScaleOfRandomRigs) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  std::vector<CameraPose> poses;
  std::vector<double> scales;
  int accurate = 0;
  constexpr int kTrials = 2000;
  for (int trial = 0; trial < kTrials; ++trial) {
    const double scale = test::Uniform(rng, 0.1, 10.0);
    RigProblem p = RandomRigProblem(rng, 2, {0, 0, 0, 1}, scale);
    // The solver is given the unit-scale rig.
    std::array<CameraPose, 2> unit = {p.cam_from_rig[0], p.cam_from_rig[1]};
    for (CameraPose& cam : unit) cam.translation /= scale;
    const int n = GeneralizedP3PScale({p.bearings[0], p.bearings[1], p.bearings[2], p.bearings[3]},
                                      {p.points[0], p.points[1], p.points[2], p.points[3]}, unit[0],
                                      unit[1], 1e-6, &poses, &scales);
    ASSERT_EQ(n, static_cast<int>(poses.size()));
    ASSERT_EQ(poses.size(), scales.size());
    ASSERT_LE(n, 4);
    double best = std::numeric_limits<double>::infinity();
    for (int s = 0; s < n; ++s) {
      EXPECT_GT(scales[s], 0.0);
      // The solution's rig at its scale puts all four points on their rays.
      for (int i = 0; i < 4; ++i) {
        CameraPose cam = unit[p.camera_of[i]];
        cam.translation *= scales[s];
        const Eigen::Vector3d in_cam = cam.Apply(poses[s].Apply(p.points[i]));
        EXPECT_GT(in_cam.z(), 0.0);
        EXPECT_LT((in_cam.normalized() - p.bearings[i]).norm(), 1e-7);
      }
      best = std::min(
          best, test::PoseError(poses[s], p.rig_from_world) + std::abs(scales[s] / scale - 1.0));
    }
    accurate += best < 1e-8;
  }
  EXPECT_GE(accurate, kTrials - kTrials / 200) << accurate;
}

TEST(GeneralizedP3PScale, ABaselineAlongTheFourthRayGivesNoScale) {
  SplitMix64 rng = test::SplitMixFrom(test::Rng());
  RigProblem p = RandomRigProblem(rng, 2, {0, 0, 0, 1});
  std::vector<CameraPose> poses;
  std::vector<double> scales;
  // Camera 1 at camera 0's centre: the scale moves nothing.
  CameraPose same_centre = p.cam_from_rig[1];
  same_centre.translation = -(same_centre.rotation * p.cam_from_rig[0].Center());
  EXPECT_EQ(GeneralizedP3PScale({p.bearings[0], p.bearings[1], p.bearings[2], p.bearings[3]},
                                {p.points[0], p.points[1], p.points[2], p.points[3]},
                                p.cam_from_rig[0], same_centre, 1.0, &poses, &scales),
            0);
  EXPECT_TRUE(poses.empty() && scales.empty());
  // Camera 1 displaced along the fourth point's ray.
  CameraPose along = p.cam_from_rig[1];
  const Eigen::Vector3d ray_in_rig = along.rotation.conjugate() * p.bearings[3];
  along.translation = -(along.rotation * (p.cam_from_rig[0].Center() + 0.7 * ray_in_rig));
  EXPECT_EQ(GeneralizedP3PScale({p.bearings[0], p.bearings[1], p.bearings[2], p.bearings[3]},
                                {p.points[0], p.points[1], p.points[2], p.points[3]},
                                p.cam_from_rig[0], along, 1.0, &poses, &scales),
            0);
}

}  // namespace
}  // namespace cwloc
