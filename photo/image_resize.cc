#include "photo/image_resize.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace cwloc {
namespace {

// The source samples and normalised weights of each output sample along one axis.
struct Contributions {
  std::vector<uint32_t> first;  // first source index per output index
  std::vector<uint32_t> count;  // number of source samples
  std::vector<double> weights;  // window-sized rows
  uint32_t window = 0;
};

Contributions TentWeights(uint32_t source_size, uint32_t output_size) {
  const double scale = double(output_size) / double(source_size);
  // The tent has radius 1 in output pixels: 1 / scale source pixels when shrinking.
  const double radius = scale < 1.0 ? 1.0 / scale : 1.0;
  const double filter_scale = scale < 1.0 ? scale : 1.0;
  Contributions c;
  c.window = 2 * static_cast<uint32_t>(std::ceil(radius)) + 1;
  c.first.resize(output_size);
  c.count.resize(output_size);
  c.weights.assign(size_t{output_size} * c.window, 0.0);
  for (uint32_t u = 0; u < output_size; ++u) {
    const double center = double(u) / scale + 0.5 / scale;
    const int left = std::max(0, static_cast<int>(center - radius + 0.5));
    int right = std::min(static_cast<int>(center + radius + 0.5), static_cast<int>(source_size));
    double* w = &c.weights[size_t{u} * c.window];
    double total = 0.0;
    for (int s = left; s < right; ++s) {
      const double x = std::abs(filter_scale * (double(s) + 0.5 - center));
      const double weight = filter_scale * (x < 1.0 ? 1.0 - x : 0.0);
      w[s - left] = weight;
      total += weight;
    }
    if (total > 0.0 && total != 1.0) {
      for (int s = left; s < right; ++s) w[s - left] /= total;
    }
    // Trailing zero weights are dropped, as FreeImage does.
    while (right > left && w[right - left - 1] == 0.0) --right;
    c.first[u] = static_cast<uint32_t>(left);
    c.count[u] = static_cast<uint32_t>(right - left);
  }
  return c;
}

inline uint8_t RoundToByte(double value) {
  return static_cast<uint8_t>(std::clamp(static_cast<int>(value + 0.5), 0, 255));
}

// Rows y .. y + kRows - 1 of `image` resized along x into `out` (as wide as the weights say):
// the rows share each output column's weights, and every pixel sums its terms in order.
template <int kRows>
void ResizeRowsAlongX(const GreyImage& image, const Contributions& c, uint32_t y, GreyImage* out) {
  const size_t stride = image.width, width = out->width;
  const uint8_t* in = &image.pixels[y * stride];
  uint8_t* rows = &out->pixels[y * width];
  for (size_t x = 0; x < width; ++x) {
    const double* w = &c.weights[x * c.window];
    const uint8_t* p = in + c.first[x];
    double sums[kRows] = {};
    for (uint32_t i = 0; i < c.count[x]; ++i) {
      for (int r = 0; r < kRows; ++r) sums[r] += w[i] * double(p[r * stride + i]);
    }
    for (int r = 0; r < kRows; ++r) rows[r * width + x] = RoundToByte(sums[r]);
  }
}

}  // namespace

ImageSize ExtractionSize(uint32_t width, uint32_t height, uint32_t max_image_size) {
  if (width <= max_image_size && height <= max_image_size) return {width, height};
  const double scale = double(max_image_size) / double(std::max(width, height));
  return {static_cast<uint32_t>(width * scale), static_cast<uint32_t>(height * scale)};
}

GreyImage ResizeBilinear(const GreyImage& image, uint32_t width, uint32_t height) {
  GreyImage rows_done;  // width x image.height
  if (width == image.width) {
    rows_done = image;
  } else {
    const Contributions c = TentWeights(image.width, width);
    rows_done.width = width;
    rows_done.height = image.height;
    rows_done.pixels.resize(size_t{width} * image.height);
    uint32_t y = 0;
    for (; y + 4 <= image.height; y += 4) ResizeRowsAlongX<4>(image, c, y, &rows_done);
    for (; y < image.height; ++y) ResizeRowsAlongX<1>(image, c, y, &rows_done);
  }
  if (height == image.height) return rows_done;
  GreyImage out;
  out.width = width;
  out.height = height;
  out.pixels.resize(size_t{width} * height);
  const Contributions c = TentWeights(image.height, height);
  // Bottom-up row indices, as FreeImage addresses scanlines. Each output row accumulates its
  // source rows in FreeImage's order, so every pixel sums the same terms the same way.
  std::vector<double> sums(width);
  for (uint32_t v = 0; v < height; ++v) {
    const double* w = &c.weights[size_t{v} * c.window];
    std::fill(sums.begin(), sums.end(), 0.0);
    for (uint32_t i = 0; i < c.count[v]; ++i) {
      const uint32_t source_row = image.height - 1 - (c.first[v] + i);
      const uint8_t* in = &rows_done.pixels[size_t{source_row} * width];
      for (uint32_t x = 0; x < width; ++x) sums[x] += w[i] * double(in[x]);
    }
    uint8_t* row = &out.pixels[size_t{height - 1 - v} * width];
    for (uint32_t x = 0; x < width; ++x) row[x] = RoundToByte(sums[x]);
  }
  return out;
}

}  // namespace cwloc
