#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "localizer/localization_result.h"

namespace cwloc {

// One result as described by schemas/localization-result.schema.json.
nlohmann::ordered_json ResultToJson(const LocalizationResult& result,
                                    const LocalizerOptions& options);

// The record of a query that could not be processed (bad input): name and error only.
nlohmann::ordered_json ErrorToJson(const std::string& name, const std::string& error);

// "NAME QW QX QY QZ TX TY TZ" (the visuallocalization.net submission format).
std::string PoseLine(const LocalizationResult& result);

// The options as JSON (recorded in every result).
nlohmann::ordered_json OptionsToJson(const LocalizerOptions& options);

}  // namespace cwloc
