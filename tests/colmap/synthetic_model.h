#pragma once

#include <cstdint>
#include <vector>

#include "camera/camera_models.h"
#include "colmap/reconstruction.h"

namespace cwloc::test {

struct SyntheticModelOptions {
  int num_cameras = 3;
  int num_images = 12;
  int num_points3D = 300;
  int min_track_length = 2;
  int max_track_length = 6;
  // Extra points2D per image that observe no 3D point (most keypoints in a real model).
  int num_unobserved_points2D = 10;
  // Models given to cameras in turn; empty means every model COLMAP knows.
  std::vector<CameraModelId> camera_models;
  // The rig layout (COLMAP >= 3.12): cameras in rigs of two (the second with a
  // sensor_from_rig), an uncalibrated IMU in the first rig, and images grouped into frames.
  // Image poses are sensor_from_rig * rig_from_world, computed like the readers do.
  bool with_rigs = false;
  // Ids with gaps, as after COLMAP deletes images and points, and one point id above 2^32, to
  // catch id/index mix-ups and 32-bit truncation.
  bool sparse_ids = true;
};

// A random but consistent COLMAP model drawn from cwloc::test::Rng(): cameras on a sphere
// looking at a cloud of points, points2D that are the projections (with 0.3 px noise) of
// their 3D points through each camera's model, tracks that match the points2D exactly,
// occasionally two observations of one point in the same image (COLMAP has those).
// Stored quaternions have a squared norm of exactly 1.0 in double arithmetic, so a program
// that re-normalizes them (COLMAP 3.8 does on every read) keeps them bit for bit.
colmap::Reconstruction SyntheticModel(const SyntheticModelOptions& options = {});

// Plausible parameters of `model` for an image of width x height.
std::vector<double> TypicalCameraParams(CameraModelId model, uint64_t width, uint64_t height);

// The models Debian's colmap 3.8 knows (ids 0..10).
std::vector<CameraModelId> Colmap38CameraModels();

}  // namespace cwloc::test
