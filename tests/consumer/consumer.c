/* A tiny C app: the same as consumer.cpp through the C API. The features come from the C++
 * API's reader in consumer.cpp; here they are parsed with stdio to stay in C.
 * Usage: consumer_c INDEX FEATURES MODEL WIDTH HEIGHT PARAMS... */
#include <cwloc/cwloc.h>
#include <stdio.h>
#include <stdlib.h>

/* COLMAP's text feature file: "N 128", then "X Y SCALE ORIENTATION D1..D128" lines. */
static int read_features(const char* path, float** keypoints, uint8_t** descriptors,
                         uint32_t* n) {
  FILE* file = fopen(path, "r");
  unsigned count = 0, dim = 0;
  if (file == NULL || fscanf(file, "%u %u", &count, &dim) != 2 || dim != 128) return 0;
  *keypoints = malloc(sizeof(float) * 2 * count);
  *descriptors = malloc(128 * (size_t)count);
  for (unsigned i = 0; i < count; ++i) {
    float scale, orientation;
    if (fscanf(file, "%f %f %f %f", &(*keypoints)[2 * i], &(*keypoints)[2 * i + 1], &scale,
               &orientation) != 4)
      return 0;
    for (unsigned j = 0; j < 128; ++j) {
      unsigned value;
      if (fscanf(file, "%u", &value) != 1) return 0;
      (*descriptors)[128 * i + j] = (uint8_t)value;
    }
  }
  fclose(file);
  *n = count;
  return 1;
}

int main(int argc, char** argv) {
  if (argc < 7) {
    fprintf(stderr, "usage: consumer_c INDEX FEATURES MODEL WIDTH HEIGHT PARAMS...\n");
    return 2;
  }
  float* keypoints = NULL;
  uint8_t* descriptors = NULL;
  uint32_t n = 0;
  if (!read_features(argv[2], &keypoints, &descriptors, &n)) {
    fprintf(stderr, "%s: cannot read the features\n", argv[2]);
    return 2;
  }
  double params[16];
  size_t num_params = 0;
  for (int i = 6; i < argc && num_params < 16; ++i) params[num_params++] = atof(argv[i]);
  const cwloc_camera camera = {argv[3], (uint32_t)atoi(argv[4]), (uint32_t)atoi(argv[5]),
                               params, num_params, CWLOC_CALIBRATION_KNOWN};

  cwloc_localizer* localizer = NULL;
  cwloc_result* result = NULL;
  if (cwloc_localizer_open(argv[1], 0, &localizer) != CWLOC_OK ||
      cwloc_localize_features(localizer, keypoints, descriptors, n, &camera, NULL, &result) !=
          CWLOC_OK) {
    fprintf(stderr, "error: %s\n", cwloc_last_error());
    return 2;
  }
  int status = 0;
  if (cwloc_result_success(result)) {
    double center[3], inliers = 0;
    cwloc_result_values(result, "center", center, 3, NULL);
    cwloc_result_value(result, "num_inliers", &inliers);
    printf("center %.17g %.17g %.17g inliers %u\n", center[0], center[1], center[2],
           (unsigned)inliers);
    /* The fields of a geo pose, by their paths; absent unless the index is georeferenced. */
    static const char* const kGeo[] = {"geo.latitude_deg", "geo.longitude_deg", "geo.height_m",
                                       "geo.heading_deg",  "geo.pitch_deg",     "geo.roll_deg"};
    double geo[6];
    int georeferenced = 1;
    for (int i = 0; i < 6 && georeferenced; ++i)
      georeferenced = cwloc_result_value(result, kGeo[i], &geo[i]) == CWLOC_OK;
    if (georeferenced) {
      printf("geo %.17g %.17g %.17g heading %.17g pitch %.17g roll %.17g\n", geo[0], geo[1],
             geo[2], geo[3], geo[4], geo[5]);
    }
  } else {
    const char* reason = "";
    cwloc_result_text(result, "failure_reason", &reason);
    printf("not localized: %s\n", reason);
    status = 1;
  }
  cwloc_result_destroy(result);
  cwloc_localizer_close(localizer);
  free(keypoints);
  free(descriptors);
  return status;
}
