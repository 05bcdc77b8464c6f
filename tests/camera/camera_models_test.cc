#include "camera/camera_models.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "tests/test_util.h"

namespace cwloc {
namespace {

// COLMAP's table (src/colmap/sensor/models.h): id, name, number of parameters.
struct Expected {
  int id;
  const char* name;
  int num_params;
};
constexpr Expected kColmapModels[] = {
    {0, "SIMPLE_PINHOLE", 3},
    {1, "PINHOLE", 4},
    {2, "SIMPLE_RADIAL", 4},
    {3, "RADIAL", 5},
    {4, "OPENCV", 8},
    {5, "OPENCV_FISHEYE", 8},
    {6, "FULL_OPENCV", 12},
    {7, "FOV", 5},
    {8, "SIMPLE_RADIAL_FISHEYE", 4},
    {9, "RADIAL_FISHEYE", 5},
    {10, "THIN_PRISM_FISHEYE", 12},
    {11, "RAD_TAN_THIN_PRISM_FISHEYE", 16},
    {12, "SIMPLE_DIVISION", 4},
    {13, "DIVISION", 5},
    {14, "SIMPLE_FISHEYE", 3},
    {15, "FISHEYE", 4},
    {16, "EUCM", 6},
    {17, "EQUIRECTANGULAR", 2},
};

TEST(CameraModelsTest, TableMatchesColmap) {
  const auto models = AllCameraModels();
  ASSERT_EQ(models.size(), std::size(kColmapModels));
  for (size_t i = 0; i < models.size(); ++i) {
    SCOPED_TRACE(kColmapModels[i].name);
    EXPECT_EQ(static_cast<int>(models[i].id), kColmapModels[i].id);
    EXPECT_EQ(models[i].name, kColmapModels[i].name);
    EXPECT_EQ(models[i].num_params, kColmapModels[i].num_params);
    EXPECT_TRUE(models[i].can_project);
    EXPECT_EQ(CameraModelName(models[i].id), kColmapModels[i].name);
    EXPECT_EQ(CameraModelNumParams(models[i].id), kColmapModels[i].num_params);
  }
}

TEST(CameraModelsTest, LookupByIdAndName) {
  for (const Expected& e : kColmapModels) {
    const auto by_id = FindCameraModel(e.id);
    ASSERT_TRUE(by_id.has_value()) << e.id;
    EXPECT_EQ(by_id->name, e.name);
    const auto by_name = FindCameraModel(std::string_view(e.name));
    ASSERT_TRUE(by_name.has_value()) << e.name;
    EXPECT_EQ(static_cast<int>(by_name->id), e.id);
  }
}

TEST(CameraModelsTest, UnknownIdAndName) {
  for (int32_t id :
       {-1, 18, 99, std::numeric_limits<int32_t>::max(), std::numeric_limits<int32_t>::min()}) {
    EXPECT_FALSE(FindCameraModel(id).has_value()) << id;
    EXPECT_EQ(CameraModelName(static_cast<CameraModelId>(id)), "");
    EXPECT_EQ(CameraModelNumParams(static_cast<CameraModelId>(id)), -1);
  }
  for (const char* name : {"", "simple_radial", "SIMPLE_RADIAL ", "PINHOLE2", "INVALID"}) {
    EXPECT_FALSE(FindCameraModel(std::string_view(name)).has_value()) << '"' << name << '"';
  }
}

TEST(CameraModelsTest, KnownProjections) {
  std::array<double, 2> px{};
  const std::vector<double> simple_pinhole = {100, 50, 40};
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kSimplePinhole, simple_pinhole, {1, 2, 4}, &px));
  EXPECT_DOUBLE_EQ(px[0], 75);
  EXPECT_DOUBLE_EQ(px[1], 90);

