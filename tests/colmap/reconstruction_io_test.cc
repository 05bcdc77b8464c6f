#include "colmap/reconstruction_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "base/error.h"
#include "tests/colmap/synthetic_model.h"
#include "tests/test_util.h"

namespace cwloc::colmap {
namespace {

namespace fs = std::filesystem;
using test::InputErrorOf;
using ::testing::HasSubstr;

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void WriteFile(const fs::path& path, const std::string& bytes) {
  // A new file rather than truncating the old one: ext4 flushes files truncated and rewritten
  // (auto_da_alloc), which makes the fuzz loops below 30 times slower.
  fs::remove(path);
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string ReadError(const fs::path& dir) {
  return InputErrorOf([&] { ReadReconstruction(dir); });
}

// Everything but rigs and frames.
void ExpectSameContent(const Reconstruction& a, const Reconstruction& b) {
  EXPECT_EQ(a.cameras, b.cameras);
  EXPECT_EQ(a.images, b.images);
  EXPECT_EQ(a.points3D, b.points3D);
}

TEST(Rigid3dTest, ComposeInvertTransform) {
  Rigid3d a, b;
  a.rotation = {std::cos(0.3), std::sin(0.3), 0, 0};  // 0.6 rad about x
  a.translation = {1, -2, 0.5};
  b.rotation = {std::cos(0.2), 0, 0, std::sin(0.2)};  // 0.4 rad about z
  b.translation = {0.3, 0, -1};
  const std::array<double, 3> x = {0.7, -1.1, 2.5};
  const auto ab_x = (a * b) * x;
  const auto a_b_x = a * (b * x);
  const auto back = Inverse(a) * (a * x);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(ab_x[i], a_b_x[i], 1e-12);
    EXPECT_NEAR(back[i], x[i], 1e-12);
  }
  // 90 degrees about z takes x to y.
  Rigid3d quarter;
  quarter.rotation = {std::sqrt(0.5), 0, 0, std::sqrt(0.5)};
  const auto y = quarter * std::array<double, 3>{1, 0, 0};
  EXPECT_NEAR(y[0], 0, 1e-15);
  EXPECT_NEAR(y[1], 1, 1e-15);
  EXPECT_NEAR(y[2], 0, 1e-15);
}

// --- Round trips ------------------------------------------------------------------------

struct RoundTripCase {
  ModelFormat format;
  ModelLayout layout;
  bool model_has_rigs;
};

std::string CaseName(const ::testing::TestParamInfo<RoundTripCase>& info) {
  return std::string(info.param.format == ModelFormat::kBinary ? "Bin" : "Txt") +
         (info.param.layout == ModelLayout::kClassic ? "Classic" : "Rigs") +
         (info.param.model_has_rigs ? "FromRigModel" : "FromPlainModel");
}

class RoundTripTest : public ::testing::TestWithParam<RoundTripCase> {};

TEST_P(RoundTripTest, WriteThenReadGivesTheSameModel) {
  const RoundTripCase c = GetParam();
  test::SyntheticModelOptions options;
  options.num_cameras = 5;
  options.num_images = 20;
  options.num_points3D = 400;
  options.with_rigs = c.model_has_rigs;
  const Reconstruction model = test::SyntheticModel(options);
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), c.format, c.layout);
  const Reconstruction read = ReadReconstruction(dir.path());
  EXPECT_EQ(ReadReconstruction(dir.path(), /*threads=*/2), read);

  ExpectSameContent(read, model);
  if (c.layout == ModelLayout::kClassic) {
    EXPECT_TRUE(read.rigs.empty());
    EXPECT_TRUE(read.frames.empty());
  } else if (c.model_has_rigs) {
    EXPECT_EQ(read.rigs, model.rigs);
    EXPECT_EQ(read.frames, model.frames);
  } else {
    // COLMAP's upgrade of a classic model: one rig per camera, one frame per image.
    EXPECT_EQ(read.rigs.size(), model.cameras.size());
    ASSERT_EQ(read.frames.size(), model.images.size());
    for (const auto& [id, frame] : read.frames) {
      const Image& image = model.images.at(id);
      EXPECT_EQ(frame.rig_id, image.camera_id);
      EXPECT_EQ(frame.rig_from_world, image.cam_from_world);
      ASSERT_EQ(frame.data_ids.size(), 1u);
      EXPECT_EQ(frame.data_ids[0].data_id, id);
    }
  }
  EXPECT_EQ(read.NumObservations(), model.NumObservations());
}

