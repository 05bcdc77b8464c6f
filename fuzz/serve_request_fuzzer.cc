// What cwloc-serve makes of a request's bytes: the first byte picks the part, the rest is its
// content. 'h': a whole HTTP request (Beast's parser at small limits, the query string, a
// multipart body), 'o': the options JSON, 'g': an OSCP GeoPose request, 'f': features (text, or
// binary after "CWLF") with a camera.
#include <cstdint>
#include <string_view>

#include "base/error.h"
#include "serve/geopose_protocol.h"
#include "serve/http_server.h"
#include "serve/query_body.h"
#include "serve/request_inputs.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  cwloc::RequestInputs inputs;
  const cwloc::RequestLimits limits{inputs.options.photo.max_image_pixels};
  try {
    switch (data[0]) {
      case 'h': {
        cwloc::HttpLimits limits_small;
        limits_small.max_header_bytes = 4096;
        limits_small.max_body_bytes = 1 << 16;
        cwloc::ParseRequestBytes(bytes, limits_small);
        break;
      }
      case 'o':
        cwloc::ApplyRequestOptions(bytes, limits, &inputs);
        break;
      case 'g':
        cwloc::ParseGeoPoseRequest(bytes, &inputs);
        break;
      case 'f': {
        cwloc::ApplyRequestOptions(R"({"camera": "SIMPLE_PINHOLE 640 480 500 320 240"})", limits,
                                   &inputs);
        const cwloc::BodyKind kind = cwloc::BodyKindOf("text/plain", bytes);
        cwloc::QueryFromBody(bytes, kind, inputs, "fuzz");
        break;
      }
      default:
        break;
    }
  } catch (const cwloc::InputError&) {
  }
  return 0;
}
