#ifndef CWLOC_CWLOC_H_
#define CWLOC_CWLOC_H_

/* cwloc's C API: the C++ API of cwloc.hpp behind opaque handles, for C, Swift, Kotlin/JNI and
 * Python ctypes. Every function that can fail returns a cwloc_status; on failure
 * cwloc_last_error() gives the message (per thread, valid until that thread's next call).
 * A query that does not localize is no failure: its result says success 0 and why.
 * One cwloc_localizer may be used by many threads at once; results and options belong to the
 * thread that uses them. docs/api.md has a complete example. */

#include <stddef.h>
#include <stdint.h>

#if defined(__GNUC__)
#define CWLOC_C_API __attribute__((visibility("default")))
#else
#define CWLOC_C_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cwloc_status {
  CWLOC_OK = 0,
  CWLOC_ERROR_INVALID_ARGUMENT = 1, /* a bad argument, option or camera */
  CWLOC_ERROR_BAD_INPUT = 2,        /* a file or buffer that cannot be used */
  CWLOC_ERROR_OUT_OF_MEMORY = 3,
  CWLOC_ERROR_INTERNAL = 4, /* a bug: please report it */
  /* C only (C++ has std::optional): a result has no such value, e.g. no geo pose because the
   * index is not georeferenced or the query was not localized; cwloc_last_error() says which */
  CWLOC_ERROR_NOT_AVAILABLE = 5
} cwloc_status;

typedef enum cwloc_calibration {
  CWLOC_CALIBRATION_KNOWN = 0,       /* every parameter is held fixed */
  CWLOC_CALIBRATION_FOCAL_PRIOR = 1, /* the focal length is a guess, refined */
  CWLOC_CALIBRATION_UNKNOWN = 2      /* only the image size; the focal length is estimated */
} cwloc_calibration;

/* A camera in COLMAP's terms (see cwloc.hpp's Camera). */
typedef struct cwloc_camera {
  const char* model; /* "SIMPLE_RADIAL", ...; may be NULL for CWLOC_CALIBRATION_UNKNOWN */
  uint32_t width;
  uint32_t height;
  const double* params; /* COLMAP's order */
  size_t num_params;
  cwloc_calibration calibration;
} cwloc_camera;

/* A GPS fix (see cwloc.hpp's PositionPrior): the query was taken within radius_m of this WGS84
 * position; height_m above the ellipsoid, NaN when unknown (then the radius is horizontal). */
typedef struct cwloc_position_prior {
  double latitude_deg, longitude_deg, height_m, radius_m;
} cwloc_position_prior;

/* What an index holds (see cwloc.hpp's IndexInfo). The strings live as long as the localizer.
 * The origin is that of the ENU frame of cwloc_geo_pose.enu; 0 unless georeferenced. */
typedef struct cwloc_index_info {
  const char* path;
  const char* format_version; /* "MAJOR.MINOR" */
  uint32_t num_images, num_points, num_views;
  int georeferenced; /* 1: results have geo poses and queries may have priors */
  double origin_latitude_deg, origin_longitude_deg, origin_height_m;
} cwloc_index_info;

/* A camera's motion since the previous frame (VIO), as the C++ Motion: the frame's camera from
 * the previous frame's camera, rotation w, x, y, z and translation in metres, and its standard
 * deviations per axis in degrees and metres (0: not known). */
typedef struct cwloc_motion {
  double rotation_wxyz[4];
  double translation[3];
  double sigma_rotation_deg;
  double sigma_position;
} cwloc_motion;

/* One image of a multi-image query (a rig's frame, a VIO window; the C++ RigImage): its features
 * (keypoints, descriptors, num_features) or, when photo_path is not NULL, a JPEG or PNG file;
 * its camera (needed with features; a photo without one takes its EXIF focal length as a
 * prior); and COLMAP's cam_from_rig (X_cam = R(rotation) X_rig + translation). The first image
 * is the reference camera. */
typedef struct cwloc_rig_image {
  const char* name;
  const float* keypoints;
  const uint8_t* descriptors;
  uint32_t num_features;
  const char* photo_path;
  const cwloc_camera* camera;
  double cam_from_rig_rotation_wxyz[4];
  double cam_from_rig_translation[3];
} cwloc_rig_image;

typedef struct cwloc_localizer cwloc_localizer;
typedef struct cwloc_options cwloc_options;
typedef struct cwloc_result cwloc_result;
typedef struct cwloc_tracker cwloc_tracker;

