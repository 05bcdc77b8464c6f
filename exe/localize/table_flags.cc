#include "exe/localize/table_flags.h"

#include <span>
#include <string_view>
#include <variant>

#include "base/option_value.h"

namespace cwloc {
namespace {

std::string TypeName(const OptionSpec& spec, const OptionValue& value) {
  if (!spec.range.names.empty()) {
    std::string names;
    for (std::string_view name : spec.range.names)
      names += (names.empty() ? "" : "|") + std::string(name);
    return "{" + names + "}";
  }
  if (std::holds_alternative<double>(value)) return "FLOAT";
  return std::holds_alternative<int32_t>(value) ? "INT" : "UINT";
}

}  // namespace

void TableFlags::AddTo(CLI::App* app) {
  const QueryOptions defaults;
  const std::span<const OptionSpec> table = OptionTable();
  texts_.resize(table.size());
  switches_ = std::make_unique<bool[]>(table.size());
  for (size_t i = 0; i < table.size(); ++i) {
    const OptionSpec& spec = table[i];
    const OptionValue value = spec.get(defaults);
    const std::string flag = "--" + std::string(spec.flag);
    CLI::Option* option = nullptr;
    if (const bool* on = std::get_if<bool>(&value)) {
      switches_[i] = *on;
      // A switch that is on by default is turned off by --no-NAME.
      const std::string names = *on ? flag + ",!--no-" + std::string(spec.flag) : flag;
      option = app->add_flag(names, switches_[i], std::string(spec.help));
    } else {
      option = app->add_option(flag, texts_[i], std::string(spec.help))
                   ->default_str(FormatOptionValue(value))
                   ->type_name(TypeName(spec, value));
    }
    option->group(kGroup);
    options_.push_back(option);
  }
}

void TableFlags::Apply(QueryOptions* options) const {
  const std::span<const OptionSpec> table = OptionTable();
  for (size_t i = 0; i < table.size(); ++i) {
    if (options_[i]->count() == 0) continue;
    const OptionSpec& spec = table[i];
    const bool is_switch = spec.type == OptionValue(false).index();
    spec.set(options, is_switch ? OptionValue(switches_[i]) : ParseOption(spec, texts_[i]));
  }
  CheckOptionRules(*options);
}

}  // namespace cwloc
