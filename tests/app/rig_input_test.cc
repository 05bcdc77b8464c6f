// --rig (COLMAP 3.12's rig_config.json with an image list) and --frames: the frames they give
// and every bad input refused with the file and the entry named.
#include "app/rig_input.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/test_util.h"

namespace cwloc {
namespace {

std::filesystem::path Write(const test::TempDir& dir, const std::string& name,
                            const std::string& text) {
  const std::filesystem::path path = dir / name;
  std::ofstream(path) << text;
  return path;
}

// A stereo rig and a three-camera rig, as COLMAP's documentation writes them.
constexpr const char* kTwoRigs = R"([
  {"cameras": [
    {"image_prefix": "rig1/camera1/", "ref_sensor": true},
    {"image_prefix": "rig1/camera2/", "cam_from_rig_rotation": [0.7071067811865475, 0.0, 0.7071067811865476, 0.0],
     "cam_from_rig_translation": [0, 0, 0], "camera_model_name": "SIMPLE_PINHOLE", "camera_params": [500, 320, 240]}
  ]},
  {"cameras": [
    {"image_prefix": "rig2/a/", "cam_from_rig_rotation": [1, 0, 0, 0], "cam_from_rig_translation": [0.5, 0, 0]},
    {"image_prefix": "rig2/b/", "ref_sensor": true},
    {"image_prefix": "rig2/c/", "cam_from_rig_rotation": [1, 0, 0, 0], "cam_from_rig_translation": [-0.5, 0, 0]}
  ]}
])";

std::vector<QueryListEntry> Entries(const std::vector<std::string>& names) {
  std::vector<QueryListEntry> entries;
  for (const std::string& name : names) entries.push_back({name, ""});
  return entries;
}

TEST(RigConfig, ReadsColmapsFormat) {
  const test::TempDir dir;
  const auto rigs = ReadRigConfig(Write(dir, "rig_config.json", kTwoRigs));
  ASSERT_EQ(rigs.size(), 2u);
  ASSERT_EQ(rigs[0].size(), 2u);
  EXPECT_TRUE(rigs[0][0].ref_sensor);
  EXPECT_TRUE(rigs[0][0].cam_from_rig.rotation.isApprox(Eigen::Quaterniond::Identity()));
  EXPECT_EQ(rigs[0][1].image_prefix, "rig1/camera2/");
  EXPECT_NEAR(rigs[0][1].cam_from_rig.rotation.y(), 0.7071067811865476, 1e-15);
  EXPECT_EQ(rigs[0][1].model_name, "SIMPLE_PINHOLE");
  EXPECT_EQ(rigs[0][1].params, (std::vector<double>{500, 320, 240}));
  EXPECT_EQ(rigs[1][0].cam_from_rig.translation, Eigen::Vector3d(0.5, 0, 0));
  EXPECT_TRUE(rigs[1][1].ref_sensor);
}

TEST(RigConfig, GroupsImagesIntoFramesAsColmapsRigConfigurator) {
  const test::TempDir dir;
  const auto config = Write(dir, "rig_config.json", kTwoRigs);
  const auto rigs = ReadRigConfig(config);
  // A frame: one rig's images whose names agree after the prefix; any subset of its cameras.
  const auto frames =
      FramesOfRigs(rigs, config,
                   Entries({"rig2/c/0001.jpg", "rig1/camera2/0001.jpg", "rig2/b/0001.jpg",
                            "rig1/camera1/0001.jpg", "rig1/camera2/0002.jpg", "rig2/a/0001.jpg"}),
                   dir / "list.txt", dir.path());
  ASSERT_EQ(frames.size(), 3u);
  // In the order of each frame's first image; its reference sensor first, then config order.
  EXPECT_EQ(frames[0].name, "0001.jpg");
  ASSERT_EQ(frames[0].images.size(), 3u);
  EXPECT_EQ(frames[0].images[0].source.name, "rig2/b/0001.jpg");
  EXPECT_EQ(frames[0].images[1].source.name, "rig2/a/0001.jpg");
  EXPECT_EQ(frames[0].images[2].source.name, "rig2/c/0001.jpg");
  EXPECT_EQ(frames[0].images[2].cam_from_rig.translation, Eigen::Vector3d(-0.5, 0, 0));
  EXPECT_EQ(frames[1].name, "0001.jpg");
  ASSERT_EQ(frames[1].images.size(), 2u);
  EXPECT_EQ(frames[1].images[0].source.name, "rig1/camera1/0001.jpg");
  EXPECT_EQ(frames[1].images[1].model_name, "SIMPLE_PINHOLE");
  EXPECT_EQ(frames[1].images[1].source.path, dir.path() / "rig1/camera2/0001.jpg");
  EXPECT_EQ(frames[2].name, "0002.jpg");
  ASSERT_EQ(frames[2].images.size(), 1u);  // the reference camera need not be in a frame
  EXPECT_EQ(frames[2].images[0].source.name, "rig1/camera2/0002.jpg");
}

