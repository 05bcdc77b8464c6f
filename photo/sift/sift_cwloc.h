#pragma once

#include "photo/sift/sift_extractor.h"

namespace cwloc::sift_internal {

// SiftOptions::Implementation::kCwloc: our implementation of VLFeat's SIFT (sift_cwloc.cc).
SiftFeatures ExtractSiftCwloc(const GreyImage& image, const SiftOptions& options);

}  // namespace cwloc::sift_internal
