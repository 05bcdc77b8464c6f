// A COLMAP database.db as cwloc-index and cwloc-localize --database read it: the schema,
// cameras, images, keypoints and descriptors of every image, and each image as a query.
#include <algorithm>
#include <cstdint>

#include "app/database/database_queries.h"
#include "base/error.h"
#include "colmap/database.h"
#include "fuzz/fuzz_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cwloc;
  const auto path = fuzz::WriteFile("database.db", data, size);
  try {
    const colmap::DatabaseReader reader(path);
    reader.ReadAllCameras();
    reader.ReadPriorFocalLengths();
    const std::vector<colmap::DatabaseImage> images = reader.ReadAllImages();
    const DatabaseQueries queries(path);
    // A mutated file may claim many images; a few are enough to reach every reader.
    for (size_t i = 0; i < std::min<size_t>(images.size(), 8); ++i) {
      try {
        reader.ReadFeatures(images[i].image_id);
        queries.Load(images[i].name);
      } catch (const InputError&) {
      }
    }
  } catch (const InputError&) {
  }
  return 0;
}
