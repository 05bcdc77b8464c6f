// A query photo's bytes: JPEG and PNG decoding to grey and the EXIF focal length and GPS
// (cwloc-localize --image). Photos above a megapixel are refused from their header, as
// --max-image-pixels does, to keep each run short; SIFT is not run (it sees only pixels).
#include <cstdint>
#include <span>

#include "base/error.h"
#include "photo/exif.h"
#include "photo/image_decode.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cwloc;
  const std::span<const uint8_t> bytes(data, size);
  uint32_t width = 640, height = 480;
  try {
    const GreyImage image = DecodeGreyImage(bytes, "fuzz photo", 1'000'000);
    width = image.width;
    height = image.height;
  } catch (const InputError&) {
  }
  ReadExifFocal(bytes, width, height);
  ReadExifGps(bytes);
  return 0;
}
