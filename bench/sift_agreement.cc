// cwloc-sift-agreement: how many of COLMAP's SIFT features (a COLMAP database) our extraction
// reproduces on the same photos, and how many of ours COLMAP has (docs/sift.md).
//
//   cwloc-sift-agreement --database DB --images DIR [--max-num-features 6000]
//       [--implementation vlfeat|fast] [--descriptor-threshold 100] [--json FILE] [NAME...]
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "base/stopwatch.h"
#include "photo/sift/sift_extractor.h"
#include "tests/support/sift_agreement_util.h"

namespace fs = std::filesystem;
using namespace cwloc;
using sift_bench::ImplementationNames;
using sift_bench::ParseImplementation;

namespace {

double Percentile(std::vector<float> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, size_t(q * double(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"How many of COLMAP's SIFT features cwloc's extraction reproduces"};
  fs::path database, images_dir, json_path;
  std::vector<std::string> names;
  std::string implementation = "cwloc";
  SiftOptions options;
  options.max_num_features = 6000;
  sift_bench::AgreementCriteria criteria;
  app.add_option("--database", database, "COLMAP database.db")->required();
  app.add_option("--images", images_dir, "folder of the photos")->required();
  app.add_option("--max-num-features", options.max_num_features);
  app.add_option("--implementation", implementation)->check(CLI::IsMember(ImplementationNames()));
  app.add_option("--threads", options.num_threads);
  app.add_option("--descriptor-threshold", criteria.max_descriptor_distance);
  app.add_option("--position-px", criteria.max_position_px);
  app.add_option("--orientation-deg", criteria.max_orientation_deg);
  app.add_option("--json", json_path, "also write the table as JSON");
  app.add_option("names", names, "photo names (default: every .jpg in --images)");
  CLI11_PARSE(app, argc, argv);
  options.implementation = ParseImplementation(implementation);
  if (names.empty()) {
    for (const auto& entry : fs::directory_iterator(images_dir)) {
      if (entry.path().extension() == ".jpg") names.push_back(entry.path().filename().string());
    }
    std::sort(names.begin(), names.end());
  }

  nlohmann::json report = nlohmann::json::array();
  std::printf(
      "| photo | COLMAP | ours | COLMAP found in ours | ours found in COLMAP | desc dist p50 / p90 "
      "/ p99 | same position | extract ms |\n|---|---|---|---|---|---|---|---|\n");
  for (const std::string& name : names) {
    const SiftFeatures colmap = sift_bench::ReadColmapFeatures(database, name);
    const GreyImage image = sift_bench::DecodeJpegLikeColmap(images_dir / name);
    const Stopwatch stopwatch;
    const SiftFeatures ours = ExtractSift(image, options);
    const double ms = stopwatch.Seconds() * 1e3;
    const auto agreement = sift_bench::CompareFeatures(colmap, ours, criteria);
    const auto& d = agreement.nearest_descriptor_distances;
    std::printf("| %s | %zu | %zu | %.2f %% | %.2f %% | %.1f / %.1f / %.1f | %.2f %% | %.0f |\n",
                name.c_str(), agreement.num_a, agreement.num_b, 100 * agreement.ShareAInB(),
                100 * agreement.ShareBInA(), Percentile(d, 0.5), Percentile(d, 0.9),
                Percentile(d, 0.99), 100.0 * agreement.a_same_position_in_b / agreement.num_a, ms);
    std::fflush(stdout);
    report.push_back({{"photo", name},
                      {"colmap", agreement.num_a},
                      {"ours", agreement.num_b},
                      {"colmap_found_in_ours", agreement.ShareAInB()},
                      {"ours_found_in_colmap", agreement.ShareBInA()},
                      {"with_position_orientation_neighbour", d.size()},
                      {"descriptor_distance_p50", Percentile(d, 0.5)},
                      {"descriptor_distance_p90", Percentile(d, 0.9)},
                      {"descriptor_distance_p99", Percentile(d, 0.99)},
                      {"descriptor_distance_p999", Percentile(d, 0.999)},
                      {"descriptor_distance_max", Percentile(d, 1.0)},
                      {"colmap_same_position_in_ours", agreement.a_same_position_in_b},
                      {"extract_ms", ms}});
  }
  if (!json_path.empty()) std::ofstream(json_path) << report.dump(2) << "\n";
  return 0;
}