INSTANTIATE_TEST_SUITE_P(
    AllFormats, RoundTripTest,
    ::testing::Values(RoundTripCase{ModelFormat::kBinary, ModelLayout::kClassic, false},
                      RoundTripCase{ModelFormat::kBinary, ModelLayout::kClassic, true},
                      RoundTripCase{ModelFormat::kBinary, ModelLayout::kRigs, false},
                      RoundTripCase{ModelFormat::kBinary, ModelLayout::kRigs, true},
                      RoundTripCase{ModelFormat::kText, ModelLayout::kClassic, false},
                      RoundTripCase{ModelFormat::kText, ModelLayout::kClassic, true},
                      RoundTripCase{ModelFormat::kText, ModelLayout::kRigs, false},
                      RoundTripCase{ModelFormat::kText, ModelLayout::kRigs, true}),
    CaseName);

class BinTxtBinTest : public ::testing::TestWithParam<ModelLayout> {};

TEST_P(BinTxtBinTest, FilesAreByteIdentical) {
  test::SyntheticModelOptions options;
  options.with_rigs = GetParam() == ModelLayout::kRigs;
  const Reconstruction model = test::SyntheticModel(options);
  test::TempDir bin1, txt, bin2;
  WriteReconstruction(model, bin1.path(), ModelFormat::kBinary, GetParam());
  WriteReconstruction(ReadReconstruction(bin1.path()), txt.path(), ModelFormat::kText, GetParam());
  WriteReconstruction(ReadReconstruction(txt.path()), bin2.path(), ModelFormat::kBinary,
                      GetParam());
  std::vector<std::string> names = {"cameras.bin", "images.bin", "points3D.bin"};
  if (GetParam() == ModelLayout::kRigs) names.insert(names.end(), {"rigs.bin", "frames.bin"});
  for (const std::string& name : names) {
    const std::string a = ReadFile(bin1 / name);
    EXPECT_FALSE(a.empty()) << name;
    EXPECT_TRUE(a == ReadFile(bin2 / name)) << name << " differs after bin -> txt -> bin";
  }
  EXPECT_EQ(std::distance(fs::directory_iterator(bin2.path()), fs::directory_iterator()),
            static_cast<long>(names.size()))
      << "temporary files left behind";
}

INSTANTIATE_TEST_SUITE_P(Layouts, BinTxtBinTest,
                         ::testing::Values(ModelLayout::kClassic, ModelLayout::kRigs),
                         [](const ::testing::TestParamInfo<ModelLayout>& param_info) {
                           return param_info.param == ModelLayout::kClassic ? "Classic" : "Rigs";
                         });

TEST(ReconstructionIoTest, TextKeepsEveryDoubleBitForBit) {
  Reconstruction model;
  Camera camera;
  camera.camera_id = 1;
  camera.model_id = CameraModelId::kFullOpenCV;
  camera.width = 100;
  camera.height = 50;
  camera.params = {5e-324,
                   2.2250738585072014e-308,
                   1.7976931348623157e308,
                   -0.0,
                   0.1,
                   1.0 / 3,
                   -2.5e-17,
                   123456789.123456789,
                   1e22,
                   1e23,
                   4.35,
                   768};
  model.cameras.emplace(1, camera);
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), ModelFormat::kText);
  const Reconstruction read = ReadReconstruction(dir.path());
  ASSERT_EQ(read.cameras.at(1).params.size(), camera.params.size());
  for (size_t i = 0; i < camera.params.size(); ++i) {
    EXPECT_EQ(std::bit_cast<uint64_t>(read.cameras.at(1).params[i]),
              std::bit_cast<uint64_t>(camera.params[i]))
        << i << ": " << camera.params[i];
  }
  // COLMAP's spelling: 17 significant digits, "%g" style.
  EXPECT_THAT(ReadFile(dir / "cameras.txt"),
              HasSubstr("1 FULL_OPENCV 100 50 4.9406564584124654e-324 "
                        "2.2250738585072014e-308 1.7976931348623157e+308 -0 "
                        "0.10000000000000001 0.33333333333333331 -2.4999999999999999e-17 "
                        "123456789.12345679 1e+22 9.9999999999999992e+22 4.3499999999999996 "
                        "768\n"));
}

