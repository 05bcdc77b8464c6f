// What a batch names besides its features: a query or image list with its cameras
// (`NAME [MODEL W H PARAMS]`), and the same bytes as a --priors file and a --motion file.
#include <cstdint>

#include "app/camera_spec.h"
#include "app/motion_file.h"
#include "app/query_list.h"
#include "app/query_priors.h"
#include "base/error.h"
#include "fuzz/fuzz_file.h"

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
