// A georef file (cwloc-index build --georef) and the fit over what it holds: the model camera
// centres are the positions in a fixed frame, with a name-dependent error so that some
// observations are outliers, and the fitted frame is used once.
#include <cstdint>
#include <functional>
#include <vector>

#include "base/error.h"
#include "fuzz/fuzz_file.h"
#include "geo/georeference_fit.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace cwloc;
  try {
    const std::vector<GeoObservation> observations =
        ReadGeorefFile(fuzz::WriteFile("georef.txt", data, size));
    const GeoFrame truth(Georeference{
        observations.front().position, 0.5, Eigen::Quaterniond(0.5, 0.5, -0.5, 0.5), {}});
    std::vector<Eigen::Vector3d> centers;
    for (const GeoObservation& observation : observations) {
      const double error = double(std::hash<std::string>{}(observation.image_name) % 64);
      centers.push_back(truth.GeodeticToModel(observation.position) + Eigen::Vector3d(error, 0, 0));
    }
    const GeoFitResult fit = FitGeoreference(centers, observations);
    GeoFrame(fit.georeference).ModelToGeodetic(centers.front());
  } catch (const InputError&) {
  }
  return 0;
}
