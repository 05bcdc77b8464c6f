#pragma once
// The index of a real data set in ../shared/data (its mapping_model/bin and database.db), built
// with default options but no covariance calibration unless `calibrated` (its ten folds are
// slow under the sanitizers; covariance_calibration_test.cc asks for it), or as a compact
// index of `code_bytes` codes, once per build tree and
// shared by every test process (test::SharedFixture).
#include <Eigen/Core>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "format/index.h"
#include "geo/georeference.h"
#include "indexer/index_builder.h"
#include "tests/test_util.h"

namespace cwloc::test {

struct SharedDataIndex {
  std::filesystem::path data;   // the data set's folder
  std::filesystem::path index;  // its index file
};

// std::nullopt when the data set is not next to the source tree (the caller skips).
inline std::optional<SharedDataIndex> BuildSharedDataIndex(const std::string& name,
                                                           uint32_t code_bytes = 0,
                                                           bool calibrated = false) {
  const auto data = SharedDataDir(name);
  if (!data) return std::nullopt;
  const std::string file = name + (code_bytes ? "_" + std::to_string(code_bytes) : "") +
                           (calibrated ? "_calibrated" : "");
  const auto folder = SharedFixture("data_" + file, [&](const std::filesystem::path& out) {
    IndexBuildOptions options;
    options.model_dir = *data / "mapping_model" / "bin";
    options.database_path = *data / "database.db";
    options.output_path = out / "index.cwl";
    options.code_bytes = code_bytes;
    if (!calibrated) options.calibration_samples = 0;
    BuildIndex(options);
  });
  return SharedDataIndex{*data, folder / "index.cwl"};
}

// A herz_jesu_p25 image's camera centre in Strecha's metric ground-truth frame.
inline Eigen::Vector3d StrechaCenter(const std::filesystem::path& data, const std::string& name) {
  std::ifstream in(data / "strecha_gt_cameras" / (name + ".camera"));
  std::vector<double> values;
  for (double v; in >> v;) values.push_back(v);
  // K (9), distortion (3), R (9), C (3), w h.
  if (values.size() != 26) throw std::runtime_error(name + ": not a Strecha camera file");
  return {values[21], values[22], values[23]};
}

// herz_jesu_p25 on the globe: Strecha's metric ground-truth frame (strecha_gt_cameras/) taken
// as east, north and up of `origin` (the frame is metric; any rigid placement is a valid test).
// Writes a georef file of each model image's Strecha camera centre to `path`, for `index`'s
// images; the fit then finds scale_to_metres.txt's similarity, with its ~2 cm residual.
inline void WriteStrechaGeorefFile(const std::filesystem::path& data, const Index& index,
                                   const Geodetic& origin, const std::filesystem::path& path) {
  Georeference strecha_as_enu;
  strecha_as_enu.origin = origin;
  const GeoFrame strecha(strecha_as_enu);
  std::ofstream out(path);
  for (const IndexImage& image : index.images()) {
    const std::string name(index.ImageName(image));
    const Geodetic g = strecha.EnuToGeodetic(StrechaCenter(data, name));
    char line[256];
    std::snprintf(line, sizeof(line), "%s %.12f %.12f %.6f\n", name.c_str(), g.latitude_deg,
                  g.longitude_deg, g.height_m);
    out << line;
  }
}

}  // namespace cwloc::test
