#pragma once

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>

#include "localizer/query.h"
#include "photo/image_decode.h"
#include "photo/image_resize.h"
#include "photo/sift/sift_extractor.h"

namespace cwloc {

// How photos become features; every default is colmap feature_extractor's.
struct PhotoOptions {
  uint32_t max_image_size = kDefaultMaxImageSize;      // --max-image-size
  uint64_t max_image_pixels = kDefaultMaxImagePixels;  // --max-image-pixels
  SiftOptions sift;                                    // its max_num_features: --max-features
};

// Turns a JPEG or PNG into a query as `colmap feature_extractor` would: decoded to grey,
// shrunk to max_image_size, SIFT, keypoints scaled back to the photo's own pixels. Its camera
// has the photo's size and, when the EXIF gives a focal length, that focal as a prior
// (SIMPLE_RADIAL f, w/2, h/2, 0; source exif); otherwise the focal is unknown (source none).
// Throws InputError naming the file for an unreadable or broken photo.
Query LoadPhotoQuery(const std::filesystem::path& path, const std::string& name,
                     const PhotoOptions& options);

// The same from the file's bytes in memory; `source` names them in errors.
Query PhotoQueryFromBytes(std::span<const uint8_t> bytes, const std::string& source,
                          const std::string& name, const PhotoOptions& options);

// The SIFT part for an already decoded grey image: resize to max_image_size, extract, scale
// the keypoints back to the image's own pixels; fills query->keypoints, descriptors and photo.
// Throws InputError naming query->Source() when no feature is found.
void ExtractPhotoFeatures(GreyImage image, const PhotoOptions& options, Query* query);

}  // namespace cwloc
