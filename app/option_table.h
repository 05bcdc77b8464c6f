#pragma once

// The option table (option_table.inc) as data: cwloc-localize makes its flags from it, libcwloc
// its Options fields and cwloc_options_set names, and both check values through it, so every
// surface accepts the same values and refuses the others with the same message.

#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "app/photo_query.h"
#include "app/query_priors.h"
#include "base/option_value.h"
#include "localizer/localizer_options.h"
#include "localizer/tracker.h"

namespace cwloc {

// Everything a localization is told besides its inputs: the pipeline's knobs, how photos
// become features, and whether a photo's EXIF GPS becomes a prior. Defaults are the members'.
struct QueryOptions {
  LocalizerOptions localizer;
  TrackerOptions tracker;  // a sequence's frames
  PhotoOptions photo;
  bool use_exif_gps = false;
  double exif_gps_radius_m = kDefaultExifGpsRadiusM;
};

struct OptionSpec {
  std::string_view flag;  // cwloc-localize's flag without dashes; the C API's name
  std::string_view name;  // api::Options' field; the key in a result record's "parameters"
  std::string_view help;
  ValueRange range;
  size_t type;  // index of the option's type in OptionValue
  OptionValue (*get)(const QueryOptions& options);
  void (*set)(QueryOptions* options, const OptionValue& value);  // of the spec's type, checked
};

// Every option, in the table's order.
std::span<const OptionSpec> OptionTable();

// The option with this flag name (without dashes); throws InputError "unknown option 'NAME'".
const OptionSpec& FindOption(std::string_view flag);

// "--FLAG VALUE: expected ..." unless the value is in the option's range.
void CheckOption(const OptionSpec& spec, const OptionValue& value);

// Text as cwloc-localize takes it ("12", "0.7", "1e3", "true", "cluster-wise"), or a number
// as the C API takes it, as the option's type; throws InputError naming the flag when it is
// not a value of that type or is out of range.
OptionValue ParseOption(const OptionSpec& spec, std::string_view text);
OptionValue OptionFromNumber(const OptionSpec& spec, double number);

// Sets one option, checked; throws InputError naming the flag.
void SetOption(QueryOptions* options, std::string_view flag, const OptionValue& value);

// Checks every option of options (set in code or through the table) and the rules between
// them (CheckOptionRules); throws InputError naming the flags.
void ValidateQueryOptions(const QueryOptions& options);

// The rules between options whose values were checked one by one (CheckOption): RANSAC's
// iteration bounds, what this build can compute (SIFT without VLFeat, a refiner without Ceres).
void CheckOptionRules(const QueryOptions& options);

}  // namespace cwloc