TEST(ReconstructionIoTest, TextHeadersAreColmaps) {
  test::SyntheticModelOptions options;
  options.num_cameras = 1;
  options.num_images = 2;
  options.num_points3D = 3;
  options.min_track_length = options.max_track_length = 2;
  options.sparse_ids = false;
  const Reconstruction model = test::SyntheticModel(options);
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), ModelFormat::kText, ModelLayout::kRigs);
  const std::string cameras_header =
      "# Camera list with one line of data per camera:\n"
      "#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n"
      "# Number of cameras: 1\n1 ";
  EXPECT_EQ(ReadFile(dir / "cameras.txt").substr(0, cameras_header.size()), cameras_header);
  const std::string images_header =
      "# Image list with two lines of data per image:\n"
      "#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n"
      "#   POINTS2D[] as (X, Y, POINT3D_ID)\n"
      "# Number of images: 2, mean observations per image: ";
  EXPECT_EQ(ReadFile(dir / "images.txt").substr(0, images_header.size()), images_header);
  const std::string points_header =
      "# 3D point list with one line of data per point:\n"
      "#   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n"
      "# Number of points: 3, mean track length: ";
  EXPECT_EQ(ReadFile(dir / "points3D.txt").substr(0, points_header.size()), points_header);
  EXPECT_THAT(ReadFile(dir / "rigs.txt"), HasSubstr("# Number of rigs: 1\n1 1 CAMERA 1\n"));
  EXPECT_THAT(ReadFile(dir / "frames.txt"),
              HasSubstr("#   FRAME_ID, RIG_ID, RIG_FROM_WORLD[QW, QX, QY, QZ, TX, TY, TZ], "
                        "NUM_DATA_IDS, DATA_IDS[] as (SENSOR_TYPE, SENSOR_ID, DATA_ID)\n"
                        "# Number of frames: 2\n1 1 "));
}

TEST(ReconstructionIoTest, TextNamesWithSpacesAndCrlfLines) {
  test::SyntheticModelOptions options;
  options.num_images = 3;
  Reconstruction model = test::SyntheticModel(options);
  model.images.begin()->second.name = "holiday photos/IMG 0001.JPG";
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), ModelFormat::kText);
  EXPECT_EQ(ReadReconstruction(dir.path()), model);
  // Files edited on Windows.
  for (const char* name : {"cameras.txt", "images.txt", "points3D.txt"}) {
    std::string text = ReadFile(dir / name), crlf;
    for (char ch : text) {
      if (ch == '\n') crlf += '\r';
      crlf += ch;
    }
    WriteFile(dir / name, crlf);
  }
  EXPECT_EQ(ReadReconstruction(dir.path()), model);

  // Names the text format cannot hold are refused, not silently changed.
  test::TempDir other;
  for (const char* name : {"two\nlines.jpg", "trailing.jpg ", " leading.jpg"}) {
    model.images.begin()->second.name = name;
    EXPECT_THAT(InputErrorOf([&] { WriteReconstruction(model, other.path(), ModelFormat::kText); }),
                HasSubstr("images.txt: image " + std::to_string(model.images.begin()->first) +
                          ": name '" + name + "' cannot be stored in a text model"));
    WriteReconstruction(model, other.path(), ModelFormat::kBinary);
    EXPECT_EQ(ReadReconstruction(other.path()), model);
  }
}

TEST(ReconstructionIoTest, EmptyModelAndEmptyTracks) {
  test::TempDir dir;
  for (ModelFormat format : {ModelFormat::kBinary, ModelFormat::kText}) {
    WriteReconstruction(Reconstruction{}, dir.path(), format, ModelLayout::kRigs);
    EXPECT_EQ(ReadReconstruction(dir.path()), Reconstruction{});
    fs::remove_all(dir.path());
    fs::create_directory(dir.path());
  }
  // A point without observations, an image without points2D, a rig without sensors.
  Reconstruction model;
  model.cameras[1] = Camera{1, CameraModelId::kSimplePinhole, 10, 10, {1, 5, 5}};
  model.images[1] = Image{1, 1, "a.jpg", {}, {}};
  model.points3D[3] = Point3D{3, {1, 2, 3}, {1, 2, 3}, 0.5, {}};
  for (ModelFormat format : {ModelFormat::kBinary, ModelFormat::kText}) {
    WriteReconstruction(model, dir.path(), format);
    EXPECT_EQ(ReadReconstruction(dir.path()), model);
    fs::remove_all(dir.path());
    fs::create_directory(dir.path());
  }
  model.rigs[1] = Rig{1, {SensorType::kCamera, 1}, {}};
  model.rigs[2] = Rig{2, {SensorType::kInvalid, UINT32_MAX}, {}};
  model.frames[1] = Frame{1, 1, {}, {{{SensorType::kCamera, 1}, 1}}};
  for (ModelFormat format : {ModelFormat::kBinary, ModelFormat::kText}) {
    WriteReconstruction(model, dir.path(), format, ModelLayout::kRigs);
    EXPECT_EQ(ReadReconstruction(dir.path()), model);
  }
  EXPECT_THAT(ReadFile(dir / "points3D.txt"), HasSubstr("\n3 1 2 3 1 2 3 0.5 \n"));
  EXPECT_THAT(ReadFile(dir / "rigs.txt"), HasSubstr("\n2 0\n"));
}

