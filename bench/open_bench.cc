// cwloc-open-bench: how long Index::Open takes (mmap + header, table and section checks),
// the cost a device pays before its first query. Prints the median over repeated opens.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "base/error.h"
#include "base/stopwatch.h"
#include "format/index.h"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: cwloc-open-bench INDEX [REPETITIONS]\n");
    return 2;
  }
  const int repetitions = argc > 2 ? std::max(1, std::atoi(argv[2])) : 200;
  std::vector<double> ms;
  size_t views = 0;
  try {
    for (int i = 0; i < repetitions; ++i) {
      const cwloc::Stopwatch stopwatch;
      const cwloc::Index index = cwloc::Index::Open(argv[1]);
      ms.push_back(stopwatch.Seconds() * 1e3);
      views = index.num_views();
    }
  } catch (const cwloc::InputError& e) {
    std::fprintf(stderr, "cwloc-open-bench: error: %s\n", e.what());
    return 2;
  }
  std::sort(ms.begin(), ms.end());
  std::printf(
      "| index | views | opens | median ms | p90 ms | max ms |\n|---|---|---|---|---|---|\n");
  std::printf("| %s | %zu | %d | %.4f | %.4f | %.4f |\n", argv[1], views, repetitions,
              ms[ms.size() / 2], ms[ms.size() * 9 / 10], ms.back());
  return 0;
}
