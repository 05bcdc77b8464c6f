#pragma once

#include <functional>
#include <string_view>

namespace cwloc {

// Exit codes shared by every cwloc tool.
inline constexpr int kExitOk = 0;
inline constexpr int kExitNotLocalized = 1;
inline constexpr int kExitBadInput = 2;
inline constexpr int kExitInternalError = 3;

// Runs a tool's body and turns exceptions into an error line on stderr and an exit code:
// InputError -> 2 ("<tool>: error: <message>"), anything else -> 3 (a bug in cwloc).
int RunTool(std::string_view tool_name, const std::function<int()>& body);

}  // namespace cwloc