TEST(RigConfig, BadConfigsAreRefusedWithTheFileAndEntryNamed) {
  const test::TempDir dir;
  const auto error = [&](const std::string& text) {
    const auto path = Write(dir, "rig_config.json", text);
    return test::InputErrorOf([&] { ReadRigConfig(path); });
  };
  const std::string file = (dir / "rig_config.json").string();
  EXPECT_EQ(error(R"([{"cameras": []}])"), file + ": rig 1 names no camera");
  EXPECT_EQ(error("[]"), file +
                             ": a rig config is a JSON array of rigs, each {\"cameras\": [...]} "
                             "(COLMAP 3.12's rig_config.json)");
  EXPECT_EQ(error("[{"), file + ": not valid JSON");
  EXPECT_EQ(error(R"([{"cameras": [{"image_prefix": "a/", "ref_sensor": true},
      {"image_prefix": "b/", "cam_from_rig_rotation": [1, 0, 0, 0.5], "cam_from_rig_translation": [0, 0, 0]}]}])"),
            file +
                ": rig 1, camera 2: cam_from_rig_rotation: the quaternion (w, x, y, z) has "
                "length 1.118033988749895, not 1");
  EXPECT_EQ(error(R"([{"cameras": [{"image_prefix": "a/", "ref_sensor": true},
      {"image_prefix": "b/"}]}])"),
            file +
                ": rig 1, camera 2: a camera that is not the reference sensor needs "
                "cam_from_rig_rotation [w, x, y, z] and cam_from_rig_translation [x, y, z]");
  EXPECT_EQ(error(R"([{"cameras": [{"image_prefix": "a/"}]}])"),
            file +
                ": rig 1, camera 1: a camera that is not the reference sensor needs "
                "cam_from_rig_rotation [w, x, y, z] and cam_from_rig_translation [x, y, z]");
  EXPECT_EQ(error(R"([{"cameras": [{"image_prefix": "a/", "ref_sensor": true},
      {"image_prefix": "b/", "ref_sensor": true}]}])"),
            file + ": rig 1 has 2 cameras with \"ref_sensor\": true; a rig has exactly one");
  EXPECT_EQ(error(R"([{"cameras": [{"image_prefix": "a/", "ref_sensor": true}]},
      {"cameras": [{"image_prefix": "a/", "ref_sensor": true}]}])"),
            file + ": rig 2, camera 1: image_prefix 'a/' is also rig 1, camera 1's");
  EXPECT_EQ(error(R"([{"cameras": [{"ref_sensor": true}]}])"),
            file + ": rig 1, camera 1: \"image_prefix\" must be a string");
  EXPECT_EQ(error(R"([{"cameras": [{"image_prefix": "a/", "ref_sensor": true},
      {"image_prefix": "b/", "cam_from_rig_rotation": [1, 0, 0], "cam_from_rig_translation": [0, 0, 0]}]}])"),
            file + ": rig 1, camera 2: \"cam_from_rig_rotation\" must be 4 finite numbers");
}

