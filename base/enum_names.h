#pragma once

#include <array>
#include <cstddef>
#include <optional>
#include <string_view>

namespace cwloc {

// The enum value whose name, in a table in enum order (the CLI's and the JSON's spelling), is
// `name`; nullopt for none.
template <typename Enum, size_t N>
std::optional<Enum> ParseEnumName(const std::array<std::string_view, N>& names,
                                  std::string_view name) {
  for (size_t i = 0; i < N; ++i) {
    if (names[i] == name) return static_cast<Enum>(i);
  }
  return std::nullopt;
}

}  // namespace cwloc