  // u = 0.25, v = 0.5, r^2 = 0.3125, factor 1 + 0.1 r^2 = 1.03125.
  const std::vector<double> simple_radial = {100, 50, 40, 0.1};
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kSimpleRadial, simple_radial, {1, 2, 4}, &px));
  EXPECT_DOUBLE_EQ(px[0], 75.78125);
  EXPECT_DOUBLE_EQ(px[1], 91.5625);

  // Equidistant fisheye: a ray at 45 degrees lands f * pi/4 from the principal point.
  const std::vector<double> fisheye = {200, 210, 320, 240};
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kFisheye, fisheye, {1, 0, 1}, &px));
  EXPECT_NEAR(px[0], 320 + 200 * std::numbers::pi / 4, 1e-12);
  EXPECT_NEAR(px[1], 240, 1e-12);

  // Equirectangular: straight ahead is the image centre, +x is a quarter turn to the right,
  // straight behind is the right edge.
  const std::vector<double> equirect = {2000, 1000};
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kEquirectangular, equirect, {0, 0, 5}, &px));
  EXPECT_NEAR(px[0], 1000, 1e-9);
  EXPECT_NEAR(px[1], 500, 1e-9);
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kEquirectangular, equirect, {3, 0, 0}, &px));
  EXPECT_NEAR(px[0], 1500, 1e-9);
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kEquirectangular, equirect, {0, 0, -1}, &px));
  EXPECT_NEAR(px[0], 2000, 1e-9);
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kEquirectangular, equirect, {0, -1, 0}, &px));
  EXPECT_NEAR(px[1], 0, 1e-9);  // -y is up
}

TEST(CameraModelsTest, ZeroDistortionIsPinhole) {
  const std::array<double, 3> point = {0.3, -0.2, 2.0};
  std::array<double, 2> expected{};
  ASSERT_TRUE(ProjectToPixel(CameraModelId::kPinhole, std::vector<double>{500, 480, 320, 240},
                             point, &expected));
  for (const CameraModelInfo& info : AllCameraModels()) {
    std::vector<double> params(info.num_params, 0.0);
    const std::string name(info.name);
    if (name.find("FISHEYE") != std::string::npos || name == "EQUIRECTANGULAR") continue;
    if (name.rfind("SIMPLE_", 0) == 0 || name == "RADIAL") {
      continue;  // one focal length; covered by the pinhole comparison above
    }
    params[0] = 500, params[1] = 480, params[2] = 320, params[3] = 240;
    if (name == "EUCM") params[5] = 1.0;  // alpha = 0: plain pinhole for any beta
    std::array<double, 2> px{};
    ASSERT_TRUE(ProjectToPixel(info.id, params, point, &px)) << name;
    EXPECT_NEAR(px[0], expected[0], 1e-9) << name;
    EXPECT_NEAR(px[1], expected[1], 1e-9) << name;
  }
}

TEST(CameraModelsTest, RejectsBadInput) {
  std::array<double, 2> px{};
  std::array<double, 2> xy{};
  const std::vector<double> params = {100, 50, 40, 0.1};
  EXPECT_FALSE(ProjectToPixel(CameraModelId::kSimpleRadial, params, {0, 0, -1}, &px));
  EXPECT_FALSE(ProjectToPixel(CameraModelId::kSimpleRadial, params, {1, 1, 0}, &px));
  EXPECT_FALSE(ProjectToPixel(CameraModelId::kSimpleRadial, params, {NAN, 0, 1}, &px));
  // Wrong parameter count, unknown model.
  EXPECT_FALSE(ProjectToPixel(CameraModelId::kRadial, params, {0, 0, 1}, &px));
  EXPECT_FALSE(PixelToNormalized(CameraModelId::kRadial, params, {10, 10}, &xy));
  EXPECT_FALSE(ProjectToPixel(static_cast<CameraModelId>(42), params, {0, 0, 1}, &px));
  EXPECT_FALSE(PixelToNormalized(static_cast<CameraModelId>(42), params, {0, 0}, &xy));
  // A pixel beyond the largest radius that a barrel distortion reaches has no preimage:
  // with k = -0.5 the distorted radius peaks at 0.544; r_d = 1 must fail, not return garbage.
  const std::vector<double> strong_barrel = {100, 0, 0, -0.5};
  EXPECT_FALSE(PixelToNormalized(CameraModelId::kSimpleRadial, strong_barrel, {100, 0}, &xy));
  EXPECT_TRUE(PixelToNormalized(CameraModelId::kSimpleRadial, strong_barrel, {40, 0}, &xy));
  // Fisheye pixels at or beyond 90 degrees have no normalized coordinates.
  const std::vector<double> fisheye = {100, 0, 0};
  EXPECT_FALSE(PixelToNormalized(CameraModelId::kSimpleFisheye, fisheye, {160, 0}, &xy));
  // Equirectangular pixels behind the camera neither.
  const std::vector<double> equirect = {2000, 1000};
  EXPECT_FALSE(PixelToNormalized(CameraModelId::kEquirectangular, equirect, {10, 500}, &xy));
}

