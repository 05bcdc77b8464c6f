#include "photo/image_decode.h"

#include <jerror.h>
#include <jpeglib.h>
#include <png.h>
#include <strings.h>

#include <csetjmp>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include "base/bounded_file.h"
#include "base/error.h"

namespace cwloc {
namespace {

void CheckSize(const std::filesystem::path& path, uint64_t width, uint64_t height,
               uint64_t max_pixels) {
  const std::string file = path.string();
  if (width < kMinImageSide || height < kMinImageSide) {
    throw InputError(file + ": the image is " + std::to_string(width) + " x " +
                     std::to_string(height) + " pixels; SIFT needs at least " +
                     std::to_string(kMinImageSide) + " x " + std::to_string(kMinImageSide));
  }
  if (width * height > max_pixels) {
    throw InputError(file + ": the image is " + std::to_string(width) + " x " +
                     std::to_string(height) + " pixels, more than the limit of " +
                     std::to_string(max_pixels) + " (--max-image-pixels)");
  }
}

// libjpeg reports errors through a callback that must not return: it longjmps back to
// DecodeJpeg with the message. Corrupt-data warnings (a truncated file) count as errors.
struct JpegErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void JpegErrorExit(j_common_ptr info) {
  auto* manager = reinterpret_cast<JpegErrorManager*>(info->err);
  (*info->err->format_message)(info, manager->message);
  std::longjmp(manager->jump, 1);
}

void JpegEmitMessage(j_common_ptr info, int level) {
  if (level < 0) JpegErrorExit(info);  // a warning: corrupt or truncated data
}

GreyImage DecodeJpeg(std::span<const uint8_t> bytes, const std::filesystem::path& path,
                     uint64_t max_pixels) {
  jpeg_decompress_struct info;
  JpegErrorManager errors;
  info.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = JpegErrorExit;
  errors.base.emit_message = JpegEmitMessage;
  errors.message[0] = '\0';
  GreyImage image;
  std::vector<uint8_t> row;
  // Filled before any longjmp can happen and only read after the jump: no volatile needed
  // for the objects above, whose addresses do not change.
  if (setjmp(errors.jump)) {
    const bool out_of_memory = errors.base.msg_code == JERR_OUT_OF_MEMORY;
    jpeg_destroy_decompress(&info);
    if (out_of_memory) throw std::bad_alloc();
    throw InputError(path.string() + ": corrupt JPEG: " + errors.message);
  }
  jpeg_create_decompress(&info);
  jpeg_mem_src(&info, bytes.data(), static_cast<unsigned long>(bytes.size()));
  jpeg_read_header(&info, TRUE);
  if (info.jpeg_color_space == JCS_CMYK || info.jpeg_color_space == JCS_YCCK) {
    jpeg_destroy_decompress(&info);
    throw InputError(path.string() + ": CMYK JPEGs are not supported; convert it to RGB");
  }
  const bool grey = info.jpeg_color_space == JCS_GRAYSCALE;
  info.out_color_space = grey ? JCS_GRAYSCALE : JCS_RGB;
  info.dct_method = JDCT_IFAST;
  info.do_fancy_upsampling = FALSE;
  // The size check can throw: it runs outside libjpeg, so clean up first.
  try {
    CheckSize(path, info.image_width, info.image_height, max_pixels);
  } catch (...) {
    jpeg_destroy_decompress(&info);
    throw;
  }
  jpeg_start_decompress(&info);
  image.width = info.output_width;
  image.height = info.output_height;
  try {
    image.pixels.resize(size_t{image.width} * image.height);
    row.resize(size_t{image.width} * info.output_components);
  } catch (...) {
    jpeg_destroy_decompress(&info);
    throw;
  }
  while (info.output_scanline < info.output_height) {
    uint8_t* out = image.pixels.data() + size_t{info.output_scanline} * image.width;
    JSAMPROW rows[1] = {grey ? out : row.data()};
    jpeg_read_scanlines(&info, rows, 1);
    if (!grey) {
      for (uint32_t x = 0; x < image.width; ++x)
        out[x] = Luma709(row[3 * x], row[3 * x + 1], row[3 * x + 2]);
    }
  }
  jpeg_finish_decompress(&info);
  jpeg_destroy_decompress(&info);
  return image;
}

struct PngReader {
  std::span<const uint8_t> bytes;
  size_t offset = 0;
  char message[256] = {};
};

void PngRead(png_structp png, png_bytep out, png_size_t length) {
  auto* reader = static_cast<PngReader*>(png_get_io_ptr(png));
  if (length > reader->bytes.size() - reader->offset) png_error(png, "the file is truncated");
  std::memcpy(out, reader->bytes.data() + reader->offset, length);
  reader->offset += length;
}

void PngError(png_structp png, png_const_charp message) {
  auto* reader = static_cast<PngReader*>(png_get_error_ptr(png));
  std::snprintf(reader->message, sizeof(reader->message), "%s", message);
  png_longjmp(png, 1);
}

void PngWarning(png_structp, png_const_charp) {}

GreyImage DecodePng(std::span<const uint8_t> bytes, const std::filesystem::path& path,
                    uint64_t max_pixels) {
  PngReader reader{bytes};
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &reader, PngError, PngWarning);
  if (png == nullptr) throw std::bad_alloc();
  png_infop info = png_create_info_struct(png);
  if (info == nullptr) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw std::bad_alloc();
  }
  GreyImage image;
  std::vector<uint8_t> expanded;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    // png_malloc's failure, in the words of libpng 1.6 ("memory") and older ("Memory").
    if (strcasecmp(reader.message, "Out of memory") == 0) throw std::bad_alloc();
    throw InputError(path.string() + ": corrupt PNG: " + reader.message);
  }
  png_set_read_fn(png, &reader, PngRead);
  // libpng's own limit is 1e6 x 1e6; ours is checked below, before any pixel buffer exists.
  png_set_user_limits(png, 0x7fffffff, 0x7fffffff);
  png_read_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info);
  const png_uint_32 height = png_get_image_height(png, info);
  try {
    CheckSize(path, width, height, max_pixels);
  } catch (...) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw;
  }
  const int color_type = png_get_color_type(png, info);
  // FreeImage's conversions: 16-bit keeps the high byte, palettes and low-bit grey expand to
  // 8 bits, alpha (and tRNS transparency) is ignored.
  png_set_strip_16(png);
  if (color_type == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
  if (color_type == PNG_COLOR_TYPE_GRAY) png_set_expand_gray_1_2_4_to_8(png);
  if (color_type & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
  png_set_interlace_handling(png);
  png_read_update_info(png, info);
  const int channels = png_get_channels(png, info);
  image.width = width;
  image.height = height;
  // Whole rows of the expanded image (interlaced files need them all), then grey.
  try {
    image.pixels.resize(size_t{width} * height);
    expanded.resize(size_t{width} * height * channels);
    rows.resize(height);
  } catch (...) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw;
  }
  for (png_uint_32 y = 0; y < height; ++y) rows[y] = expanded.data() + size_t{y} * width * channels;
  png_read_image(png, rows.data());
  for (size_t i = 0; i < image.pixels.size(); ++i) {
    const uint8_t* p = expanded.data() + i * channels;
    image.pixels[i] = channels >= 3 ? Luma709(p[0], p[1], p[2]) : p[0];
  }
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return image;
}

}  // namespace

std::vector<uint8_t> ReadPhotoFile(const std::filesystem::path& path) {
  return ReadFileBounded(path, kPhotoFile);
}

GreyImage DecodeGreyImage(std::span<const uint8_t> bytes, const std::filesystem::path& path,
                          uint64_t max_pixels) {
  static constexpr uint8_t kPngSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  if (bytes.empty()) throw InputError(path.string() + ": the file is empty");
  if (bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF)
    return DecodeJpeg(bytes, path, max_pixels);
  if (bytes.size() >= 8 && std::memcmp(bytes.data(), kPngSignature, 8) == 0)
    return DecodePng(bytes, path, max_pixels);
  throw InputError(path.string() + ": not a JPEG or PNG image");
}

}  // namespace cwloc
