#pragma once

// Writes a generated city in the layout of the shared real-data sets (see docs/synth.md):
// mapping_model/bin (and txt), database.db with every image's features, the query lists and
// ground truth, scale_to_metres.txt, README.txt and stats.json; with a query rig its
// rig_config.json; with --geo also the files of city_geo.h, and the model and ground truth in
// the model frame. Everything is written into a
// temporary sibling directory that Commit() renames into place, so a failure or an interrupt
// never leaves a half-written output.

#include <filesystem>
#include <string>

#include "tools/synth/city_geo.h"
#include "tools/synth/city_scene.h"

namespace cwloc::synth {

struct WriteOptions {
  bool text = false;         // also write mapping_model/txt
  int threads = 0;           // for rendering descriptors; 0: all cores
  std::string command_line;  // recorded in README.txt
  GeoOptions geo;            // --geo: the model frame and the geo files (city_geo.h)
};

struct WriteTimings {
  double model_seconds = 0;
  double database_seconds = 0;
  double files_seconds = 0;
};

class SceneWriter {
 public:
  // Checks the output path and creates the temporary directory next to it. Throws InputError
  // when the path exists and is not an empty directory (unless `overwrite`), or cannot be
  // created or written.
  SceneWriter(const std::filesystem::path& output_dir, bool overwrite);
  ~SceneWriter();  // removes the temporary directory unless committed
  SceneWriter(const SceneWriter&) = delete;
  SceneWriter& operator=(const SceneWriter&) = delete;

  const std::filesystem::path& output_dir() const { return output_dir_; }
  const std::filesystem::path& temp_dir() const { return temp_dir_; }

  // Writes everything but stats.json into the temporary directory.
  WriteTimings Write(const CityScene& scene, const WriteOptions& options,
                     const CityScene::Progress& progress = {});

  // Writes stats.json and moves the result to the output path (replacing an old one when
  // overwriting).
  void Commit(const std::string& stats_json);

 private:
  std::filesystem::path output_dir_;
  std::filesystem::path temp_dir_;
  bool overwrite_ = false;
  bool committed_ = false;
};

// The model a triangulating SfM would give: mapping images only, every keypoint as a point2D
// (clutter and single-view points with an invalid point3D id), points seen >= 2 times; in the
// model frame (world coordinates without --geo).
colmap::Reconstruction BuildReconstruction(const CityScene& scene, int threads = 0,
                                           const ModelFrame& frame = {});

}  // namespace cwloc::synth
