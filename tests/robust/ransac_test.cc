#include "robust/ransac.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <random>
#include <set>
#include <vector>

#include "tests/test_util.h"

namespace cwloc {
namespace {

double Uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// y = a x + b from two points; the residual is the vertical distance.
class LineEstimator {
 public:
  struct Model {
    double a = 0.0, b = 0.0;
  };
  static constexpr size_t kSampleSize = 2;

  LineEstimator(const std::vector<Eigen::Vector2d>& points, double threshold)
      : points_(points), threshold_sq_(threshold * threshold) {}

  size_t NumData() const { return points_.size(); }
  void GenerateModels(std::span<const uint32_t> sample, std::vector<Model>* models) const {
    ++samples_;
    const Eigen::Vector2d& p = points_[sample[0]];
    const Eigen::Vector2d& q = points_[sample[1]];
    EXPECT_NE(sample[0], sample[1]);
    if (p.x() == q.x()) return;
    const double a = (q.y() - p.y()) / (q.x() - p.x());
    models->push_back({a, p.y() - a * p.x()});
  }
  double Score(const Model& m, uint32_t* num_inliers, double /*bound*/) const {
    double score = 0.0;
    *num_inliers = 0;
    for (const auto& p : points_) {
      const double r = p.y() - m.a * p.x() - m.b;
      if (r * r < threshold_sq_) {
        score += r * r;
        ++*num_inliers;
      } else {
        score += threshold_sq_;
      }
    }
    return score;
  }
  // Least squares on the inliers.
  void Refine(Model* m) const {
    Eigen::Matrix2d ata = Eigen::Matrix2d::Zero();
    Eigen::Vector2d atb = Eigen::Vector2d::Zero();
    for (const auto& p : points_) {
      const double r = p.y() - m->a * p.x() - m->b;
      if (r * r >= threshold_sq_) continue;
      const Eigen::Vector2d row(p.x(), 1.0);
      ata += row * row.transpose();
      atb += row * p.y();
    }
    if (std::abs(ata.determinant()) < 1e-12) return;
    const Eigen::Vector2d ab = ata.inverse() * atb;
    m->a = ab(0);
    m->b = ab(1);
  }

  mutable int samples_ = 0;

 private:
  const std::vector<Eigen::Vector2d>& points_;
  double threshold_sq_;
};

static_assert(RansacEstimator<LineEstimator>);

std::vector<Eigen::Vector2d> LineData(std::mt19937_64& rng, int num_inliers, int num_outliers,
                                      double a, double b, double noise) {
  std::vector<Eigen::Vector2d> points;
  std::normal_distribution<double> n(0.0, noise);
  for (int i = 0; i < num_inliers; ++i) {
    const double x = Uniform(rng, -10, 10);
    points.emplace_back(x, a * x + b + n(rng));
  }
  for (int i = 0; i < num_outliers; ++i) {
    points.emplace_back(Uniform(rng, -10, 10), Uniform(rng, -100, 100));
  }
  std::shuffle(points.begin(), points.end(), rng);
  return points;
}

TEST(Ransac, FitsALineWithManyOutliers) {
  auto& rng = test::Rng();
  const auto points = LineData(rng, 60, 240, 2.0, -3.0, 0.05);
  const LineEstimator estimator(points, 0.3);
  LineEstimator::Model model;
  const RansacStats stats = Ransac(estimator, RansacOptions{}, RansacRun{}, &model);
  EXPECT_NEAR(model.a, 2.0, 0.02);
  EXPECT_NEAR(model.b, -3.0, 0.05);
  EXPECT_GE(stats.num_inliers, 58u);  // a few random outliers may fall on the line
  EXPECT_LE(stats.num_inliers, 66u);
  EXPECT_DOUBLE_EQ(stats.inlier_ratio, stats.num_inliers / 300.0);
  EXPECT_GE(stats.refinements, 1u);
  EXPECT_GE(stats.iterations, RansacOptions{}.min_iterations);
  EXPECT_EQ(static_cast<int>(stats.iterations), estimator.samples_);
  // Adaptive stop: w = 0.2, s = 2, 0.9999 -> 226 samples, well below the maximum.
  EXPECT_LE(stats.iterations, 400u);
}

TEST(Ransac, IsDeterministicForASeed) {
  auto& rng = test::Rng();
  const auto points = LineData(rng, 50, 150, -1.0, 4.0, 0.1);
  const LineEstimator estimator(points, 0.5);
  const RansacOptions options;
  RansacRun run;
  run.seed = 42;
  LineEstimator::Model m1, m2, m3;
  const RansacStats s1 = Ransac(estimator, options, run, &m1);
  const RansacStats s2 = Ransac(estimator, options, run, &m2);
  EXPECT_EQ(m1.a, m2.a);
  EXPECT_EQ(m1.b, m2.b);
  EXPECT_EQ(s1.iterations, s2.iterations);
  EXPECT_EQ(s1.refinements, s2.refinements);
  EXPECT_EQ(s1.score, s2.score);
  run.seed = 43;
  Ransac(estimator, options, run, &m3);
  EXPECT_NEAR(m3.a, -1.0, 0.05);
}

TEST(Ransac, RequiredIterations) {
  EXPECT_EQ(RansacRequiredIterations(0.5, 3, 0.99, 10000), 35u);
  EXPECT_EQ(RansacRequiredIterations(1.0, 3, 0.99, 10000), 0u);
  EXPECT_EQ(RansacRequiredIterations(0.0, 3, 0.99, 10000), 10000u);
  EXPECT_EQ(RansacRequiredIterations(1e-6, 4, 0.9999, 5000), 5000u);
  // More outliers, more samples; a larger sample, more samples.
  EXPECT_LT(RansacRequiredIterations(0.3, 3, 0.9999, 1u << 30),
            RansacRequiredIterations(0.2, 3, 0.9999, 1u << 30));
  EXPECT_LT(RansacRequiredIterations(0.3, 3, 0.9999, 1u << 30),
            RansacRequiredIterations(0.3, 4, 0.9999, 1u << 30));
}

TEST(Ransac, RespectsIterationBoundsAndTinyInput) {
  auto& rng = test::Rng();
  const auto points = LineData(rng, 5, 295, 1.0, 0.0, 0.01);
  const LineEstimator estimator(points, 0.05);
  RansacOptions options;
  options.min_iterations = 10;
  options.max_iterations = 50;
  LineEstimator::Model model;
  EXPECT_LE(Ransac(estimator, options, RansacRun{}, &model).iterations, 50u);

  const std::vector<Eigen::Vector2d> one = {Eigen::Vector2d(1, 1)};
  const LineEstimator tiny(one, 0.1);
  const RansacStats stats = Ransac(tiny, RansacOptions{}, RansacRun{}, &model);
  EXPECT_EQ(stats.iterations, 0u);
  EXPECT_EQ(stats.num_inliers, 0u);
}

}  // namespace
}  // namespace cwloc
