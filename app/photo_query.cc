#include "app/photo_query.h"

#include <stdexcept>

#include "base/error.h"
#include "base/stopwatch.h"
#include "photo/exif.h"

namespace cwloc {

Query LoadPhotoQuery(const std::filesystem::path& path, const std::string& name,
                     const PhotoOptions& options) {
  const Stopwatch time;
  Query query = PhotoQueryFromBytes(ReadPhotoFile(path), path.string(), name, options);
  query.extraction_seconds = time.Seconds();
  return query;
}

Query PhotoQueryFromBytes(std::span<const uint8_t> bytes, const std::string& source,
                          const std::string& name, const PhotoOptions& options) {
  const Stopwatch time;
  GreyImage image = DecodeGreyImage(bytes, source, options.max_image_pixels);
  const uint32_t width = image.width;
  const uint32_t height = image.height;

  Query query;
  query.name = name;
  query.source = source;
  if (const auto exif = ReadExifFocal(bytes, width, height)) {
    query.camera = FocalPriorCamera(exif->focal_length_px, width, height, IntrinsicsSource::kExif);
  } else {
    query.camera = UnknownFocalCamera(width, height, IntrinsicsSource::kNone);
  }
  ExtractPhotoFeatures(std::move(image), options, &query);
  if (const auto gps = ReadExifGps(bytes))
    query.exif_gps = GpsFix{gps->latitude_deg, gps->longitude_deg};
  query.extraction_seconds = time.Seconds();
  return query;
}

void ExtractPhotoFeatures(GreyImage image, const PhotoOptions& options, Query* query) {
  const Stopwatch time;
  const uint32_t width = image.width;
  const uint32_t height = image.height;
  const ImageSize size = ExtractionSize(width, height, options.max_image_size);
  if (size.width != width || size.height != height)
    image = ResizeBilinear(image, size.width, size.height);
  const SiftFeatures features = ExtractSift(image, options.sift);
  // COLMAP scales keypoints back in single precision (FeatureKeypoint::Rescale).
  const float scale_x = static_cast<float>(double(width) / double(size.width));
  const float scale_y = static_cast<float>(double(height) / double(size.height));
  query->keypoints.clear();
  query->keypoints.reserve(features.keypoints.size() * 2);
  for (const SiftKeypoint& keypoint : features.keypoints) {
    query->keypoints.push_back(keypoint.x * scale_x);
    query->keypoints.push_back(keypoint.y * scale_y);
  }
  query->descriptors = features.descriptors;
  if (query->NumFeatures() == 0)
    throw InputError(query->Source() + ": no SIFT features found in the photo");
  query->photo = PhotoInfo{size.width, size.height, options.sift.first_octave,
                           uint32_t(options.sift.max_num_features)};
  query->extraction_seconds = time.Seconds();
}

}  // namespace cwloc