CWLOC_C_API const char* cwloc_version(void);
CWLOC_C_API const char* cwloc_last_error(void);

/* Writes (atomically) the index that a delta of `cwloc-index update --delta` makes of the
 * index it was made for, bit for bit (docs/format.md, "Deltas"); CWLOC_ERROR_BAD_INPUT and
 * nothing written for a delta made for another index, or a damaged file. threads: 0 = all. */
CWLOC_C_API cwloc_status cwloc_index_apply(const char* index_path, const char* delta_path,
                                           const char* output_path, int threads);

/* Opens an index file read-only (verify != 0: also check every checksum). */
CWLOC_C_API cwloc_status cwloc_localizer_open(const char* index_path, int verify,
                                              cwloc_localizer** out);
CWLOC_C_API void cwloc_localizer_close(cwloc_localizer* localizer);
CWLOC_C_API cwloc_status cwloc_localizer_info(const cwloc_localizer* localizer,
                                              cwloc_index_info* info);

/* Options with cwloc-localize's defaults; NULL options anywhere below means the defaults. */
CWLOC_C_API cwloc_status cwloc_options_create(cwloc_options** out);
CWLOC_C_API void cwloc_options_destroy(cwloc_options* options);
/* Sets an option by its cwloc-localize flag name without dashes (every line of
 * <cwloc/options.inc>: "k", "checks", "nb", "refine", ...), from a number (a switch takes 1 or
 * 0) or, with _text, from text as cwloc-localize takes it ("cluster-wise", "0.7", "true").
 * An unknown name or a value out of range is CWLOC_ERROR_INVALID_ARGUMENT, with the message
 * cwloc-localize gives ("--nb 0: expected at least 1"); rules between options are checked
 * when a query runs. */
CWLOC_C_API cwloc_status cwloc_options_set(cwloc_options* options, const char* name, double value);
CWLOC_C_API cwloc_status cwloc_options_set_text(cwloc_options* options, const char* name,
                                                const char* value);
/* cwloc_options_set_text(options, "matcher", matcher). */
CWLOC_C_API cwloc_status cwloc_options_set_matcher(cwloc_options* options, const char* matcher);
/* Priors for every query (a georeferenced index only; docs/geo.md); NULL removes one. The
 * position prior wins over a photo's EXIF GPS ("use-exif-gps"). gravity_xyz is the direction
 * gravity pulls in the camera frame (x right, y down, z forward): at rest, the accelerometer's
 * reading negated. Values are checked when a query runs. */
CWLOC_C_API cwloc_status cwloc_options_set_position_prior(cwloc_options* options,
                                                          const cwloc_position_prior* prior);
CWLOC_C_API cwloc_status cwloc_options_set_gravity(cwloc_options* options,
                                                   const double gravity_xyz[3]);

/* Queries. camera may be NULL for photos (EXIF focal prior, else estimated). Keypoints are
 * x, y pairs in COLMAP's pixel convention; descriptors num_features x 128 bytes. */
CWLOC_C_API cwloc_status cwloc_localize_features(const cwloc_localizer* localizer,
                                                 const float* keypoints, const uint8_t* descriptors,
                                                 uint32_t num_features, const cwloc_camera* camera,
                                                 const cwloc_options* options, cwloc_result** out);
CWLOC_C_API cwloc_status cwloc_localize_photo(const cwloc_localizer* localizer, const char* path,
                                              const cwloc_camera* camera,
                                              const cwloc_options* options, cwloc_result** out);
CWLOC_C_API cwloc_status cwloc_localize_encoded_photo(const cwloc_localizer* localizer,
                                                      const uint8_t* bytes, size_t size,
                                                      const cwloc_camera* camera,
                                                      const cwloc_options* options,
                                                      cwloc_result** out);
CWLOC_C_API cwloc_status cwloc_localize_grey_image(
    const cwloc_localizer* localizer, const uint8_t* pixels, uint32_t width, uint32_t height,
    size_t stride, const cwloc_camera* camera, const cwloc_options* options, cwloc_result** out);

/* Several images localized as one generalized camera (cwloc-localize --frames); unknown_scale
 * 1: the cam_from_rig translations are known up to one scale, which is estimated. name: the
 * frame's, may be NULL ("frame"). The result's fields are a rig frame's (cwloc.hpp's
 * RigResult): "rig.num_inliers", "images.0.pose.rotation", ... */
