#include "geo/georeference.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <vector>

#include "base/error.h"
#include "tests/geo/geo_test_util.h"
#include "tests/test_util.h"

namespace cwloc {
namespace {

using test::Degrees;
using test::Ecef;
using test::EnuFromEcef;
using test::Radians;
using test::Uniform;

// cam_from_model for a camera whose axes (x right, y down, z forward) are given in the model.
Eigen::Quaterniond CamFromModel(const Eigen::Vector3d& x, const Eigen::Vector3d& z) {
  Eigen::Matrix3d model_from_cam;
  model_from_cam.col(0) = x.normalized();
  model_from_cam.col(2) = z.normalized();
  model_from_cam.col(1) = model_from_cam.col(2).cross(model_from_cam.col(0));
  return Eigen::Quaterniond(model_from_cam.transpose());
}

// The camera axes in ENU for a heading, pitch and roll, written out from the convention:
// ned_from_cam = Rz(heading) Ry(pitch) Rx(roll) with the camera's z, x, y as forward, right, down.
Eigen::Matrix3d EnuFromCam(double heading_deg, double pitch_deg, double roll_deg) {
  const Eigen::Matrix3d ned_from_body =
      (Eigen::AngleAxisd(Radians(heading_deg), Eigen::Vector3d::UnitZ()) *
       Eigen::AngleAxisd(Radians(pitch_deg), Eigen::Vector3d::UnitY()) *
       Eigen::AngleAxisd(Radians(roll_deg), Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  Eigen::Matrix3d enu_from_ned;
  enu_from_ned << 0, 1, 0, 1, 0, 0, 0, 0, -1;
  Eigen::Matrix3d body_from_cam;  // cam x = body right (y), cam y = body down (z), cam z = fwd
  body_from_cam << 0, 0, 1, 1, 0, 0, 0, 1, 0;
  return enu_from_ned * ned_from_body * body_from_cam;
}

// Difference of two angles in degrees, modulo 360.
double AngleDifference(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 360.0);
  return std::min(d, 360 - d);
}

void ExpectAttitude(const CameraAttitude& a, double heading, double pitch, double roll,
                    double tolerance_deg = 1e-9) {
  EXPECT_LE(AngleDifference(a.heading_deg, heading), tolerance_deg) << a.heading_deg;
  EXPECT_NEAR(a.pitch_deg, pitch, tolerance_deg);
  EXPECT_LE(AngleDifference(a.roll_deg, roll), tolerance_deg) << a.roll_deg;
  EXPECT_GE(a.heading_deg, 0);
  EXPECT_LT(a.heading_deg, 360);
  EXPECT_GE(a.pitch_deg, -90);
  EXPECT_LE(a.pitch_deg, 90);
  EXPECT_GT(a.roll_deg, -180);
  EXPECT_LE(a.roll_deg, 180);
}

Georeference RandomGeoreference(const Geodetic& origin) {
  Georeference g;
  g.origin = origin;
  g.scale = std::pow(10.0, Uniform(-2, 2));
  g.rotation = test::RandomRotation();
  g.translation = Eigen::Vector3d{Uniform(-1000, 1000), Uniform(-1000, 1000), Uniform(-100, 100)};
  return g;
}

// Model -> ENU -> lat/lon/height -> ENU -> model within 1 mm, and the geodetic position agrees
// with WGS84 written out (ECEF of the origin plus the ENU offset) within 1 mm.
TEST(GeoFrameTest, RoundTripIsWithinAMillimetreAnywhereOnTheGlobe) {
  std::vector<Geodetic> origins;
  for (double lat : {90.0, -90.0, 89.9999, -89.9999, 0.0, 45.0, -33.3}) {
    for (double lon : {180.0, -180.0, 179.9999, -179.9999, 0.0, 13.4, 359.9}) {
      origins.push_back({lat, lon, Uniform(-400, 9000)});
    }
  }
  for (int i = 0; i < 200; ++i) {
    origins.push_back(
        {Degrees(std::asin(Uniform(-1, 1))), Uniform(-180, 360), Uniform(-400, 9000)});
  }
  double max_round_trip_m = 0, max_geodetic_m = 0;
  int points = 0;
  for (const Geodetic& origin : origins) {
    SCOPED_TRACE(testing::Message() << "origin " << origin.latitude_deg << ", "
                                    << origin.longitude_deg << ", " << origin.height_m);
    const Georeference georeference = RandomGeoreference(origin);
    const GeoFrame frame(georeference);
    const Eigen::Matrix3d enu_from_ecef = EnuFromEcef(origin.latitude_deg, origin.longitude_deg);
    const Eigen::Vector3d origin_ecef = Ecef(origin);
    std::vector<Eigen::Vector3d> enus;
    // 5 km along each axis (across the antimeridian, beyond a pole), then random points.
    for (const Eigen::Vector3d& direction : {Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(-1, 0, 0),
                                             Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(0, -1, 0)}) {
      enus.push_back(5000 * direction +
                     Eigen::Vector3d(0, 0, Uniform(-400, 9000) - origin.height_m));
    }
    for (int k = 0; k < 20; ++k) {
      const double r = 5000 * std::sqrt(Uniform(0, 1)), azimuth = Uniform(0, 2 * std::numbers::pi);
      enus.emplace_back(r * std::sin(azimuth), r * std::cos(azimuth),
                        Uniform(-400, 9000) - origin.height_m);
    }
    for (const Eigen::Vector3d& enu : enus) {
      const Eigen::Vector3d model = georeference.EnuToModel(enu);
      const Geodetic geodetic = frame.ModelToGeodetic(model);
      ASSERT_GE(geodetic.latitude_deg, -90);
      ASSERT_LE(geodetic.latitude_deg, 90);
      ASSERT_GE(geodetic.longitude_deg, -180);
      ASSERT_LE(geodetic.longitude_deg, 180);
      const Eigen::Vector3d back = frame.GeodeticToModel(geodetic);
      const double round_trip_m = georeference.scale * (back - model).norm();
      const double geodetic_m =
          (Ecef(geodetic) - (origin_ecef + enu_from_ecef.transpose() * enu)).norm();
      EXPECT_LT(round_trip_m, 1e-3);
      EXPECT_LT(geodetic_m, 1e-3);
      max_round_trip_m = std::max(max_round_trip_m, round_trip_m);
      max_geodetic_m = std::max(max_geodetic_m, geodetic_m);
      ++points;
    }
  }
  std::cout << points << " points: round trip max " << max_round_trip_m * 1e3
            << " mm, against WGS84 written out max " << max_geodetic_m * 1e3 << " mm\n";
  RecordProperty("round_trip_max_mm", std::to_string(max_round_trip_m * 1e3));
}

TEST(GeoFrameTest, EnuToGeodeticNearTheAntimeridianAndThePole) {
  // 1 km east of 179.9999 E is in the western hemisphere.
  const GeoFrame east(GeoreferenceFromEnuModel({10, 179.9999, 0}));
  const Geodetic across = east.EnuToGeodetic({1000, 0, 0});
  EXPECT_LT(across.longitude_deg, -179.99);
  EXPECT_GT(across.longitude_deg, -180);
  // 1 km north of 89.9999 N on meridian 0 is beyond the pole, on meridian 180.
  const GeoFrame pole(GeoreferenceFromEnuModel({89.9999, 0, 0}));
  const Geodetic beyond = pole.EnuToGeodetic({0, 1000, 0});
  EXPECT_NEAR(std::abs(beyond.longitude_deg), 180, 1e-9);
  EXPECT_LT(beyond.latitude_deg, 89.992);
  EXPECT_GT(beyond.latitude_deg, 89.99);
}

TEST(GeoFrameTest, ModelDirectionsRotateWithoutScale) {
  const Georeference g = RandomGeoreference({48, 11, 500});
  const Eigen::Vector3d d = test::RandomUnitVector();
  EXPECT_LT((g.EnuDirectionToModel(g.ModelDirectionToEnu(d)) - d).norm(), 1e-14);
  EXPECT_NEAR(g.ModelDirectionToEnu(d).norm(), 1, 1e-14);
  const Eigen::Vector3d a(1, 2, 3), b(-4, 5, 0.5);
  EXPECT_LT((g.ModelToEnu(a) - g.ModelToEnu(b) - g.scale * g.ModelDirectionToEnu(a - b)).norm(),
            1e-9);
}

// Cameras at the ENU origin of an ENU-model georeference: the model frame is the local ENU.
TEST(GeoFrameTest, KnownAttitudes) {
  const GeoFrame frame(GeoreferenceFromEnuModel({48.1, 11.5, 520}));
  const Eigen::Vector3d at(0, 0, 0);
  const Eigen::Vector3d east(1, 0, 0), north(0, 1, 0), up(0, 0, 1);
  {
    SCOPED_TRACE("level, looking north");
    ExpectAttitude(frame.Attitude(CamFromModel(east, north), at), 0, 0, 0);
  }
  {
    SCOPED_TRACE("level, looking east");
    ExpectAttitude(frame.Attitude(CamFromModel(-north, east), at), 90, 0, 0);
  }
  {
    SCOPED_TRACE("level, looking south, then west");
    ExpectAttitude(frame.Attitude(CamFromModel(-east, -north), at), 180, 0, 0);
    ExpectAttitude(frame.Attitude(CamFromModel(north, -east), at), 270, 0, 0);
  }
  {
    SCOPED_TRACE("30 degrees up, looking north");
    const double c = std::cos(Radians(30)), s = std::sin(Radians(30));
    ExpectAttitude(frame.Attitude(CamFromModel(east, c * north + s * up), at), 0, 30, 0);
    ExpectAttitude(frame.Attitude(CamFromModel(east, c * north - s * up), at), 0, -30, 0);
  }
  {
    SCOPED_TRACE("looking north, the image's x axis 20 degrees below the horizon: roll +20");
    const double c = std::cos(Radians(20)), s = std::sin(Radians(20));
    const Eigen::Quaterniond q = CamFromModel(c * east - s * up, north);
    ExpectAttitude(frame.Attitude(q, at), 0, 0, 20);
    // Image up (-y) leans to the right, towards the east.
    const Eigen::Vector3d image_up = -(q.conjugate() * Eigen::Vector3d::UnitY());
    EXPECT_GT(image_up.dot(east), 0);
    ExpectAttitude(frame.Attitude(CamFromModel(c * east + s * up, north), at), 0, 0, -20);
  }
  {
    SCOPED_TRACE("upside down: roll 180, never -180");
    ExpectAttitude(frame.Attitude(CamFromModel(-east, north), at), 0, 0, 180);
    EXPECT_EQ(frame.Attitude(CamFromModel(-east, north), at).roll_deg, 180);
  }
  {
    SCOPED_TRACE("straight down and straight up: roll 0, heading from the image x axis");
    // Pitching a north-looking level camera down by 90 degrees leaves x east, image up north.
    const CameraAttitude down = frame.Attitude(CamFromModel(east, -up), at);
    ExpectAttitude(down, 0, -90, 0);
    EXPECT_EQ(down.roll_deg, 0);
    ExpectAttitude(frame.Attitude(CamFromModel(north, -up), at), 270, -90, 0);
    ExpectAttitude(frame.Attitude(CamFromModel(-north, up), at), 90, 90, 0);
    const CameraAttitude up_south = frame.Attitude(CamFromModel(-east, up), at);
    ExpectAttitude(up_south, 180, 90, 0);
  }
}

// The convention written out (EnuFromCam) for random angles, away from the gimbal case.
TEST(GeoFrameTest, RandomAttitudesFollowTheConvention) {
  const GeoFrame frame(GeoreferenceFromEnuModel({-33.9, 151.2, 40}));
  for (int i = 0; i < 1000; ++i) {
    const double heading = Uniform(0, 360), pitch = Uniform(-89.99, 89.99),
                 roll = Uniform(-180, 180);
    const Eigen::Matrix3d enu_from_cam = EnuFromCam(heading, pitch, roll);
    const Eigen::Quaterniond q(Eigen::Matrix3d(enu_from_cam.transpose()));
    ExpectAttitude(frame.Attitude(q, Eigen::Vector3d(0, 0, 0)), heading, pitch, roll, 1e-8);
  }
  // Within a hair of the vertical, still not the gimbal case: heading and roll are kept.
  ExpectAttitude(
      frame.Attitude(Eigen::Quaterniond(Eigen::Matrix3d(EnuFromCam(37, 89.9999, 25).transpose())),
                     Eigen::Vector3d(0, 0, 0)),
      37, 89.9999, 25, 1e-6);
  // In the gimbal case (|pitch| > 90 - 5.7e-8 degrees) heading + roll become the heading.
  const CameraAttitude gimbal =
      frame.Attitude(Eigen::Quaterniond(Eigen::Matrix3d(EnuFromCam(37, 90, 25).transpose())),
                     Eigen::Vector3d(0, 0, 0));
  ExpectAttitude(gimbal, 37 - 25, 90, 0, 1e-9);
  const CameraAttitude gimbal_down =
      frame.Attitude(Eigen::Quaterniond(Eigen::Matrix3d(EnuFromCam(37, -90, 25).transpose())),
                     Eigen::Vector3d(0, 0, 0));
  ExpectAttitude(gimbal_down, 37 + 25, -90, 0, 1e-9);
}

// The attitude is taken in the local ENU frame at the camera, not at the origin: cameras in an
// ECEF model, built from WGS84 written out at their own positions. (Exactly at a pole north is
// the meridian of the longitude the conversion returns, which rounding decides.)
TEST(GeoFrameTest, AttitudeIsInTheLocalFrameAtTheCamera) {
  struct Case {
    Geodetic origin, camera;
  };
  const Case cases[] = {
      {{48.0, 11.0, 500}, {49.0, 11.0, 700}},            // 1 degree north of the origin
      {{-12.0, 179.99, 0}, {-12.01, -179.98, 30}},       // across the antimeridian
      {{89.995, 0.0, 100}, {89.995, 180.0, 100}},        // beyond the north pole
      {{-89.9999, 45.0, 2800}, {-89.99999, 0.0, 2800}},  // 1.1 m from the south pole
      {{0.0, -179.9999, 10}, {0.001, 179.9999, 10}},     // equator, antimeridian
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(testing::Message()
                 << "camera at " << c.camera.latitude_deg << ", " << c.camera.longitude_deg);
    const GeoFrame frame(GeoreferenceFromEcefModel(c.origin));
    const Eigen::Matrix3d ecef_from_enu =
        EnuFromEcef(c.camera.latitude_deg, c.camera.longitude_deg).transpose();
    for (const auto& [heading, pitch, roll] :
         {std::array<double, 3>{0, 0, 0}, {90, 0, 0}, {213, 31, -47}, {359, -60, 170}}) {
      const Eigen::Matrix3d ecef_from_cam = ecef_from_enu * EnuFromCam(heading, pitch, roll);
      const Eigen::Quaterniond cam_from_ecef(Eigen::Matrix3d(ecef_from_cam.transpose()));
      ExpectAttitude(frame.Attitude(cam_from_ecef, Ecef(c.camera)), heading, pitch, roll, 1e-7);
    }
  }
  // The same camera seen from an ENU model at a far origin: the same attitude.
  const Geodetic camera{49.0, 11.0, 700};
  const GeoFrame far(GeoreferenceFromEnuModel({48.0, 11.0, 500}));
  const Eigen::Matrix3d far_from_ecef = EnuFromEcef(48.0, 11.0);
  const Eigen::Matrix3d far_from_cam =
      far_from_ecef * EnuFromEcef(49.0, 11.0).transpose() * EnuFromCam(10, 5, 3);
  const Eigen::Vector3d center = far.GeodeticToEnu(camera);
  ExpectAttitude(
      far.Attitude(Eigen::Quaterniond(Eigen::Matrix3d(far_from_cam.transpose())), center), 10, 5, 3,
      1e-7);
}

TEST(GeoFrameTest, GravityAtTheOriginIsEnuDown) {
  for (int i = 0; i < 50; ++i) {
    const Georeference g = RandomGeoreference(
        {Degrees(std::asin(Uniform(-1, 1))), Uniform(-180, 180), Uniform(-400, 9000)});
    const GeoFrame frame(g);
    const Eigen::Vector3d gravity = frame.GravityInModel(g.EnuToModel(Eigen::Vector3d::Zero()));
    EXPECT_NEAR(gravity.norm(), 1, 1e-14);
    EXPECT_LT((gravity - g.EnuDirectionToModel(Eigen::Vector3d(0, 0, -1))).norm(), 1e-12);
  }
}

TEST(GeoFrameTest, GravityOneDegreeOfLatitudeAway) {
  for (const Geodetic origin : {Geodetic{48, 11, 500}, Geodetic{-0.5, 179.5, 0},
                                Geodetic{89.5, -30, 100}, Geodetic{-89.9, 120, 3000}}) {
    // Towards the equator, so the point stays on this side of the pole.
    const double lat = origin.latitude_deg > 0 ? origin.latitude_deg - 1 : origin.latitude_deg + 1;
    const Geodetic point{lat, origin.longitude_deg, 250};
    const Eigen::Vector3d expected_ecef =
        -EnuFromEcef(lat, origin.longitude_deg).row(2).transpose();
    // An ECEF model: gravity is the inward normal there in ECEF.
    const GeoFrame ecef(GeoreferenceFromEcefModel(origin));
    const Eigen::Vector3d in_ecef = ecef.GravityInModel(Ecef(point));
    EXPECT_LT((in_ecef - expected_ecef).norm(), 1e-12);
    // A random similarity: the same direction through the origin's ENU and the rotation.
    const Georeference g = RandomGeoreference(origin);
    const GeoFrame frame(g);
    const Eigen::Vector3d model_point = frame.GeodeticToModel(point);
    const Eigen::Vector3d expected = g.EnuDirectionToModel(
        EnuFromEcef(origin.latitude_deg, origin.longitude_deg) * expected_ecef);
    const Eigen::Vector3d gravity = frame.GravityInModel(model_point);
    EXPECT_LT((gravity - expected).norm(), 1e-12);
    // It differs from the origin's down by about one degree.
    const Eigen::Vector3d down_at_origin = g.EnuDirectionToModel(Eigen::Vector3d(0, 0, -1));
    EXPECT_NEAR(Degrees(std::acos(gravity.dot(down_at_origin))), 1.0, 0.01);
  }
}

TEST(GeoreferenceTest, EcefModel) {
  const Geodetic origin{52.5189, 13.4003, 60};
  const Georeference g = GeoreferenceFromEcefModel(origin);
  EXPECT_EQ(g.scale, 1);
  EXPECT_LT(g.ModelToEnu(Ecef(origin)).norm(), 1e-8);
  const GeoFrame frame(g);
  for (const Geodetic p :
       {Geodetic{52.52, 13.41, 45}, Geodetic{52.5189, 13.4003, 60}, Geodetic{-33.9, 151.2, 40}}) {
    const Geodetic back = frame.ModelToGeodetic(Ecef(p));
    EXPECT_NEAR(back.latitude_deg, p.latitude_deg, 1e-10);
    EXPECT_NEAR(back.longitude_deg, p.longitude_deg, 1e-10);
    EXPECT_NEAR(back.height_m, p.height_m, 1e-6);
    EXPECT_LT((frame.GeodeticToModel(p) - Ecef(p)).norm(), 1e-6);
  }
  EXPECT_LT(test::AngleBetween(g.rotation.toRotationMatrix(), EnuFromEcef(52.5189, 13.4003)),
            1e-14);
}

TEST(GeoreferenceTest, EnuModel) {
  const Geodetic origin{-33.9, 151.2, 40};
  const Georeference g = GeoreferenceFromEnuModel(origin);
  EXPECT_EQ(g.scale, 1);
  EXPECT_EQ(g.translation, Eigen::Vector3d::Zero());
  const GeoFrame frame(g);
  const Geodetic at_origin = frame.ModelToGeodetic(Eigen::Vector3d::Zero());
  EXPECT_NEAR(at_origin.latitude_deg, -33.9, 1e-12);
  EXPECT_NEAR(at_origin.longitude_deg, 151.2, 1e-12);
  EXPECT_NEAR(at_origin.height_m, 40, 1e-9);
  const Eigen::Vector3d up = frame.GeodeticToModel({-33.9, 151.2, 140});
  EXPECT_LT((up - Eigen::Vector3d(0, 0, 100)).norm(), 1e-9);
}

TEST(GeoreferenceTest, GeoFrameCopiesAndMoves) {
  const Georeference g = RandomGeoreference({10, 20, 30});
  GeoFrame a(g);
  GeoFrame b(std::move(a));
  EXPECT_EQ(b.georeference().scale, g.scale);
  GeoFrame c(GeoreferenceFromEnuModel({0, 0, 0}));
  c = std::move(b);
  const Geodetic p = c.ModelToGeodetic(Eigen::Vector3d(1, 2, 3));
  EXPECT_LT((c.GeodeticToModel(p) - Eigen::Vector3d(1, 2, 3)).norm() * g.scale, 1e-6);
}

void ExpectInputError(const std::function<void()>& f, const std::string& message) {
  try {
    f();
    ADD_FAILURE() << "no InputError; expected: " << message;
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()), message);
  }
}

TEST(GeoreferenceTest, ValidateGeodetic) {
  EXPECT_NO_THROW(ValidateGeodetic({90, -180, -400}, "p"));
  EXPECT_NO_THROW(ValidateGeodetic({-90, 359.999, 9000}, "p"));
  ExpectInputError(
      [] {
        ValidateGeodetic({90.5, 0, 0}, "the origin");
      },
      "the origin: latitude 90.5 is outside [-90, 90]");
  ExpectInputError(
      [] {
        ValidateGeodetic({-91, 0, 0}, "p");
      },
      "p: latitude -91 is outside [-90, 90]");
  ExpectInputError(
      [] {
        ValidateGeodetic({NAN, 0, 0}, "p");
      },
      "p: latitude nan is outside [-90, 90]");
  ExpectInputError(
      [] {
        ValidateGeodetic({0, 360, 0}, "p");
      },
      "p: longitude 360 is outside [-180, 360)");
  ExpectInputError(
      [] {
        ValidateGeodetic({0, -180.5, 0}, "p");
      },
      "p: longitude -180.5 is outside [-180, 360)");
  ExpectInputError([] { ValidateGeodetic({0, 0, INFINITY}, "p"); }, "p: height inf is not finite");
}

TEST(GeoreferenceTest, GeoFrameRejectsABadGeoreference) {
  Georeference g;
  g.origin = {0, 400, 0};
  ExpectInputError([&] { GeoFrame frame(g); },
                   "georeference origin: longitude 400 is outside [-180, 360)");
  g.origin = {0, 0, 0};
  g.scale = 0;
  ExpectInputError([&] { GeoFrame frame(g); }, "georeference: scale 0 is not a positive number");
  g.scale = 1;
  g.rotation = Eigen::Quaterniond(0, 0, 0, 0);
  ExpectInputError([&] { GeoFrame frame(g); },
                   "georeference: the rotation is not a finite non-zero quaternion");
  g.rotation = Eigen::Quaterniond(2, 0, 0, 0);  // normalized, not rejected
  g.translation = Eigen::Vector3d(0, NAN, 0);
  ExpectInputError([&] { GeoFrame frame(g); }, "georeference: the translation is not finite");
  g.translation = Eigen::Vector3d::Zero();
  EXPECT_EQ(GeoFrame(g).georeference().rotation.w(), 1);
  ExpectInputError(
      [] {
        GeoreferenceFromEcefModel({95, 0, 0});
      },
      "ECEF georeference origin: latitude 95 is outside [-90, 90]");
  ExpectInputError(
      [] {
        GeoreferenceFromEnuModel({0, 0, NAN});
      },
      "ENU georeference origin: height nan is not finite");
}

}  // namespace
}  // namespace cwloc
