#pragma once

#include <cstddef>  // before grey_image.h, which uses size_t without it
#include <cstdint>
#include <vector>

#include "photo/grey_image.h"

namespace cwloc {

// SIFT extraction as COLMAP 3.8's CPU extractor (ExtractSiftFeaturesCPU, VLFeat 0.9.20/21)
// does it. Every default is the default of COLMAP 3.8's SiftExtractionOptions, so features
// extracted with default options match the ones in a COLMAP-built database (docs/sift.md).
struct SiftOptions {
  // Keep coarse DoG levels until their keypoint count (before orientations) exceeds this;
  // the level that crosses the cap is kept whole, so the result can exceed it.
  int max_num_features = 8192;
  // First octave of the pyramid; -1 upsamples the image by 2 first. Below -1 only in builds
  // with VLFeat, which runs those (docs/sift.md).
  int first_octave = -1;
  int num_octaves = 4;
  int octave_resolution = 3;  // DoG levels per octave
  // DoG peak threshold (image intensities in [0, 1]); COLMAP's 0.02 / octave_resolution.
  double peak_threshold = 0.02 / 3;
  double edge_threshold = 10.0;  // max ratio of principal curvatures
  // Of VLFeat's up to 4 orientations per keypoint (in histogram-bin order, not by
  // strength), keep the first this many.
  int max_num_orientations = 2;
  bool upright = false;  // orientation 0 for every keypoint
  enum class Normalization {
    kL1Root,  // L1-normalize, then element-wise square root (RootSIFT); COLMAP's default
    kL2,      // L2-normalize
  };
  Normalization normalization = Normalization::kL1Root;

  // Not COLMAP options: how we compute, never what.
  enum class Implementation {
    // Ours: VLFeat's algorithm in VLFeat's arithmetic, several times faster (docs/sift.md).
    kCwloc,
    // VLFeat's vl_sift_* called exactly as COLMAP 3.8 calls them (the reference); only in
    // builds with VLFeat (SiftVlfeatAvailable()).
    kVlfeat,
  };
  Implementation implementation = Implementation::kCwloc;
  // Threads inside one photo (>= 1); results do not depend on it.
  int num_threads = 1;
};

// COLMAP's keypoint convention: the centre of the top-left pixel is (0.5, 0.5); scale is
// VLFeat's sigma in pixels, orientation in radians (VLFeat's angle, image y down).
struct SiftKeypoint {
  float x = 0, y = 0, scale = 0, orientation = 0;
};

inline constexpr int kSiftDescriptorDim = 128;

struct SiftFeatures {
  std::vector<SiftKeypoint> keypoints;
  // keypoints.size() x 128, row-major, in COLMAP's (UBC) element order: for each 4x4
  // spatial cell (row-major), 8 orientation bins. Normalized as options.normalization says,
  // then round(512 * v) clamped to [0, 255].
  std::vector<uint8_t> descriptors;

  size_t size() const { return keypoints.size(); }
  const uint8_t* Descriptor(size_t i) const { return descriptors.data() + i * kSiftDescriptorDim; }
};

// Whether this build has VLFeat (cmake -DCWLOC_WITH_VLFEAT=ON): Implementation::kVlfeat and
// first_octave < -1 need it.
bool SiftVlfeatAvailable();

// Throws std::invalid_argument naming the option when one is out of range or needs VLFeat in
// a build without it.
void ValidateSiftOptions(const SiftOptions& options);

// Extracts SIFT features from `image` (coordinates in its pixel frame). Throws
// std::invalid_argument on bad options or an empty image. Thread-safe: photos may be
// extracted concurrently.
SiftFeatures ExtractSift(const GreyImage& image, const SiftOptions& options = {});

}  // namespace cwloc
