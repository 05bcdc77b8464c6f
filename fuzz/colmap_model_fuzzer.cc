// A COLMAP sparse model as cwloc-index reads it: binary or text, classic or with rigs and
// frames, every cross-reference checked (fuzz/model_container.h packs the files).
#include <cstdint>

#include "base/error.h"
#include "colmap/reconstruction_io.h"
#include "fuzz/fuzz_file.h"
#include "fuzz/model_container.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const auto dir = cwloc::fuzz::ProcessFolder() / "model";
  cwloc::fuzz::UnpackModel({data, size}, dir);
  try {
    cwloc::colmap::ReadReconstruction(dir);
  } catch (const cwloc::InputError&) {
  }
  return 0;
}
