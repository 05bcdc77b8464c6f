// A tiny C++ app: localize one COLMAP feature file with a known camera and print the pose, and
// the camera on the globe when the index is georeferenced.
// Usage: consumer_cpp INDEX FEATURES MODEL WIDTH HEIGHT PARAMS...
#include <cwloc/cwloc.hpp>
#include <cstdio>
#include <cstdlib>

int main(int argc, char** argv) {
  if (argc < 7) {
    std::fprintf(stderr, "usage: consumer_cpp INDEX FEATURES MODEL WIDTH HEIGHT PARAMS...\n");
    return 2;
  }
  try {
    const cwloc::api::Localizer localizer = cwloc::api::Localizer::Open(argv[1]);
    cwloc::api::Camera camera;
    camera.model = argv[3];
    camera.width = static_cast<uint32_t>(std::atoi(argv[4]));
    camera.height = static_cast<uint32_t>(std::atoi(argv[5]));
    for (int i = 6; i < argc; ++i) camera.params.push_back(std::atof(argv[i]));
    const cwloc::api::Result result =
        localizer.Localize(cwloc::api::ReadFeatureFile(argv[2]), camera);
    if (!result.success) {
      std::printf("not localized: %s\n", result.failure_reason.c_str());
      return 1;
    }
    std::printf("center %.17g %.17g %.17g inliers %u\n", result.center[0], result.center[1],
                result.center[2], result.num_inliers);
    if (localizer.Info().georeferenced && result.geo) {
      const cwloc::api::GeoPose& geo = *result.geo;
      std::printf("geo %.17g %.17g %.17g heading %.17g pitch %.17g roll %.17g\n", geo.latitude_deg,
                  geo.longitude_deg, geo.height_m, geo.heading_deg, geo.pitch_deg, geo.roll_deg);
    }
    return 0;
  } catch (const cwloc::api::Error& e) {
    std::fprintf(stderr, "error %d: %s\n", static_cast<int>(e.code()), e.what());
    return 2;
  }
}
