#pragma once

#include "photo/sift/sift_extractor.h"

namespace cwloc::sift_internal {

// SiftOptions::Implementation::kVlfeat: VLFeat called exactly as COLMAP 3.8 calls it.
SiftFeatures ExtractSiftVlfeat(const GreyImage& image, const SiftOptions& options);

}  // namespace cwloc::sift_internal
