#pragma once

// A whole COLMAP model in one fuzz input, so that libFuzzer mutates all its files together:
// a flags byte (bit 0: text, else binary; bit 1: the rig layout with rigs and frames), then
// each file as a little-endian uint32 length and that many bytes, in kModelFileStems order.
// A length past the end takes what is left; files past the end are empty.

#include <array>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <vector>

namespace cwloc::fuzz {

inline constexpr std::array<const char*, 5> kModelFileStems = {"cameras", "images", "points3D",
                                                               "rigs", "frames"};
inline constexpr uint8_t kModelText = 1, kModelRigs = 2;

// Writes the model into `dir` (emptied first) and returns it.
inline void UnpackModel(std::span<const uint8_t> input, const std::filesystem::path& dir) {
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  if (input.empty()) return;
  const uint8_t flags = input[0];
  const size_t num_files = (flags & kModelRigs) ? 5 : 3;
  const std::string extension = (flags & kModelText) ? ".txt" : ".bin";
  size_t at = 1;
  for (size_t file = 0; file < num_files; ++file) {
    uint32_t length = 0;
    if (input.size() - at >= 4) {
      std::memcpy(&length, input.data() + at, 4);
      at += 4;
    } else {
      at = input.size();
    }
    const size_t take = std::min<size_t>(length, input.size() - at);
    std::ofstream(dir / (std::string(kModelFileStems[file]) + extension), std::ios::binary)
        .write(reinterpret_cast<const char*>(input.data() + at),
               static_cast<std::streamsize>(take));
    at += take;
  }
}

// The input UnpackModel turns back into the model in `dir` (for the seed corpus).
inline std::vector<uint8_t> PackModel(const std::filesystem::path& dir, uint8_t flags) {
  std::vector<uint8_t> input = {flags};
  const size_t num_files = (flags & kModelRigs) ? 5 : 3;
  const std::string extension = (flags & kModelText) ? ".txt" : ".bin";
  for (size_t file = 0; file < num_files; ++file) {
    std::ifstream in(dir / (std::string(kModelFileStems[file]) + extension), std::ios::binary);
    const std::vector<uint8_t> bytes{std::istreambuf_iterator<char>(in), {}};
    const uint32_t length = static_cast<uint32_t>(bytes.size());
    const auto* length_bytes = reinterpret_cast<const uint8_t*>(&length);
    input.insert(input.end(), length_bytes, length_bytes + 4);
    input.insert(input.end(), bytes.begin(), bytes.end());
  }
  return input;
}

}  // namespace cwloc::fuzz