TEST(CameraModelsTest, MeanFocalLength) {
  EXPECT_DOUBLE_EQ(
      MeanFocalLength(CameraModelId::kSimpleRadial, std::vector<double>{1375.5, 768, 512, -0.001}),
      1375.5);
  EXPECT_DOUBLE_EQ(
      MeanFocalLength(CameraModelId::kOpenCV, std::vector<double>{500, 520, 1, 2, 0, 0, 0, 0}),
      510);
  EXPECT_NEAR(MeanFocalLength(CameraModelId::kEquirectangular, std::vector<double>{2000, 1000}),
              2000 / (2 * std::numbers::pi), 1e-12);
  EXPECT_TRUE(std::isnan(MeanFocalLength(CameraModelId::kOpenCV, std::vector<double>{500})));
}

TEST(CameraModelsTest, FovSmallOmegaIsContinuous) {
  // The small-omega series and the closed form must agree where they meet.
  std::array<double, 2> a{}, b{};
  const std::array<double, 3> point = {0.7, -0.4, 1.0};
  ASSERT_TRUE(
      ProjectToPixel(CameraModelId::kFOV, std::vector<double>{500, 500, 0, 0, 0.99e-6}, point, &a));
  ASSERT_TRUE(
      ProjectToPixel(CameraModelId::kFOV, std::vector<double>{500, 500, 0, 0, 1.01e-6}, point, &b));
  EXPECT_NEAR(a[0], b[0], 1e-8);
  EXPECT_NEAR(a[1], b[1], 1e-8);
  EXPECT_NEAR(a[0], 350, 1e-6);  // omega -> 0 is the pinhole
}

// Realistic parameters for a 1000x800 image, per model.
std::vector<double> TypicalParams(CameraModelId model) {
  switch (model) {
    case CameraModelId::kSimplePinhole:
      return {500, 500, 400};
    case CameraModelId::kPinhole:
      return {520, 480, 510, 390};
    case CameraModelId::kSimpleRadial:
      return {500, 500, 400, -0.08};
    case CameraModelId::kRadial:
      return {500, 500, 400, -0.1, 0.02};
    case CameraModelId::kOpenCV:
      return {520, 480, 510, 390, -0.1, 0.02, 0.001, -0.002};
    case CameraModelId::kOpenCVFisheye:
      return {300, 310, 500, 400, 0.05, -0.01, 0.002, -0.0005};
    case CameraModelId::kFullOpenCV:
      return {520, 480, 510, 390, -0.1, 0.02, 0.001, -0.002, 0.001, 0.01, 0.001, 0.0005};
    case CameraModelId::kFOV:
      return {400, 410, 500, 400, 0.9};
    case CameraModelId::kSimpleRadialFisheye:
      return {300, 500, 400, 0.03};
    case CameraModelId::kRadialFisheye:
      return {300, 500, 400, 0.03, -0.005};
    case CameraModelId::kThinPrismFisheye:
      return {300, 310, 500, 400, 0.03, -0.005, 0.001, -0.001, 0.0005, -0.0001, 0.001, -0.0008};
    case CameraModelId::kRadTanThinPrismFisheye:
      return {300,     310,      500,   400,     0.03,   -0.005,  0.001,  -0.0002,
              0.00005, -0.00001, 0.001, -0.0008, 0.0005, -0.0002, 0.0003, -0.0001};
    case CameraModelId::kSimpleDivision:
      return {500, 500, 400, -0.1};
    case CameraModelId::kDivision:
      return {520, 480, 510, 390, -0.1};
    case CameraModelId::kSimpleFisheye:
      return {300, 500, 400};
    case CameraModelId::kFisheye:
      return {300, 310, 500, 400};
    case CameraModelId::kEUCM:
      return {300, 310, 500, 400, 0.6, 1.1};
    case CameraModelId::kEquirectangular:
      return {2000, 1000};
  }
  return {};
}

