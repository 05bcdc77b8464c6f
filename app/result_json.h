#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "app/option_table.h"
#include "results/localization_result.h"
#include "results/rig_result.h"
#include "solvers/camera_pose.h"

namespace cwloc {

// One result as described by schemas/localization-result.schema.json: its fields
// (results/localization_result.h) and the options it was made with.
nlohmann::ordered_json ResultToJson(const LocalizationResult& result, const QueryOptions& options);

// The record of a query that could not be processed (bad input): name and error only.
nlohmann::ordered_json ErrorToJson(const std::string& name, const std::string& error);

// A rig frame's record (the schema's rig_frame): its fields (results/rig_result.h) and options.
nlohmann::ordered_json RigResultToJson(const RigResult& result, const QueryOptions& options);

// "NAME QW QX QY QZ TX TY TZ" (the visuallocalization.net submission format).
std::string PoseLine(const LocalizationResult& result);
std::string PoseLine(const std::string& name, const Transform& cam_from_world);

// Every option of the table by its name (OptionSpec::name), as a result records them.
nlohmann::ordered_json OptionsToJson(const QueryOptions& options);

}  // namespace cwloc