TEST(RigConfig, ImagesThatFitNoCameraOrRepeatOneAreRefused) {
  const test::TempDir dir;
  const auto config = Write(dir, "rig_config.json", kTwoRigs);
  const auto rigs = ReadRigConfig(config);
  const std::string list = (dir / "list.txt").string();
  EXPECT_EQ(test::InputErrorOf([&] {
              FramesOfRigs(rigs, config, Entries({"rig1/camera1/0001.jpg", "rig3/x/0001.jpg"}),
                           list, dir.path());
            }),
            list + ": image 'rig3/x/0001.jpg' matches no image_prefix of " + config.string());
  EXPECT_EQ(test::InputErrorOf([&] {
              FramesOfRigs(rigs, config,
                           Entries({"rig1/camera1/0001.jpg", "rig1/camera1/0001.jpg"}), list,
                           dir.path());
            }),
            list +
                ": frame '0001.jpg' of rig 1 lists camera 'rig1/camera1/' twice "
                "('rig1/camera1/0001.jpg' and 'rig1/camera1/0001.jpg')");
}

TEST(FramesFile, ReadsFramesOfConsecutiveLines) {
  const test::TempDir dir;
  const auto path = Write(dir, "frames.txt",
                          "# frame image qw qx qy qz tx ty tz [camera]\n"
                          "f1 a.jpg 1 0 0 0 0 0 0 SIMPLE_PINHOLE 640 480 500 320 240\n"
                          "f1 b.txt 0 0 1 0 0.5 0 0\n"
                          "\n"
                          "f2 c.jpg 1 0 0 0 0 0 0\n");
  const auto frames = ReadFramesFile(path, dir / "images");
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(frames[0].name, "f1");
  ASSERT_EQ(frames[0].images.size(), 2u);
  EXPECT_EQ(frames[0].images[0].source.kind, QuerySource::Kind::kPhoto);
  EXPECT_EQ(frames[0].images[0].source.camera_spec, "SIMPLE_PINHOLE 640 480 500 320 240");
  EXPECT_EQ(frames[0].images[0].source.path, dir / "images" / "a.jpg");
  EXPECT_EQ(frames[0].images[1].source.kind, QuerySource::Kind::kTextFeatures);
  EXPECT_TRUE(frames[0].images[1].cam_from_rig.rotation.isApprox(Eigen::Quaterniond(0, 0, 1, 0)));
  EXPECT_EQ(frames[0].images[1].cam_from_rig.translation, Eigen::Vector3d(0.5, 0, 0));
  EXPECT_EQ(frames[1].name, "f2");
}

TEST(FramesFile, BadLinesAreRefusedWithTheLineNamed) {
  const test::TempDir dir;
  const auto error = [&](const std::string& text) {
    const auto path = Write(dir, "frames.txt", text);
    return test::InputErrorOf([&] { ReadFramesFile(path, dir.path()); });
  };
  const std::string file = (dir / "frames.txt").string();
  EXPECT_EQ(error("f1 a.jpg 1 0 0 0 0 0\n"),
            file +
                ":1: expected 'FRAME_ID IMAGE QW QX QY QZ TX TY TZ [MODEL W H PARAMS]' (the "
                "image's cam_from_rig)");
  EXPECT_EQ(error("f1 a.jpg 2 0 0 0 0 0 0\n"),
            file + ":1: cam_from_rig: the quaternion (w, x, y, z) has length 2, not 1");
  EXPECT_EQ(error("f1 a.jpg 1 0 0 0 0 0 0\nf2 b.jpg 1 0 0 0 0 0 0\nf1 c.jpg 1 0 0 0 0 0 0\n"),
            file +
                ":3: frame 'f1' continues after other lines (it was on line 1); the lines "
                "of a frame are consecutive");
  EXPECT_EQ(error("f1 a.jpg 1 0 0 0 0 0 0\nf1 a.jpg 1 0 0 0 1 0 0\n"),
            file + ":2: frame 'f1' lists image 'a.jpg' twice");
  EXPECT_EQ(error("# nothing\n"), file + ": no frames");
}

}  // namespace
}  // namespace cwloc