CWLOC_C_API cwloc_status cwloc_localize_rig(const cwloc_localizer* localizer,
                                            const cwloc_rig_image* images, size_t num_images,
                                            int unknown_scale, const char* name,
                                            const cwloc_options* options, cwloc_result** out);

/* A tracker: the frames of one moving camera, in order (cwloc-localize --sequence), with the
 * options given here (NULL: the defaults). Each frame is tracked from the frames before it,
 * localized from scratch when that fails, or lost (no pose). One tracker per stream, its calls
 * one at a time; trackers of one localizer may run on several threads; the localizer must
 * outlive them. Reset forgets the frames so far. */
CWLOC_C_API cwloc_status cwloc_tracker_create(const cwloc_localizer* localizer,
                                              const cwloc_options* options, cwloc_tracker** out);
CWLOC_C_API void cwloc_tracker_destroy(cwloc_tracker* tracker);
CWLOC_C_API cwloc_status cwloc_tracker_reset(cwloc_tracker* tracker);
/* timestamp: when the frame was seen, seconds (any origin; as the C++ Tracker::Track takes it);
 * it and motion may be NULL (the device does not know them). */
CWLOC_C_API cwloc_status cwloc_track_features(cwloc_tracker* tracker, const float* keypoints,
                                              const uint8_t* descriptors, uint32_t num_features,
                                              const cwloc_camera* camera, const double* timestamp,
                                              const cwloc_motion* motion, cwloc_result** out);
CWLOC_C_API cwloc_status cwloc_track_photo(cwloc_tracker* tracker, const char* path,
                                           const cwloc_camera* camera, const double* timestamp,
                                           const cwloc_motion* motion, cwloc_result** out);
CWLOC_C_API cwloc_status cwloc_track_grey_image(cwloc_tracker* tracker, const uint8_t* pixels,
                                                uint32_t width, uint32_t height, size_t stride,
                                                const cwloc_camera* camera, const double* timestamp,
                                                const cwloc_motion* motion, cwloc_result** out);

/* Results: read with these accessors, then destroy. A field is named by its path: the names of
 * <cwloc/localization_result.h> (a rig frame's: <cwloc/rig_result.h>), where each field is
 * described once, joined by dots, a list's item by its index: "num_inliers", "rotation",
 * "camera.params", "covariance.position_radius95", "tracking.mode", "ranked_images.0.name",
 * "priors.position.clusters_in_radius". An unknown path is CWLOC_ERROR_INVALID_ARGUMENT; a value
 * the result does not have (no covariance on failure, no tracking for a query localized alone)
 * is CWLOC_ERROR_NOT_AVAILABLE; cwloc_last_error() says which. Pointers they return live as long
 * as the result. */
CWLOC_C_API void cwloc_result_destroy(cwloc_result* result);
/* 1 when localized (the field "success"), else 0; 0 for NULL. */
CWLOC_C_API int cwloc_result_success(const cwloc_result* result);
/* A number: an integer or real field, a switch (1 or 0), an enum's index ("tracking.mode": 0
 * tracked, 1 relocalized, 2 lost, in the order of cwloc.hpp's enums). */
CWLOC_C_API cwloc_status cwloc_result_value(const cwloc_result* result, const char* path,
                                            double* value);
/* Text: a string field or an enum's name ("name", "failure_reason", "tracking.mode":
 * "tracked"). */
CWLOC_C_API cwloc_status cwloc_result_text(const cwloc_result* result, const char* path,
                                           const char** text);
/* A list of numbers ("rotation": w, x, y, z; "camera.params"; "covariance.pose": 36, row-major):
 * *count gets its length, values (NULL to ask the length only) its numbers;
 * CWLOC_ERROR_INVALID_ARGUMENT when capacity is smaller than the length. */
CWLOC_C_API cwloc_status cwloc_result_values(const cwloc_result* result, const char* path,
                                             double* values, size_t capacity, size_t* count);
/* The length of a list ("ranked_images", "inliers", "images", "camera.params"). */
CWLOC_C_API cwloc_status cwloc_result_size(const cwloc_result* result, const char* path,
                                           size_t* size);
/* The JSON record cwloc-localize writes for this query (schemas/localization-result.schema.json).
 */
CWLOC_C_API const char* cwloc_result_json(const cwloc_result* result);

#ifdef __cplusplus
}
#endif

#endif /* CWLOC_CWLOC_H_ */
