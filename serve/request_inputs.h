#pragma once

// What one request says besides its photo or features: the `options` part of /v1/localize, a
// session's options and a frame's (docs/serve.md, "Options").

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "app/option_table.h"
#include "app/query_assembly.h"
#include "localizer/tracker.h"

namespace cwloc {

struct RequestInputs {
  QueryOptions options;  // the server's defaults, then the request's
  CameraInputs cameras;
  PriorInputs priors;
  std::string name = "query";         // the record's name
  std::optional<double> timestamp;    // a session frame's time, seconds
  std::optional<FrameMotion> motion;  // a session frame's motion since the previous frame
};

// What a request's options may not raise: the server's own values.
struct RequestLimits {
  uint64_t max_image_pixels = 0;
};

// Options text is small; a larger part is refused before it is parsed.
inline constexpr size_t kMaxOptionsBytes = 64 << 10;

// Applies a JSON object whose keys are the option table's flags (as cwloc_options_set takes
// them: "max-features", "nb") with a number, a string as the CLI takes it, or true/false; and
// camera ("MODEL W H PARAMS"), image_size ("W H"), focal (px, a prior), unknown_focal,
// prior_position ("LAT LON [HEIGHT] RADIUS_M" or its numbers), prior_gravity ("GX GY GZ" or
// its numbers), name, and for a session's frame timestamp (seconds) and motion ("QW QX QY QZ
// TX TY TZ [SIGMA_ROT_DEG SIGMA_POS]" or its numbers, as --motion's lines). Then checks the
// options as cwloc-localize does, and the limits. Throws InputError "options: ..." naming the
// key and the problem.
void ApplyRequestOptions(std::string_view json_text, const RequestLimits& limits,
                         RequestInputs* inputs);

}  // namespace cwloc
