// --prior-position, --prior-gravity and --priors files: what they parse to and every bad input.
#include "app/query_priors.h"

#include <gtest/gtest.h>

#include <fstream>

#include "base/error.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(PositionPriorOption, TakesAnOptionalHeight) {
  const PositionPrior horizontal = ParsePositionPrior("48.8566 2.3522 50", "--prior-position");
  EXPECT_DOUBLE_EQ(horizontal.latitude_deg, 48.8566);
  EXPECT_DOUBLE_EQ(horizontal.longitude_deg, 2.3522);
  EXPECT_FALSE(horizontal.height_m.has_value());
  EXPECT_DOUBLE_EQ(horizontal.radius_m, 50);
  const PositionPrior full = ParsePositionPrior("-33.9 151.2 12.5 30", "--prior-position");
  ASSERT_TRUE(full.height_m.has_value());
  EXPECT_DOUBLE_EQ(*full.height_m, 12.5);
  EXPECT_DOUBLE_EQ(full.radius_m, 30);
  EXPECT_EQ(full.source, PriorSource::kOption);
}

TEST(PositionPriorOption, BadValuesNameTheProblem) {
  EXPECT_EQ(ErrorOf([] { ParsePositionPrior("48.8 2.3", "--prior-position"); }),
            "--prior-position '48.8 2.3': expected 'LAT LON [HEIGHT] RADIUS_M'");
  EXPECT_EQ(ErrorOf([] { ParsePositionPrior("48.8 east 50", "--prior-position"); }),
            "--prior-position '48.8 east 50': expected 'LAT LON [HEIGHT] RADIUS_M'");
  EXPECT_EQ(ErrorOf([] { ParsePositionPrior("91 2.3 50", "--prior-position"); }),
            "--prior-position: latitude 91.000000 is outside [-90, 90]");
  EXPECT_EQ(ErrorOf([] { ParsePositionPrior("48 400 50", "--prior-position"); }),
            "--prior-position: longitude 400.000000 is outside [-180, 360)");
  EXPECT_EQ(ErrorOf([] { ParsePositionPrior("48 2 0", "--prior-position"); }),
            "--prior-position: the radius must be a positive number of metres");
  EXPECT_EQ(ErrorOf([] { ParsePositionPrior("48 2 nan", "--prior-position"); }),
            "--prior-position '48 2 nan': expected 'LAT LON [HEIGHT] RADIUS_M'");
}

TEST(GravityPriorOption, ParsesAnyNonZeroVector) {
  const auto g = ParseGravityPrior("0.01 9.8 -0.2", "--prior-gravity");
  EXPECT_EQ(g, (std::array<double, 3>{0.01, 9.8, -0.2}));
  EXPECT_EQ(ErrorOf([] { ParseGravityPrior("0 0 0", "--prior-gravity"); }),
            "--prior-gravity: expected a non-zero vector 'GX GY GZ' (camera frame)");
  EXPECT_EQ(ErrorOf([] { ParseGravityPrior("0 1", "--prior-gravity"); }),
            "--prior-gravity: expected a non-zero vector 'GX GY GZ' (camera frame)");
  EXPECT_EQ(ErrorOf([] { ParseGravityPrior("0 1 x", "--prior-gravity"); }),
            "--prior-gravity '0 1 x': expected 'GX GY GZ'");
}

class PriorsFileTest : public testing::Test {
 protected:
  std::filesystem::path Write(const std::string& text) {
    const auto path = dir_ / "priors.txt";
    std::ofstream(path) << text;
    return path;
  }
  test::TempDir dir_;
};

TEST_F(PriorsFileTest, ReadsPositionsAndGravityPerQuery) {
  const auto path = Write(
      "# priors\n"
      "q1.jpg position 48.1 11.5 520.25 50\n"
      "q1.jpg gravity 0 1 0\n"
      "\n"
      "q2.jpg position 48.2 11.6 - 25\n");
  const auto priors = ReadPriorsFile(path);
  ASSERT_EQ(priors.size(), 2u);
  const QueryPriors& q1 = priors.at("q1.jpg");
  ASSERT_TRUE(q1.position && q1.gravity);
  EXPECT_DOUBLE_EQ(q1.position->latitude_deg, 48.1);
  EXPECT_DOUBLE_EQ(*q1.position->height_m, 520.25);
  EXPECT_DOUBLE_EQ(q1.position->radius_m, 50);
  EXPECT_EQ(q1.position->source, PriorSource::kFile);
  EXPECT_EQ(*q1.gravity, (std::array<double, 3>{0, 1, 0}));
  const QueryPriors& q2 = priors.at("q2.jpg");
  EXPECT_FALSE(q2.position->height_m.has_value());
  EXPECT_FALSE(q2.gravity.has_value());
}

TEST_F(PriorsFileTest, BadLinesNameTheFileAndLine) {
  auto error = [&](const std::string& text) {
    const auto path = Write(text);
    const std::string message = ErrorOf([&] { ReadPriorsFile(path); });
    return message.substr(0, path.string().size()) == path.string()
               ? message.substr(path.string().size())
               : message;
  };
  EXPECT_EQ(error("q position 48 11 - 50\nq\n"), ":2: expected 'NAME position|gravity ...'");
  EXPECT_EQ(error("q position 48 11 50\n"),
            ":1: expected 'NAME position LAT LON HEIGHT|- RADIUS_M'");
  EXPECT_EQ(error("q position 48 x 0 50\n"), ":1: a position field is not a number");
  EXPECT_EQ(error("q position 100 11 0 50\n"), ":1: latitude 100.000000 is outside [-90, 90]");
  EXPECT_EQ(error("q gravity 0 0 0\n"), ":1: expected a non-zero vector 'GX GY GZ' (camera frame)");
  EXPECT_EQ(error("q gravity 0 1 0\nq gravity 0 1 0\n"), ":2: a second gravity for 'q'");
  EXPECT_EQ(error("q heading 90\n"), ":1: unknown prior 'heading', expected position or gravity");
  EXPECT_EQ(ErrorOf([&] { ReadPriorsFile(dir_ / "missing.txt"); }),
            (dir_ / "missing.txt").string() + ": cannot open the priors file");
}

}  // namespace
}  // namespace cwloc
