#include "serve/query_body.h"

#include <cstdint>
#include <cstring>
#include <span>

#include "app/feature_file.h"
#include "app/photo_query.h"
#include "base/error.h"
#include "photo/grey_image.h"

namespace cwloc {

BodyKind BodyKindOf(std::string_view content_type, std::string_view bytes) {
  if (bytes.size() >= 4 && std::memcmp(bytes.data(), kFeatureBinaryMagic, 4) == 0)
    return BodyKind::kFeatureBinary;
  if (content_type.substr(0, content_type.find(';')) == "text/plain") return BodyKind::kFeatureText;
  return BodyKind::kPhoto;
}

Query QueryFromBody(std::string_view bytes, BodyKind kind, const RequestInputs& inputs,
                    const std::string& what) {
  const QueryAssembler assembler(inputs.options, inputs.cameras, inputs.priors);
  const std::span<const uint8_t> data(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size());
  if (kind == BodyKind::kPhoto) {
    Query query = PhotoQueryFromBytes(data, what, inputs.name, inputs.options.photo);
    assembler.Complete({inputs.name, QuerySource::Kind::kImage}, &query);
    return query;
  }
  if (!inputs.cameras.camera && !inputs.cameras.image_size) {
    throw InputError(what +
                     ": features need a camera: give options 'camera' (\"MODEL W H PARAMS\") "
                     "or 'image_size' (\"W H\")");
  }
  Query query;
  query.name = inputs.name;
  query.source = what;
  if (kind == BodyKind::kFeatureText) {
    ParseFeatureText(bytes, what, &query);
  } else {
    ParseFeatureBinary(data, what, &query);
  }
  assembler.Complete({inputs.name, QuerySource::Kind::kFeatures}, &query);
  return query;
}

Query QueryFromGreyPixels(std::string_view pixels, uint32_t width, uint32_t height,
                          const RequestInputs& inputs, const std::string& what) {
  if (uint64_t{width} * height > inputs.options.photo.max_image_pixels) {
    throw InputError(what + ": " + std::to_string(uint64_t{width} * height) +
                     " pixels, more than max-image-pixels " +
                     std::to_string(inputs.options.photo.max_image_pixels));
  }
  if (pixels.size() != uint64_t{width} * height)
    throw InputError(what + ": " + std::to_string(pixels.size()) + " bytes for " +
                     std::to_string(width) + " x " + std::to_string(height) + " grey pixels");
  Query query;
  query.name = inputs.name;
  query.source = what;
  query.camera.width = width;  // the image's own size, which a given camera must have
  query.camera.height = height;
  query.camera.calibration = Calibration::kUnknown;
  query.camera.source = IntrinsicsSource::kNone;
  const QueryAssembler assembler(inputs.options, inputs.cameras, inputs.priors);
  assembler.Complete({inputs.name, QuerySource::Kind::kImage}, &query);
  GreyImage image;
  image.width = width;
  image.height = height;
  image.pixels.assign(pixels.begin(), pixels.end());
  ExtractPhotoFeatures(std::move(image), inputs.options.photo, &query);
  return query;
}

}  // namespace cwloc
