#include "solvers/three_quadrics.h"

#include <gtest/gtest.h>

#include "tests/support/synthetic_pose.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

Eigen::Vector3d Evaluate(const Eigen::Matrix<double, 3, 10>& c, const Eigen::Vector3d& p) {
  const double x = p(0), y = p(1), z = p(2);
  Eigen::Matrix<double, 10, 1> m;
  m << x * x, x * y, x * z, y * y, y * z, z * z, x, y, z, 1.0;
  return c * m;
}

// Random quadrics through a known point: random coefficients, constant term adjusted.
Eigen::Matrix<double, 3, 10> QuadricsThrough(const Eigen::Vector3d& p, std::mt19937_64& rng) {
  Eigen::Matrix<double, 3, 10> c;
  for (int k = 0; k < 3; ++k) {
    for (int j = 0; j < 10; ++j) c(k, j) = test::Uniform(rng, -1.0, 1.0);
  }
  c.col(9) -= Evaluate(c, p);
  return c;
}

TEST(ThreeQuadrics, FindsAKnownSolution) {
  auto& rng = test::Rng();
  Eigen::Matrix<double, 3, 8> solutions;
  int found = 0;
  const int kTrials = 2000;
  for (int trial = 0; trial < kTrials; ++trial) {
    const Eigen::Vector3d p(test::Uniform(rng, -2, 2), test::Uniform(rng, -2, 2),
                            test::Uniform(rng, -2, 2));
    const Eigen::Matrix<double, 3, 10> c = QuadricsThrough(p, rng);
    const int n = SolveThreeQuadrics(c, &solutions);
    ASSERT_GE(n, 0);
    ASSERT_LE(n, 8);
    bool hit = false;
    for (int i = 0; i < n; ++i) {
      ASSERT_TRUE(solutions.col(i).allFinite());
      // Every returned point solves the system.
      EXPECT_LT(Evaluate(c, solutions.col(i)).norm(),
                1e-8 * (1.0 + solutions.col(i).squaredNorm()));
      hit = hit || (solutions.col(i) - p).norm() < 1e-8;
    }
    found += hit;
  }
  EXPECT_GE(found, kTrials * 995 / 1000);
}

TEST(ThreeQuadrics, SeparableSystemHasAllEightSolutions) {
  // (x^2 - 1, y^2 - 4, z^2 - 9) mixed by an invertible matrix: solutions (+-1, +-2, +-3).
  Eigen::Matrix<double, 3, 10> pure = Eigen::Matrix<double, 3, 10>::Zero();
  pure(0, 0) = 1.0;
  pure(0, 9) = -1.0;
  pure(1, 3) = 1.0;
  pure(1, 9) = -4.0;
  pure(2, 5) = 1.0;
  pure(2, 9) = -9.0;
  Eigen::Matrix3d mix;
  mix << 2, 1, 0, 1, 3, 1, 0, 1, 4;
  Eigen::Matrix<double, 3, 8> solutions;
  ASSERT_EQ(SolveThreeQuadrics(mix * pure, &solutions), 8);
  for (int i = 0; i < 8; ++i) {
    EXPECT_NEAR(std::abs(solutions(0, i)), 1.0, 1e-10);
    EXPECT_NEAR(std::abs(solutions(1, i)), 2.0, 1e-10);
    EXPECT_NEAR(std::abs(solutions(2, i)), 3.0, 1e-10);
  }
}

TEST(ThreeQuadrics, DegenerateInput) {
  Eigen::Matrix<double, 3, 8> solutions;
  EXPECT_EQ(SolveThreeQuadrics(Eigen::Matrix<double, 3, 10>::Zero(), &solutions), 0);
  Eigen::Matrix<double, 3, 10> c = Eigen::Matrix<double, 3, 10>::Ones();
  c(1, 4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(SolveThreeQuadrics(c, &solutions), 0);
}

}  // namespace
}  // namespace cwloc
