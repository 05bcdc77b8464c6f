#pragma once

// cwloc-localize's command line as parsed, shared by its main and the files that run it.

#include <string>
#include <vector>

#include "app/option_table.h"

namespace cwloc {

struct CliOptions {
  std::string index_path;
  std::string database_path;
  std::vector<std::string> query_names;
  std::string query_list;
  std::vector<std::string> feature_files;
  std::vector<std::string> images;
  std::string image_list;
  std::string image_dir;
  std::string camera_spec;
  std::string image_size;
  double focal = 0.0;
  bool unknown_focal = false;
  std::string prior_position;  // --prior-position, for every query
  std::string prior_gravity;   // --prior-gravity, for every query
  std::string priors_path;     // --priors: per query
  QueryOptions options;        // the option table's
  std::string output_path;
  std::string poses_path;
  std::string trajectory_path;  // --sequence's poses
  std::string trajectory_format = "tum";
  int threads = 1;
  bool sequence = false;    // the queries are frames of one camera, in order
  std::string video_path;   // --video: a sequence of a video file's frames
  std::string motion_path;  // --motion: the frames' motion from VIO
  uint32_t video_step = 1;
  std::string rig_config_path;         // --rig: COLMAP's rig_config.json, with --image-list
  std::string frames_path;             // --frames: each image's cam_from_rig, frame by frame
  std::string frames_scale = "known";  // --frames-scale: known, or unknown (VIO up to scale)
  bool verify = false;
  bool quiet = false;
};

}  // namespace cwloc
