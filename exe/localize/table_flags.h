#pragma once

// The option table's flags on a CLI11 command line (cwloc-localize's, and cwloc-serve's
// defaults for its requests).

#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "app/option_table.h"

namespace cwloc {

// Each value is kept as given and goes through the table once parsing is done, so a tool
// refuses what libcwloc refuses, with the same message.
class TableFlags {
 public:
  void AddTo(CLI::App* app);

  // Every flag given, through the table: ParseOption checks a value, a switch has no range,
  // the defaults are in range (option_table_test), and CheckOptionRules adds the rules between
  // options.
  void Apply(QueryOptions* options) const;

  static constexpr const char* kGroup =
      "Localization (also cwloc::api::Options, cwloc_options_set)";

 private:
  std::vector<std::string> texts_;
  std::unique_ptr<bool[]> switches_;  // CLI11 sets bools, and vector<bool> has none to point at
  std::vector<CLI::Option*> options_;
};

}  // namespace cwloc
