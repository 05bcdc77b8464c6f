#include "app/query_list.h"

#include <fstream>
#include <sstream>

#include "base/bounded_file.h"
#include "base/error.h"

namespace cwloc {

std::string RestOfLine(std::istream& fields) {
  std::string rest;
  std::getline(fields, rest);
  rest.erase(0, rest.find_first_not_of(" \t\r"));
  rest.erase(rest.find_last_not_of(" \t\r") + 1);
  return rest;
}

std::vector<QueryListEntry> ReadQueryList(const std::filesystem::path& list) {
  CheckInputFile(list, kQueryListFile);
  std::ifstream in(list);
  if (!in) throw InputError(list.string() + ": cannot open the list");
  std::vector<QueryListEntry> entries;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    QueryListEntry entry;
    if (!(fields >> entry.name) || entry.name[0] == '#') continue;
    entry.camera = RestOfLine(fields);
    entries.push_back(std::move(entry));
  }
  if (in.bad()) throw InputError(list.string() + ": cannot read the list");
  return entries;
}

}  // namespace cwloc
