#pragma once

#include <string>
#include <vector>

#include "localizer/query.h"

namespace cwloc {

// "MODEL WIDTH HEIGHT PARAMS..." as in COLMAP's cameras.txt (e.g. "SIMPLE_RADIAL 1536 1024
// 1375.8 768 512 -0.0008"): a fully known camera. Throws InputError naming `what` (the
// option or file it came from) for an unknown model, a wrong parameter count or bad numbers.
QueryCamera ParseCameraSpec(const std::string& spec, const std::string& what);

// The same camera from its parts (the library API's input), checked the same way.
QueryCamera MakeKnownCamera(const std::string& model_name, uint32_t width, uint32_t height,
                            std::vector<double> params, const std::string& what);

// "WIDTH HEIGHT" (or "WIDTHxHEIGHT"): only the image size is known; the focal is estimated.
QueryCamera ParseImageSize(const std::string& spec, const std::string& what);

// The same from the numbers (the library API's input), checked the same way; no source set.
QueryCamera ImageSizeCamera(uint32_t width, uint32_t height, const std::string& what);

// A camera with an unknown focal length built from a known camera's image size.
QueryCamera WithUnknownFocal(const QueryCamera& camera);

}  // namespace cwloc
