#pragma once

#include <filesystem>

#include "indexer/colmap/reconstruction.h"

namespace cwloc::colmap {

enum class ModelFormat { kBinary, kText };
enum class ModelLayout {
  kClassic,  // cameras, images, points3D (COLMAP <= 3.11; Debian's colmap 3.8)
  kRigs,     // plus rigs and frames (COLMAP >= 3.12)
};

// Reads a sparse model directory. Picks binary when cameras.bin exists, text when
// cameras.txt does, and the rig layout when rigs.* and frames.* are present.
// Throws InputError naming the file, the record and the field on any malformed input.
Reconstruction ReadReconstruction(const std::filesystem::path& dir);
Reconstruction ReadReconstructionBinary(const std::filesystem::path& dir);
Reconstruction ReadReconstructionText(const std::filesystem::path& dir);

// Writes a model COLMAP reads back. With kRigs, a model without rigs and frames gets one
// trivial rig per camera and one frame per image, as COLMAP does when it upgrades a model.
void WriteReconstruction(const Reconstruction& reconstruction, const std::filesystem::path& dir,
                         ModelFormat format, ModelLayout layout = ModelLayout::kClassic);

}  // namespace cwloc::colmap
