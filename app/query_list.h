#pragma once

#include <filesystem>
#include <istream>
#include <string>
#include <vector>

namespace cwloc {

// One line of a query or image list: `NAME [MODEL W H PARAMS...]`, as hloc's and COLMAP's
// lists write them; `camera` is the rest of the line, trimmed (empty without one).
struct QueryListEntry {
  std::string name;
  std::string camera;
};

// The rest of a line after the fields read so far, without its surrounding blanks (a list
// line's camera, "MODEL W H PARAMS").
std::string RestOfLine(std::istream& fields);

// Every entry of a list file; blank lines and lines starting with '#' are skipped. Throws
// InputError naming the list when it cannot be read, is not a regular file or is over
// kQueryListFile's limit (base/bounded_file.h).
std::vector<QueryListEntry> ReadQueryList(const std::filesystem::path& list);

}  // namespace cwloc
