#pragma once

#include <stdexcept>
#include <string>

namespace cwloc {

// Bad input at a trust boundary (a file, a CLI option, a query). The message names
// the file, the field and what was expected; tools print it and exit with code 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace cwloc