TEST(ReconstructionIoTest, ClassicWriteRemovesStaleRigFiles) {
  test::SyntheticModelOptions options;
  options.with_rigs = true;
  const Reconstruction model = test::SyntheticModel(options);
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  ASSERT_TRUE(fs::exists(dir / "rigs.bin"));
  WriteReconstruction(model, dir.path(), ModelFormat::kBinary, ModelLayout::kClassic);
  EXPECT_FALSE(fs::exists(dir / "rigs.bin"));
  EXPECT_FALSE(fs::exists(dir / "frames.bin"));
  EXPECT_TRUE(ReadReconstruction(dir.path()).rigs.empty());
}

// --- Exact bytes ------------------------------------------------------------------------

Reconstruction TinyModel() {
  Reconstruction model;
  model.cameras[1] = Camera{1, CameraModelId::kSimpleRadial, 1536, 1024, {1375.5, 768, 512, -0.25}};
  Image image;
  image.image_id = 7;
  image.camera_id = 1;
  image.name = "a.jpg";
  image.cam_from_world.rotation = {1, 0, 0, 0};
  image.cam_from_world.translation = {1, 2, -3};
  image.points2D = {{10.5, 20.25, 5}, {30, 40, kInvalidPoint3DId}};
  model.images[7] = image;
  model.points3D[5] = Point3D{5, {1, 2, 3}, {10, 20, 30}, 0.5, {{7, 0}}};
  return model;
}

std::string Bytes(std::initializer_list<int> values) {
  std::string s;
  for (int v : values) s += static_cast<char>(v);
  return s;
}

TEST(ReconstructionIoTest, ExactBinaryBytes) {
  test::TempDir dir;
  WriteReconstruction(TinyModel(), dir.path(), ModelFormat::kBinary);

  const std::string cameras = ReadFile(dir / "cameras.bin");
  ASSERT_EQ(cameras.size(), 8u + 4 + 4 + 8 + 8 + 4 * 8);  // 64, as herz_jesu's cameras.bin
  EXPECT_EQ(cameras.substr(0, 8), Bytes({1, 0, 0, 0, 0, 0, 0, 0}));            // num_cameras
  EXPECT_EQ(cameras.substr(8, 4), Bytes({1, 0, 0, 0}));                        // camera_id
  EXPECT_EQ(cameras.substr(12, 4), Bytes({2, 0, 0, 0}));                       // SIMPLE_RADIAL
  EXPECT_EQ(cameras.substr(16, 8), Bytes({0, 6, 0, 0, 0, 0, 0, 0}));           // width 1536
  EXPECT_EQ(cameras.substr(24, 8), Bytes({0, 4, 0, 0, 0, 0, 0, 0}));           // height 1024
  EXPECT_EQ(cameras.substr(32, 8), Bytes({0, 0, 0, 0, 0, 0x7e, 0x95, 0x40}));  // 1375.5
  EXPECT_EQ(cameras.substr(56, 8), Bytes({0, 0, 0, 0, 0, 0, 0xd0, 0xbf}));     // -0.25

  const std::string images = ReadFile(dir / "images.bin");
  ASSERT_EQ(images.size(), 8u + 4 + 7 * 8 + 4 + 6 + 8 + 2 * 24);
  EXPECT_EQ(images.substr(0, 8), Bytes({1, 0, 0, 0, 0, 0, 0, 0}));         // num_reg_images
  EXPECT_EQ(images.substr(8, 4), Bytes({7, 0, 0, 0}));                     // image_id
  EXPECT_EQ(images.substr(12, 8), Bytes({0, 0, 0, 0, 0, 0, 0xf0, 0x3f}));  // qw = 1
  EXPECT_EQ(images.substr(44, 8), Bytes({0, 0, 0, 0, 0, 0, 0xf0, 0x3f}));  // tx = 1
  EXPECT_EQ(images.substr(60, 8), Bytes({0, 0, 0, 0, 0, 0, 0x08, 0xc0}));  // tz = -3
  EXPECT_EQ(images.substr(68, 4), Bytes({1, 0, 0, 0}));                    // camera_id
  EXPECT_EQ(images.substr(72, 6), std::string("a.jpg\0", 6));              // name + NUL
  EXPECT_EQ(images.substr(78, 8), Bytes({2, 0, 0, 0, 0, 0, 0, 0}));        // num_points2D
  EXPECT_EQ(images.substr(86, 8), Bytes({0, 0, 0, 0, 0, 0, 0x25, 0x40}));  // x = 10.5
  EXPECT_EQ(images.substr(102, 8), Bytes({5, 0, 0, 0, 0, 0, 0, 0}));       // point3D_id 5
  EXPECT_EQ(images.substr(126, 8), std::string(8, '\xff'));                // -1: no point

  const std::string points = ReadFile(dir / "points3D.bin");
  ASSERT_EQ(points.size(), 8u + 8 + 24 + 3 + 8 + 8 + 8);
  EXPECT_EQ(points.substr(8, 8), Bytes({5, 0, 0, 0, 0, 0, 0, 0}));         // point3D_id
  EXPECT_EQ(points.substr(40, 3), Bytes({10, 20, 30}));                    // rgb
  EXPECT_EQ(points.substr(43, 8), Bytes({0, 0, 0, 0, 0, 0, 0xe0, 0x3f}));  // error 0.5
  EXPECT_EQ(points.substr(51, 8), Bytes({1, 0, 0, 0, 0, 0, 0, 0}));        // track_length
  EXPECT_EQ(points.substr(59, 8), Bytes({7, 0, 0, 0, 0, 0, 0, 0}));        // (7, 0)

  EXPECT_EQ(ReadReconstruction(dir.path()), TinyModel());
}

