#include "exe/tool_main.h"

#include <exception>
#include <iostream>
#include <new>

#include "base/error.h"

namespace cwloc {

int RunTool(std::string_view tool_name, const std::function<int()>& body) {
  try {
    return body();
  } catch (const InputError& e) {
    std::cerr << tool_name << ": error: " << e.what() << "\n";
    return kExitBadInput;
  } catch (const std::bad_alloc&) {
    std::cerr << tool_name << ": error: out of memory\n";
    return kExitInternalError;
  } catch (const std::exception& e) {
    std::cerr << tool_name << ": internal error: " << e.what() << "\n";
    return kExitInternalError;
  }
}

}  // namespace cwloc
