// Writes the colmap_model fuzzer's seeds for one model: binary and text, classic and with rigs
// and frames (COLMAP's upgrade of a classic model), each packed as fuzz/model_container.h says.
//   make_model_seeds MODEL_DIR OUT_DIR
#include <cstdio>
#include <fstream>

#include "colmap/reconstruction_io.h"
#include "fuzz/model_container.h"

int main(int argc, char** argv) {
  using namespace cwloc;
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_model_seeds MODEL_DIR OUT_DIR\n");
    return 2;
  }
  const colmap::Reconstruction model = colmap::ReadReconstruction(argv[1]);
  const std::filesystem::path out = argv[2];
  const auto scratch = std::filesystem::temp_directory_path() / "cwloc-model-seeds";
  for (const uint8_t flags : {0, 1, 2, 3}) {
    std::filesystem::remove_all(scratch);
    std::filesystem::create_directories(scratch);
    colmap::WriteReconstruction(
        model, scratch,
        (flags & fuzz::kModelText) ? colmap::ModelFormat::kText : colmap::ModelFormat::kBinary,
        (flags & fuzz::kModelRigs) ? colmap::ModelLayout::kRigs : colmap::ModelLayout::kClassic);
    const std::vector<uint8_t> input = fuzz::PackModel(scratch, flags);
    static const char* names[] = {"binary", "text", "binary-rigs", "text-rigs"};
    std::ofstream(out / (std::string("model-") + names[flags]), std::ios::binary)
        .write(reinterpret_cast<const char*>(input.data()),
               static_cast<std::streamsize>(input.size()));
  }
  std::filesystem::remove_all(scratch);
  return 0;
}
