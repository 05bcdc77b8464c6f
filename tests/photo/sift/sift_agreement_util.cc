#include "tests/photo/sift/sift_agreement_util.h"

#include <jpeglib.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <limits>
#include <memory>
#include <numbers>
#include <stdexcept>
#include <unordered_map>

#include "format/colmap/database.h"

namespace cwloc::sift_bench {
namespace {

struct JpegError {
  jpeg_error_mgr mgr;
  std::jmp_buf jump;
  char message[JMSG_LENGTH_MAX];
};

void OnJpegError(j_common_ptr cinfo) {
  auto* error = reinterpret_cast<JpegError*>(cinfo->err);
  (*cinfo->err->format_message)(cinfo, error->message);
  std::longjmp(error->jump, 1);
}

}  // namespace

GreyImage DecodeJpegLikeColmap(const std::filesystem::path& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw std::runtime_error("cannot open " + path.string());
  jpeg_decompress_struct cinfo;
  JpegError error;
  cinfo.err = jpeg_std_error(&error.mgr);
  error.mgr.error_exit = OnJpegError;
  GreyImage image;
  std::vector<uint8_t> row;
  if (setjmp(error.jump)) {
    jpeg_destroy_decompress(&cinfo);
    throw std::runtime_error(path.string() + ": " + error.message);
  }
  jpeg_create_decompress(&cinfo);
  jpeg_stdio_src(&cinfo, file.get());
  jpeg_read_header(&cinfo, TRUE);
  cinfo.dct_method = JDCT_IFAST;
  cinfo.do_fancy_upsampling = FALSE;
  cinfo.out_color_space = cinfo.num_components == 1 ? JCS_GRAYSCALE : JCS_RGB;
  jpeg_start_decompress(&cinfo);
  image.width = cinfo.output_width;
  image.height = cinfo.output_height;
  image.pixels.resize(size_t{image.width} * image.height);
  const int channels = cinfo.output_components;
  row.resize(size_t{image.width} * channels);
  while (cinfo.output_scanline < cinfo.output_height) {
    uint8_t* out = image.pixels.data() + size_t{cinfo.output_scanline} * image.width;
    JSAMPROW rows[1] = {row.data()};
    jpeg_read_scanlines(&cinfo, rows, 1);
    if (channels == 1) {
      std::copy(row.begin(), row.end(), out);
    } else {
      for (uint32_t x = 0; x < image.width; ++x) {
        const uint8_t* p = &row[size_t{x} * 3];
        out[x] = static_cast<uint8_t>(0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2] + 0.5f);
      }
    }
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  return image;
}

SiftFeatures ReadColmapFeatures(const std::filesystem::path& database, const std::string& name) {
  colmap::DatabaseReader reader(database);
  const auto image = reader.FindImage(name);
  if (!image) throw std::runtime_error(database.string() + ": no image " + name);
  const colmap::ImageFeatures read = reader.ReadFeatures(image->image_id);
  SiftFeatures features;
  for (const colmap::Keypoint& k : read.keypoints) {
    features.keypoints.push_back({k.x, k.y, k.Scale(), k.Orientation()});
  }
  features.descriptors = read.descriptors.data;
  return features;
}

namespace {

// Buckets of keypoints on a grid of 1 px cells.
class PointGrid {
 public:
  explicit PointGrid(const std::vector<SiftKeypoint>& keypoints) {
    for (size_t i = 0; i < keypoints.size(); ++i) {
      cells_[Key(Cell(keypoints[i].x), Cell(keypoints[i].y))].push_back(i);
    }
  }
  template <typename Fn>
  void ForNear(float x, float y, Fn&& fn) const {
    const int64_t cx = Cell(x), cy = Cell(y);
    for (int64_t dy = -1; dy <= 1; ++dy) {
      for (int64_t dx = -1; dx <= 1; ++dx) {
        const auto it = cells_.find(Key(cx + dx, cy + dy));
        if (it == cells_.end()) continue;
        for (size_t i : it->second) fn(i);
      }
    }
  }

 private:
  static int64_t Cell(float v) { return static_cast<int64_t>(std::floor(v)); }
  static int64_t Key(int64_t x, int64_t y) { return (x + (1 << 20)) * (int64_t{1} << 22) + y; }
  std::unordered_map<int64_t, std::vector<size_t>> cells_;
};

float DescriptorDistance(const uint8_t* a, const uint8_t* b) {
  int sum = 0;
  for (int i = 0; i < kSiftDescriptorDim; ++i) {
    const int d = int(a[i]) - int(b[i]);
    sum += d * d;
  }
  return std::sqrt(float(sum));
}

double AngleDifferenceDeg(double a, double b) {
  double d = std::fmod(std::abs(a - b), 2 * std::numbers::pi);
  if (d > std::numbers::pi) d = 2 * std::numbers::pi - d;
  return d * 180.0 / std::numbers::pi;
}

// Counts keypoints of `a` found in `b`; optionally records nearest descriptor distances.
size_t CountFound(const SiftFeatures& a, const SiftFeatures& b, const AgreementCriteria& c,
                  std::vector<float>* nearest, size_t* same_position) {
  const PointGrid grid(b.keypoints);
  size_t found = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    const SiftKeypoint& ka = a.keypoints[i];
    float best = std::numeric_limits<float>::infinity();
    bool same = false;
    grid.ForNear(ka.x, ka.y, [&](size_t j) {
      const SiftKeypoint& kb = b.keypoints[j];
      if (ka.x == kb.x && ka.y == kb.y) same = true;
      const double dx = ka.x - kb.x, dy = ka.y - kb.y;
      if (dx * dx + dy * dy > c.max_position_px * c.max_position_px) return;
      if (AngleDifferenceDeg(ka.orientation, kb.orientation) > c.max_orientation_deg) return;
      best = std::min(best, DescriptorDistance(a.Descriptor(i), b.Descriptor(j)));
    });
    if (same && same_position) ++*same_position;
    if (std::isfinite(best)) {
      if (nearest) nearest->push_back(best);
      if (best <= c.max_descriptor_distance) ++found;
    }
  }
  return found;
}

}  // namespace

Agreement CompareFeatures(const SiftFeatures& a, const SiftFeatures& b,
                          const AgreementCriteria& criteria) {
  Agreement result;
  result.num_a = a.size();
  result.num_b = b.size();
  result.a_found_in_b = CountFound(a, b, criteria, &result.nearest_descriptor_distances,
                                   &result.a_same_position_in_b);
  result.b_found_in_a = CountFound(b, a, criteria, nullptr, nullptr);
  return result;
}

}  // namespace cwloc::sift_bench

namespace cwloc::sift_bench {

std::vector<std::string> ImplementationNames() { return {"cwloc", "vlfeat"}; }

SiftOptions::Implementation ParseImplementation(const std::string& name) {
  if (name == "cwloc") return SiftOptions::Implementation::kCwloc;
  if (name == "vlfeat") return SiftOptions::Implementation::kVlfeat;
  throw std::invalid_argument("unknown SIFT implementation " + name);
}

}  // namespace cwloc::sift_bench
