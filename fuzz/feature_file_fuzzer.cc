// A query's COLMAP text feature file (cwloc-localize --features / --query-list).
#include <cstdint>

#include "app/feature_file.h"
#include "base/error.h"
#include "fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  cwloc::Query query;
  try {
    cwloc::ReadFeatureFile(cwloc::fuzz::WriteFile("features.txt", data, size), &query);
  } catch (const cwloc::InputError&) {
  }
  return 0;
}
