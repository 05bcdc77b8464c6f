#include "photo/sift/sift_extractor.h"

#include <stdexcept>
#include <string>

#include "photo/sift/sift_cwloc.h"
#ifdef CWLOC_WITH_VLFEAT
#include "photo/sift/sift_vlfeat.h"
#endif

namespace cwloc {
namespace {

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("SIFT option " + what);
}

SiftFeatures ExtractWithVlfeat(const GreyImage& image, const SiftOptions& options) {
#ifdef CWLOC_WITH_VLFEAT
  return sift_internal::ExtractSiftVlfeat(image, options);
#else
  throw std::logic_error("SIFT: no VLFeat in this build");  // ValidateSiftOptions rejects it
#endif
}

}  // namespace

bool SiftVlfeatAvailable() {
#ifdef CWLOC_WITH_VLFEAT
  return true;
#else
  return false;
#endif
}

void ValidateSiftOptions(const SiftOptions& options) {
  Require(options.max_num_features > 0, "max_num_features must be > 0");
  Require(options.first_octave >= -3 && options.first_octave <= 8,
          "first_octave must be in [-3, 8]");
  Require(options.num_octaves > 0 && options.num_octaves <= 16, "num_octaves must be in [1, 16]");
  Require(options.octave_resolution > 0 && options.octave_resolution <= 100,
          "octave_resolution must be in [1, 100]");
  Require(options.peak_threshold > 0, "peak_threshold must be > 0");
  Require(options.edge_threshold > 0, "edge_threshold must be > 0");
  Require(options.max_num_orientations > 0, "max_num_orientations must be > 0");
  Require(options.num_threads > 0, "num_threads must be > 0");
  if (!SiftVlfeatAvailable()) {
    constexpr const char* kRebuild = " in a build without VLFeat (cmake -DCWLOC_WITH_VLFEAT=ON)";
    Require(options.implementation != SiftOptions::Implementation::kVlfeat,
            std::string("implementation kVlfeat (VLFeat itself) is not available") + kRebuild);
    Require(options.first_octave >= -1,
            std::string("first_octave must be >= -1 (below, VLFeat runs)") + kRebuild);
  }
}

SiftFeatures ExtractSift(const GreyImage& image, const SiftOptions& options) {
  ValidateSiftOptions(options);
  if (image.width == 0 || image.height == 0) {
    throw std::invalid_argument("SIFT: empty image");
  }
  if (image.pixels.size() != size_t{image.width} * image.height) {
    throw std::invalid_argument(
        "SIFT: image has " + std::to_string(image.pixels.size()) +
        " pixels, not width * height = " + std::to_string(size_t{image.width} * image.height));
  }
  // VLFeat indexes the upsampled octave with int.
  const double scale = options.first_octave < 0 ? double(1 << (-options.first_octave)) : 1.0;
  if (double(image.width) * image.height * scale * scale > 1.5e9) {
    throw std::invalid_argument("SIFT: image too large");
  }
  switch (options.implementation) {
    case SiftOptions::Implementation::kCwloc:
      // VLFeat upsamples a second time with width and height swapped (its
      // copy_and_upsample_rows calls for o < -1), which only COLMAP's features of square
      // images survive; reproducing it is not worth it: VLFeat itself runs those.
      if (options.first_octave < -1) return ExtractWithVlfeat(image, options);
      return sift_internal::ExtractSiftCwloc(image, options);
    case SiftOptions::Implementation::kVlfeat:
      return ExtractWithVlfeat(image, options);
  }
  throw std::invalid_argument("SIFT: unknown implementation");
}

}  // namespace cwloc
