#pragma once

#include <filesystem>
#include <string>
#include <vector>

namespace cwloc::test {

// A text model file as a sorted list of records (lines_per_record lines each, comments
// dropped): COLMAP 3.8 writes records in hash-map order, we write them sorted by id.
std::vector<std::string> SortedRecords(const std::filesystem::path& path, int lines_per_record);

}  // namespace cwloc::test
