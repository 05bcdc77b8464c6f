#pragma once

// A request's photo or features as a query (docs/serve.md, "Bodies").

#include <cstdint>
#include <string>
#include <string_view>

#include "localizer/query.h"
#include "serve/request_inputs.h"

namespace cwloc {

enum class BodyKind {
  kPhoto,          // JPEG or PNG: its bytes decide
  kFeatureText,    // COLMAP's text feature file (text/plain)
  kFeatureBinary,  // the "CWLF" layout (app/feature_file.h)
};

// By the part's or body's Content-Type: text/plain is text features; bytes that start with
// "CWLF" are binary features; anything else is a photo.
BodyKind BodyKindOf(std::string_view content_type, std::string_view bytes);

// The query of a body or part (`what` names it in errors), with the request's camera and
// priors as cwloc-localize gives them. Features need options.camera or options.image_size.
// Throws InputError naming `what` and the problem.
Query QueryFromBody(std::string_view bytes, BodyKind kind, const RequestInputs& inputs,
                    const std::string& what);

// The same for width x height 8-bit grey pixels, row after row (the GeoPose protocol's GRAY8).
Query QueryFromGreyPixels(std::string_view pixels, uint32_t width, uint32_t height,
                          const RequestInputs& inputs, const std::string& what);

}  // namespace cwloc
