#pragma once
// Writes PNG test images with libpng, row by row, so a huge one (a decompression bomb) costs no
// memory. Link PNG::PNG.
#include <png.h>

#include <cstdio>
#include <filesystem>
#include <stdexcept>
#include <vector>

namespace cwloc::test {

// A uniform grey PNG of any size and bit depth (1, 2, 4, 8).
inline void WriteGreyPng(const std::filesystem::path& path, uint32_t width, uint32_t height,
                         uint8_t value, int bit_depth = 8) {
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
  const std::vector<uint8_t> row((size_t{width} * bit_depth + 7) / 8, value);
  for (uint32_t y = 0; y < height; ++y) png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(file);
}

}  // namespace cwloc::test
