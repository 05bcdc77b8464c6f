#include "tests/colmap/text_records.h"

#include <algorithm>
#include <fstream>

namespace cwloc::test {

std::vector<std::string> SortedRecords(const std::filesystem::path& path, int lines_per_record) {
  std::ifstream in(path);
  std::vector<std::string> records;
  std::string line, record;
  int n = 0;
  while (std::getline(in, line)) {
    if (n == 0 && !line.empty() && line[0] == '#') continue;
    record += line + '\n';
    if (++n == lines_per_record) {
      records.push_back(record);
      record.clear();
      n = 0;
    }
  }
  std::sort(records.begin(), records.end());
  return records;
}

}  // namespace cwloc::test
