#pragma once
// Writes PNG test images with libpng, row by row, so a huge one (a decompression bomb) costs no
// memory. Link PNG::PNG.
#include <png.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace cwloc::test {

// A grey PNG whose row y is fill_row(y, &row) (row holds width * bit_depth bits).
template <typename FillRow>
void WriteGreyPngRows(const std::filesystem::path& path, uint32_t width, uint32_t height,
                      int bit_depth, FillRow fill_row) {
  FILE* file = std::fopen(path.c_str(), "wb");
  if (file == nullptr) throw std::runtime_error(path.string() + ": cannot write");
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, file);
  png_set_compression_level(png, 1);
  png_set_filter(png, 0, PNG_FILTER_NONE);
  png_set_IHDR(png, info, width, height, bit_depth, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  std::vector<uint8_t> row((size_t{width} * bit_depth + 7) / 8);
  for (uint32_t y = 0; y < height; ++y) {
    fill_row(y, &row);
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}

// A uniform grey PNG of any size and bit depth (1, 2, 4, 8).
inline void WriteGreyPng(const std::filesystem::path& path, uint32_t width, uint32_t height,
                         uint8_t value, int bit_depth = 8) {
  WriteGreyPngRows(path, width, height, bit_depth, [&](uint32_t, std::vector<uint8_t>* row) {
    std::fill(row->begin(), row->end(), value);
  });
}

// An 8-bit PNG of grey noise: SIFT finds features everywhere, so a large one takes seconds.
inline void WriteNoisePng(const std::filesystem::path& path, uint32_t width, uint32_t height,
                          uint64_t seed) {
  WriteGreyPngRows(path, width, height, 8, [&](uint32_t, std::vector<uint8_t>* row) {
    for (uint8_t& pixel : *row) {
      seed = seed * 6364136223846793005u + 1442695040888963407u;  // an LCG: cheap is all it needs
      pixel = static_cast<uint8_t>(seed >> 56);
    }
  });
}

}  // namespace cwloc::test