class CameraModelRoundTripTest : public ::testing::TestWithParam<CameraModelInfo> {};

TEST_P(CameraModelRoundTripTest, PointToPixelToPoint) {
  const CameraModelInfo info = GetParam();
  const std::vector<double> params = TypicalParams(info.id);
  ASSERT_EQ(params.size(), static_cast<size_t>(info.num_params));
  std::uniform_real_distribution<double> coord(-0.8, 0.8);
  std::uniform_real_distribution<double> depth(0.5, 20);
  for (int i = 0; i < 2000; ++i) {
    const double z = depth(test::Rng());
    const std::array<double, 3> point = {coord(test::Rng()) * z, coord(test::Rng()) * z, z};
    std::array<double, 2> px{};
    ASSERT_TRUE(ProjectToPixel(info.id, params, point, &px)) << info.name << " point " << i;
    std::array<double, 2> xy{};
    ASSERT_TRUE(PixelToNormalized(info.id, params, px, &xy))
        << info.name << " pixel " << px[0] << " " << px[1];
    EXPECT_NEAR(xy[0], point[0] / z, 1e-9) << info.name;
    EXPECT_NEAR(xy[1], point[1] / z, 1e-9) << info.name;
  }
}

TEST_P(CameraModelRoundTripTest, PixelToPointToPixel) {
  const CameraModelInfo info = GetParam();
  const std::vector<double> params = TypicalParams(info.id);
  // Central part of the image, where every model has a valid inverse (the fisheye corners
  // are beyond 90 degrees, the equirectangular sides behind the camera).
  const bool panorama = info.id == CameraModelId::kEquirectangular;
  std::uniform_real_distribution<double> x_dist(panorama ? 600 : 200, panorama ? 1400 : 800);
  std::uniform_real_distribution<double> y_dist(panorama ? 300 : 150, panorama ? 700 : 650);
  for (int i = 0; i < 2000; ++i) {
    const std::array<double, 2> px = {x_dist(test::Rng()), y_dist(test::Rng())};
    std::array<double, 2> xy{};
    ASSERT_TRUE(PixelToNormalized(info.id, params, px, &xy))
        << info.name << " pixel " << px[0] << " " << px[1];
    std::array<double, 2> back{};
    ASSERT_TRUE(ProjectToPixel(info.id, params, {xy[0], xy[1], 1.0}, &back)) << info.name;
    EXPECT_NEAR(back[0], px[0], 1e-6) << info.name;
    EXPECT_NEAR(back[1], px[1], 1e-6) << info.name;
  }
}

INSTANTIATE_TEST_SUITE_P(AllModels, CameraModelRoundTripTest,
                         ::testing::ValuesIn(AllCameraModels().begin(), AllCameraModels().end()),
                         [](const ::testing::TestParamInfo<CameraModelInfo>& param_info) {
                           return std::string(param_info.param.name);
                         });

}  // namespace
}  // namespace cwloc