TEST(ReconstructionIoTest, ExactRigBytes) {
  Reconstruction model = TinyModel();
  model.cameras[2] = Camera{2, CameraModelId::kSimplePinhole, 10, 10, {1, 5, 5}};
  Rig rig{3, {SensorType::kCamera, 1}, {}};
  rig.sensors.push_back({{SensorType::kCamera, 2}, Rigid3d{}});
  rig.sensors.push_back({{SensorType::kImu, 9}, std::nullopt});
  model.rigs[3] = rig;
  model.frames[4] = Frame{4, 3, model.images[7].cam_from_world, {{{SensorType::kCamera, 1}, 7}}};
  test::TempDir dir;
  WriteReconstruction(model, dir.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  const std::string rigs = ReadFile(dir / "rigs.bin");
  ASSERT_EQ(rigs.size(), 8u + 4 + 4 + 8 + (8 + 1 + 56) + (8 + 1));
  EXPECT_EQ(rigs.substr(8, 4), Bytes({3, 0, 0, 0}));                  // rig_id
  EXPECT_EQ(rigs.substr(12, 4), Bytes({3, 0, 0, 0}));                 // num_sensors incl. ref
  EXPECT_EQ(rigs.substr(16, 8), Bytes({0, 0, 0, 0, 1, 0, 0, 0}));     // ref: CAMERA 1
  EXPECT_EQ(rigs.substr(24, 9), Bytes({0, 0, 0, 0, 2, 0, 0, 0, 1}));  // CAMERA 2, has_pose
  EXPECT_EQ(rigs.substr(89, 9), Bytes({1, 0, 0, 0, 9, 0, 0, 0, 0}));  // IMU 9, no pose
  const std::string frames = ReadFile(dir / "frames.bin");
  ASSERT_EQ(frames.size(), 8u + 4 + 4 + 56 + 4 + 16);
  EXPECT_EQ(frames.substr(8, 8), Bytes({4, 0, 0, 0, 3, 0, 0, 0}));  // frame_id, rig_id
  EXPECT_EQ(frames.substr(72, 4), Bytes({1, 0, 0, 0}));             // num_data_ids
  EXPECT_EQ(frames.substr(76, 16), Bytes({0, 0, 0, 0, 1, 0, 0, 0, 7, 0, 0, 0, 0, 0, 0, 0}));
  EXPECT_EQ(ReadReconstruction(dir.path()), model);
}

// --- Hostile and broken input -----------------------------------------------------------

class BrokenModelTest : public ::testing::Test {
 protected:
  void SetUp() override { WriteReconstruction(TinyModel(), dir_.path(), ModelFormat::kBinary); }
  void Patch(const char* name, size_t offset, const std::string& bytes) {
    std::string data = ReadFile(dir_ / name);
    data.replace(offset, bytes.size(), bytes);
    WriteFile(dir_ / name, data);
  }
  void WriteModel(const Reconstruction& model) {
    WriteReconstruction(model, dir_.path(), ModelFormat::kBinary);
  }
  std::string Error() { return ReadError(dir_.path()); }
  std::string Path(const char* name) { return (dir_ / name).string(); }

  test::TempDir dir_;
};

TEST_F(BrokenModelTest, UnknownCameraModel) {
  Patch("cameras.bin", 12, Bytes({99, 0, 0, 0}));
  EXPECT_EQ(Error(),
            Path("cameras.bin") + ": camera 1: unknown camera model id 99 (expected 0..17)");
}

TEST_F(BrokenModelTest, HugeCountsInTinyFiles) {
  Patch("cameras.bin", 0, Bytes({0, 0, 0, 0, 0, 0, 0, 0x10}));  // 2^60 cameras
  EXPECT_EQ(Error(), Path("cameras.bin") +
                         ": header: num_cameras = 1152921504606846976 does not fit in the 56 "
                         "bytes left at byte 8 (each needs at least 40)");
  SetUp();
  Patch("images.bin", 78, Bytes({0, 0, 0, 0, 0, 0, 0, 0x01}));  // 2^56 points2D
  EXPECT_EQ(Error(), Path("images.bin") +
                         ": image 7: num_points2D = 72057594037927936 does not fit in the 48 "
                         "bytes left at byte 86 (each needs at least 24)");
  SetUp();
  Patch("points3D.bin", 51, Bytes({0xff, 0xff, 0xff, 0xff, 0, 0, 0, 0}));
  EXPECT_EQ(Error(), Path("points3D.bin") +
                         ": point3D 5: track_length = 4294967295 does not fit in the 8 bytes "
                         "left at byte 59 (each needs at least 8)");
  SetUp();
  Patch("images.bin", 0, Bytes({0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff, 0xff}));
  EXPECT_THAT(Error(), HasSubstr("header: num_reg_images = 18446744073709551615 does not fit"));
}

// Read on two threads, a model broken in images.bin and points3D.bin reports images.bin's
// error, as the one-thread read does; points3D.bin's alone is reported too.
TEST_F(BrokenModelTest, TwoThreadsReportTheErrorOneThreadDoes) {
  const auto error_on = [&](int threads) {
    return InputErrorOf([&] { ReadReconstruction(dir_.path(), threads); });
  };
  Patch("points3D.bin", 51, Bytes({0xff, 0xff, 0xff, 0xff, 0, 0, 0, 0}));
  EXPECT_EQ(error_on(2), Path("points3D.bin") +
                             ": point3D 5: track_length = 4294967295 does not fit in the 8 bytes "
                             "left at byte 59 (each needs at least 8)");
  Patch("images.bin", 78, Bytes({0, 0, 0, 0, 0, 0, 0, 0x01}));
  const std::string images_error = Path("images.bin") +
                                   ": image 7: num_points2D = 72057594037927936 does not fit in "
                                   "the 48 bytes left at byte 86 (each needs at least 24)";
  EXPECT_EQ(error_on(1), images_error);
  EXPECT_EQ(error_on(2), images_error);
}

TEST_F(BrokenModelTest, TruncatedFiles) {
  const std::string images = ReadFile(dir_ / "images.bin");
  // The count is checked against the file size before any record is read.
  WriteFile(dir_ / "images.bin", images.substr(0, 75));
  EXPECT_EQ(Error(), Path("images.bin") +
                         ": header: num_reg_images = 1 does not fit in the 67 bytes left at byte "
                         "8 (each needs at least 73)");
  // A name without its terminating NUL runs into the end of the file.
  WriteFile(dir_ / "images.bin", images.substr(0, 72) + std::string(80, 'x'));
  EXPECT_EQ(Error(), Path("images.bin") +
                         ": image 7: unexpected end of file reading name at byte 152 (file is "
                         "152 bytes)");
  // Complete name, then the points2D cut short.
  WriteFile(dir_ / "images.bin",
            images.substr(0, 72) + std::string(70, 'x') + '\0' + std::string(5, '\0'));
  EXPECT_EQ(Error(), Path("images.bin") +
                         ": image 7: unexpected end of file reading num_points2D at byte 143 "
                         "(file is 148 bytes)");
  WriteFile(dir_ / "images.bin", images + "xyz");
  EXPECT_EQ(Error(),
            Path("images.bin") + ": 3 unexpected bytes after the last image (byte 134 of 137)");
  WriteFile(dir_ / "images.bin", "");
  EXPECT_EQ(Error(), Path("images.bin") +
                         ": header: unexpected end of file reading num_reg_images at byte 0 "
                         "(file is 0 bytes)");
}

TEST_F(BrokenModelTest, EveryTruncationAndByteFlipIsAnInputError) {
  test::SyntheticModelOptions options;
  options.num_cameras = 2;
  options.num_images = 3;
  options.num_points3D = 8;
  options.num_unobserved_points2D = 2;
  options.with_rigs = true;
  WriteReconstruction(test::SyntheticModel(options), dir_.path(), ModelFormat::kBinary,
                      ModelLayout::kRigs);
  std::uniform_int_distribution<int> byte(0, 255);
  for (const char* name : {"cameras.bin", "rigs.bin", "frames.bin", "images.bin", "points3D.bin"}) {
    const std::string original = ReadFile(dir_ / name);
    for (size_t size = 0; size < original.size(); ++size) {
      WriteFile(dir_ / name, original.substr(0, size));
      EXPECT_THAT(Error(), HasSubstr(Path(name))) << name << " truncated to " << size;
    }
    for (size_t i = 0; i < original.size(); ++i) {
      std::string flipped = original;
      flipped[i] = static_cast<char>(byte(test::Rng()));
      WriteFile(dir_ / name, flipped);
      try {
        ReadReconstruction(dir_.path());  // may still be a valid model
      } catch (const InputError&) {
      }
    }
    WriteFile(dir_ / name, original);
  }
  EXPECT_EQ(Error(), "");
}

TEST_F(BrokenModelTest, BrokenCrossReferences) {
  Reconstruction model = TinyModel();
  model.images[7].camera_id = 3;
  WriteModel(model);
  EXPECT_EQ(Error(), Path("images.bin") + ": image 7: camera_id 3 is not in cameras.bin");

  model = TinyModel();
  model.images[7].points2D[1].point3D_id = 999;
  WriteModel(model);
  EXPECT_EQ(Error(),
            Path("images.bin") +
                ": image 7: point2D 1 refers to point3D 999, which is not in points3D.bin");

  model = TinyModel();
  model.points3D[6] = Point3D{6, {0, 0, 1}, {}, 1, {}};
  model.images[7].points2D[1].point3D_id = 6;  // but point 6's track does not list it
  WriteModel(model);
  EXPECT_EQ(Error(), Path("images.bin") +
                         ": image 7: point2D 1 refers to point3D 6, whose track does not list it");

  model = TinyModel();
  model.points3D[5].track = {{99, 0}};
  WriteModel(model);
  EXPECT_EQ(Error(), Path("points3D.bin") +
                         ": point3D 5: track element 0 refers to image 99, which is not in "
                         "images.bin");

  model = TinyModel();
  model.points3D[5].track = {{7, 50}};
  WriteModel(model);
  EXPECT_EQ(Error(), Path("points3D.bin") +
                         ": point3D 5: track element 0 has point2D_idx 50 but image 7 has 2 "
                         "points2D");

  model = TinyModel();
  model.points3D[5].track = {{7, 1}};
  WriteModel(model);
  EXPECT_EQ(Error(), Path("points3D.bin") +
                         ": point3D 5: track element 0 is point2D 1 of image 7, whose "
                         "point3D_id is -1 in images.bin, not 5");

  model = TinyModel();
  model.points3D[5].track = {{7, 0}, {7, 0}};
  WriteModel(model);
  EXPECT_EQ(Error(), Path("points3D.bin") + ": point3D 5: track lists point2D 0 of image 7 twice");
}

TEST_F(BrokenModelTest, DuplicateIds) {
  // Two records with id 7: the count says 2 and the record is repeated.
  std::string images = ReadFile(dir_ / "images.bin");
  std::string doubled = images + images.substr(8);
  doubled[0] = 2;
  WriteFile(dir_ / "images.bin", doubled);
  EXPECT_EQ(Error(), Path("images.bin") + ": image 7: duplicate image_id");
}

TEST_F(BrokenModelTest, RigLayoutProblems) {
  Reconstruction model = TinyModel();
  model.cameras[2] = Camera{2, CameraModelId::kSimplePinhole, 10, 10, {1, 5, 5}};
  model.rigs[3] = Rig{3, {SensorType::kCamera, 2}, {{{SensorType::kCamera, 1}, std::nullopt}}};
  model.frames[4] = Frame{4, 3, {}, {{{SensorType::kCamera, 1}, 7}}};
  WriteReconstruction(model, dir_.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  EXPECT_EQ(Error(), Path("rigs.bin") +
                         ": rig 3: sensor CAMERA 1 has no sensor_from_rig, needed for the pose "
                         "of image 7 (frame 4)");

  model.frames[4].data_ids = {{{SensorType::kCamera, 2}, 8}};
  WriteReconstruction(model, dir_.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  EXPECT_EQ(Error(), Path("images.bin") + ": image 7 is in no frame of frames.bin");

  model.frames[4].data_ids = {{{SensorType::kCamera, 2}, 7}};
  WriteReconstruction(model, dir_.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  EXPECT_EQ(Error(), Path("frames.bin") +
                         ": frame 4 lists image 7 as data of CAMERA 2, but image 7 has camera_id "
                         "1 in images.bin");

  model.frames[4].rig_id = 5;
  WriteReconstruction(model, dir_.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  EXPECT_EQ(Error(), Path("frames.bin") + ": frame 4: rig_id 5 is not in rigs.bin");

  model.rigs[3].ref_sensor = {SensorType::kCamera, 8};
  WriteReconstruction(model, dir_.path(), ModelFormat::kBinary, ModelLayout::kRigs);
  EXPECT_EQ(Error(), Path("rigs.bin") + ": rig 3: sensor CAMERA 8 is not in cameras.bin");

  fs::remove(dir_ / "frames.bin");
  EXPECT_THAT(Error(), HasSubstr(": has rigs.bin but no frames.bin"));
}

TEST_F(BrokenModelTest, MissingFilesAndDirectories) {
  fs::remove(dir_ / "points3D.bin");
  EXPECT_EQ(Error(), Path("points3D.bin") + ": cannot open: No such file or directory");
  EXPECT_THAT(ReadError(dir_ / "nope"), HasSubstr("nope: not a directory"));
  test::TempDir empty;
  EXPECT_THAT(ReadError(empty.path()), HasSubstr(": no COLMAP model (expected cameras.bin"));
}

TEST(ReconstructionIoTextTest, BrokenTextFiles) {
  test::TempDir dir;
  WriteReconstruction(TinyModel(), dir.path(), ModelFormat::kText);
  const std::string cameras = ReadFile(dir / "cameras.txt");
  const std::string images = ReadFile(dir / "images.txt");
  const std::string path_cameras = (dir / "cameras.txt").string();
  const std::string path_images = (dir / "images.txt").string();
  auto replace = [](std::string text, const std::string& from, const std::string& to) {
    const size_t at = text.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return text.replace(at, from.size(), to);
  };

  WriteFile(dir / "cameras.txt", replace(cameras, "SIMPLE_RADIAL", "SIMPLE_RADIAL_X"));
  EXPECT_EQ(ReadError(dir.path()),
            path_cameras +
                ":4: camera 1: MODEL: expected a COLMAP camera model name, found "
                "'SIMPLE_RADIAL_X'");
  WriteFile(dir / "cameras.txt", replace(cameras, " -0.25", ""));
  EXPECT_EQ(ReadError(dir.path()), path_cameras +
                                       ":4: camera 1: PARAMS: model SIMPLE_RADIAL expects 4 "
                                       "parameters, found 3");
  WriteFile(dir / "cameras.txt", replace(cameras, "1536", "15x6"));
  EXPECT_EQ(ReadError(dir.path()), path_cameras +
                                       ":4: camera 1: WIDTH: expected an unsigned 64-bit "
                                       "integer, found '15x6'");
  WriteFile(dir / "cameras.txt", cameras);

  WriteFile(dir / "images.txt", replace(images, "10.5 20.25 5", "10.5 abc 5"));
  EXPECT_EQ(ReadError(dir.path()),
            path_images + ":6: image 7: POINTS2D Y: expected a number, found 'abc'");
  WriteFile(dir / "images.txt", replace(images, "10.5 20.25 5 30 40 -1", "10.5 20.25 5 30 40"));
  EXPECT_EQ(ReadError(dir.path()),
            path_images + ":6: image 7: POINTS2D POINT3D_ID: missing (the line ends early)");
  // An empty points2D line: the image has none, so point 5's track is out of range.
  WriteFile(dir / "images.txt", images.substr(0, images.find("10.5")) + "\n");
  EXPECT_EQ(ReadError(dir.path()), (dir / "points3D.txt").string() +
                                       ": point3D 5: track element 0 has point2D_idx 0 but "
                                       "image 7 has 0 points2D");
  WriteFile(dir / "images.txt", images.substr(0, images.find("10.5")));
  EXPECT_EQ(ReadError(dir.path()),
            path_images + ":5: image 7: POINTS2D: missing (the file ends after the image line)");
  WriteFile(dir / "images.txt", images);

  const std::string points = ReadFile(dir / "points3D.txt");
  WriteFile(dir / "points3D.txt", replace(points, " 10 20 30 ", " 10 256 30 "));
  EXPECT_EQ(ReadError(dir.path()),
            (dir / "points3D.txt").string() + ":4: point3D 5: R, G, B: 256 is not in 0..255");
  WriteFile(dir / "points3D.txt", replace(points, "0.5 7 0", "0.5 7"));
  EXPECT_EQ(ReadError(dir.path()), (dir / "points3D.txt").string() +
                                       ":4: point3D 5: TRACK POINT2D_IDX: missing (the line "
                                       "ends early)");
}

// --- Writing errors ---------------------------------------------------------------------

TEST(ReconstructionIoWriteTest, UnwritableTargets) {
  test::TempDir dir;
  EXPECT_EQ(InputErrorOf(
                [&] { WriteReconstruction(TinyModel(), dir / "missing", ModelFormat::kBinary); }),
            (dir / "missing").string() + ": not a directory (create it before writing a model)");

  // A full disk: the file being replaced is kept and no temporary file is left behind.
  WriteReconstruction(TinyModel(), dir.path(), ModelFormat::kText);
  const std::string cameras = ReadFile(dir / "cameras.txt");
  {
    const test::FileSizeLimit limit(16);
    EXPECT_EQ(
        InputErrorOf([&] { WriteReconstruction(TinyModel(), dir.path(), ModelFormat::kText); }),
        (dir / "cameras.txt").string() + ": cannot write: File too large");
  }
  EXPECT_EQ(ReadFile(dir / "cameras.txt"), cameras);
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 3);
}

}  // namespace
}  // namespace cwloc::colmap
