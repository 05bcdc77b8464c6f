// What a batch names besides its features: a query or image list with its cameras
// (`NAME [MODEL W H PARAMS]`), and the same bytes as a --priors file and a --motion file.
#include <cstdint>

#include "base/error.h"
#include "fuzz/fuzz_file.h"
#include "io/camera_spec.h"
#include "io/motion_file.h"
#include "io/query_list.h"
#include "io/query_priors.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cwloc;
  const auto path = fuzz::WriteFile("list.txt", data, size);
  try {
    for (const QueryListEntry& entry : ReadQueryList(path)) {
      try {
        if (!entry.camera.empty()) ParseCameraSpec(entry.camera, entry.name);
      } catch (const InputError&) {
      }
    }
  } catch (const InputError&) {
  }
  try {
    ReadPriorsFile(path);
  } catch (const InputError&) {
  }
  try {
    ReadMotionFile(path);
  } catch (const InputError&) {
  }
  return 0;
}
