#pragma once

#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

namespace cwloc {

// "8,16,32" -> {8, 16, 32}: a tool option's list of whole numbers (empty items skipped).
inline std::vector<uint32_t> ParseCommaList(const std::string& text) {
  std::vector<uint32_t> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) {
    if (!item.empty()) out.push_back(static_cast<uint32_t>(std::stoul(item)));
  }
  return out;
}

}  // namespace cwloc
