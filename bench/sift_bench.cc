// cwloc-sift-bench: decode + SIFT-extract each photo on one thread, as COLMAP's
// feature_extractor does, and print per-photo times (bench/extraction_benchmark.sh).
//
//   cwloc-sift-bench [--implementation vlfeat|fast] [--repeat N] [--max-num-features N] PHOTO...
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "base/stopwatch.h"
#include "photo/sift/sift_extractor.h"
#include "tests/support/sift_agreement_util.h"

using namespace cwloc;
using sift_bench::ImplementationNames;
using sift_bench::ParseImplementation;

int main(int argc, char** argv) {
  CLI::App app{"Times decoding + SIFT extraction per photo"};
  std::vector<std::filesystem::path> photos;
  std::string implementation = "cwloc";
  int repeat = 1;
  SiftOptions options;
  options.max_num_features = 6000;
  app.add_option("--implementation", implementation)->check(CLI::IsMember(ImplementationNames()));
  app.add_option("--repeat", repeat, "runs per photo; the median is printed");
  app.add_option("--max-num-features", options.max_num_features);
  app.add_option("--first-octave", options.first_octave);
  app.add_option("--threads", options.num_threads, "threads inside one photo");
  app.add_option("photos", photos)->required();
  CLI11_PARSE(app, argc, argv);
  options.implementation = ParseImplementation(implementation);
  std::printf("photo\tfeatures\tdecode_ms\textract_ms\ttotal_ms\n");
  for (const auto& photo : photos) {
    std::vector<double> decode_ms, extract_ms, total_ms;
    size_t n = 0;
    for (int r = 0; r < std::max(1, repeat); ++r) {
      const Stopwatch total;
      const GreyImage image = sift_bench::DecodeJpegLikeColmap(photo);
      decode_ms.push_back(total.Seconds() * 1e3);
      const Stopwatch extract;
      n = ExtractSift(image, options).size();
      extract_ms.push_back(extract.Seconds() * 1e3);
      total_ms.push_back(total.Seconds() * 1e3);
    }
    auto median = [](std::vector<double> v) {
      std::sort(v.begin(), v.end());
      return v[v.size() / 2];
    };
    std::printf("%s\t%zu\t%.1f\t%.1f\t%.1f\n", photo.filename().c_str(), n, median(decode_ms),
                median(extract_ms), median(total_ms));
    std::fflush(stdout);
  }
  return 0;
}
