#pragma once

// cwloc-localize's rig inputs (docs/cli.md, "Rigs and multi-frame queries"): COLMAP 3.12's
// rig_config.json with an image list, or a --frames file; both become frames, each a list of
// images with their cam_from_rig.

#include <filesystem>
#include <string>
#include <vector>

#include "app/query_assembly.h"
#include "app/query_list.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// One image of a frame: where it is read from and where its camera sits on the rig.
struct RigFrameImage {
  QuerySource source;
  CameraPose cam_from_rig;
  // A rig config's camera_model_name and camera_params, which the photo's size completes
  // (empty without; the image list's camera, when it has one, comes first).
  std::string model_name;
  std::vector<double> params;
};

struct RigFrameInput {
  std::string name;
  std::vector<RigFrameImage> images;  // the first is the frame's reference camera
};

// A camera of a rig config.
struct RigConfigCamera {
  std::string image_prefix;
  bool ref_sensor = false;
  CameraPose cam_from_rig;  // the identity for the reference sensor
  std::string model_name;   // optional
  std::vector<double> params;
};

// COLMAP 3.12's rig_config.json: an array of rigs, each {"cameras": [...]} with one camera
// "ref_sensor": true (its cam_from_rig the identity) and the others' "cam_from_rig_rotation"
// [w, x, y, z] and "cam_from_rig_translation"; optional "camera_model_name" and
// "camera_params". Throws InputError naming the file and the rig and camera for a file that is
// not such JSON, a rig with no cameras or not exactly one reference sensor, a camera without an
// image_prefix or its pose, a quaternion not of unit length, two cameras with one prefix.
std::vector<std::vector<RigConfigCamera>> ReadRigConfig(const std::filesystem::path& path);

// Groups an image list's entries into frames as COLMAP's rig_configurator does: an image
// belongs to the camera whose image_prefix its name starts with (the longest), and images of
// one rig whose names agree after the prefix are one frame, named by that rest. Frames come in
// the order of their first image; a frame's images in the rig's camera order, its reference
// sensor first. `base`: the folder the names are relative to. Throws InputError naming the list
// and the image for an image that matches no prefix, or a camera listed twice in one frame.
std::vector<RigFrameInput> FramesOfRigs(const std::vector<std::vector<RigConfigCamera>>& rigs,
                                        const std::filesystem::path& config,
                                        const std::vector<QueryListEntry>& entries,
                                        const std::filesystem::path& list,
                                        const std::filesystem::path& base);

// --frames FILE: one line per image, 'FRAME_ID IMAGE QW QX QY QZ TX TY TZ [MODEL W H PARAMS]',
// the quaternion and translation the image's cam_from_rig; the lines of one frame consecutive,
// its first image the reference camera. IMAGE is relative to `base` (--image-dir, else the
// file's folder): a COLMAP text feature file when it ends in .txt, else a photo. '#' starts a
// comment line. Throws InputError naming the file and line for a malformed line, a quaternion
// not of unit length, a frame whose lines are not consecutive, or one image twice in a frame.
std::vector<RigFrameInput> ReadFramesFile(const std::filesystem::path& path,
                                          const std::filesystem::path& base);

}  // namespace cwloc
