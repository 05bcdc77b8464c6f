#pragma once

#include <cstddef>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "colmap/reconstruction.h"

namespace cwloc::colmap {

enum class ModelFormat { kBinary, kText };
enum class ModelLayout {
  kClassic,  // cameras, images, points3D (COLMAP <= 3.11; Debian's colmap 3.8)
  kRigs,     // plus rigs and frames (COLMAP >= 3.12)
};

// Reads a sparse model directory. Picks binary when cameras.bin exists, text when
// cameras.txt does, and the rig layout when rigs.* and frames.* are present (one without
// the other is an error). In the rig layout each image's cam_from_world is recomputed from
// its frame's rig_from_world and the rig's sensor_from_rig, as COLMAP does; the pose stored
// in images.* is ignored.
// Throws InputError naming the file, the record and the field on any malformed input,
// including broken cross-references (see the invariants listed on Reconstruction). A model file
// that is not a regular file or is over kColmapModelFile's limit (base/bounded_file.h)
// is refused before it is opened. With `threads` > 1, points3D.* is read on a second thread
// while images.* is (an images.* error is the one reported when both have one).
Reconstruction ReadReconstruction(const std::filesystem::path& dir, int threads = 1);
Reconstruction ReadReconstructionBinary(const std::filesystem::path& dir, int threads = 1);
Reconstruction ReadReconstructionText(const std::filesystem::path& dir, int threads = 1);

// Writes a model COLMAP reads back. With kRigs, a model without rigs and frames gets one
// trivial rig per camera and one frame per image, as COLMAP does when it upgrades a model.
// With kClassic, stale rigs.* / frames.* of the same format are removed from `dir` so that
// a later read does not pick them up. Each file is replaced atomically (AtomicFileWriter).
// Numbers in text files use 17 significant digits (COLMAP's precision), so text round-trips
// every double exactly. Throws InputError naming the file when `dir` is missing or not
// writable, or a write fails.
void WriteReconstruction(const Reconstruction& reconstruction, const std::filesystem::path& dir,
                         ModelFormat format, ModelLayout layout = ModelLayout::kClassic);

// Shared by the binary and text readers/writers of this folder; not a public interface.
namespace detail {

// The files of one model, named in error messages.
struct ModelFiles {
  std::filesystem::path cameras, images, points3D, rigs, frames;
  bool has_rigs = false;  // rigs and frames were read (the rig layout)
};
ModelFiles FilesOf(const std::filesystem::path& dir, ModelFormat format);

// Checks every cross-reference (cameras of images and rigs, rigs of frames, frames of images,
// tracks against points2D both ways) and, in the rig layout, sets each image's
// cam_from_world from its frame. Throws InputError naming the offending file and record.
void FinishReconstruction(const ModelFiles& files, Reconstruction* reconstruction);

// The per-file readers and writers of one format; ReadModel and WriteModel do the rest
// (which files exist, their order, the rig layout) the same way for binary and text.
struct ModelFileCodec {
  using Reader = void (*)(const std::filesystem::path&, Reconstruction*);
  using Writer = void (*)(const Reconstruction&, const std::filesystem::path&);
  Reader read_cameras, read_rigs, read_frames, read_images, read_points3D;
  Writer write_cameras, write_images, write_points3D;
  void (*write_rigs)(const std::map<rig_t, Rig>&, const std::filesystem::path&);
  void (*write_frames)(const std::map<frame_t, Frame>&, const std::filesystem::path&);
};
const ModelFileCodec& BinaryCodec();
const ModelFileCodec& TextCodec();

Reconstruction ReadModel(const std::filesystem::path& dir, ModelFormat format, int threads);
// `dir` exists.
void WriteModel(const Reconstruction& reconstruction, const std::filesystem::path& dir,
                ModelFormat format, ModelLayout layout);

// The rigs and frames written for the rig layout: the model's own, or one trivial rig per
// camera and one frame per image when it has none.
void RigsAndFramesToWrite(const Reconstruction& reconstruction, std::map<rig_t, Rig>* rigs,
                          std::map<frame_t, Frame>* frames);

}  // namespace detail
}  // namespace cwloc::colmap
