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

/* Wall-clock seconds per stage: one field per line of <cwloc/stage_times.inc>. */
typedef struct cwloc_stage_times {
#define CWLOC_STAGE_TIME(name, help) double name;
#include "cwloc/stage_times.inc"
#undef CWLOC_STAGE_TIME
} cwloc_stage_times;

/* A GPS fix (see cwloc.hpp's PositionPrior): the query was taken within radius_m of this WGS84
 * position; height_m above the ellipsoid, NaN when unknown (then the radius is horizontal). */
typedef struct cwloc_position_prior {
  double latitude_deg, longitude_deg, height_m, radius_m;
} cwloc_position_prior;

/* A localized camera on the globe (see cwloc.hpp's GeoPose; docs/geo.md defines the angles). */
typedef struct cwloc_geo_pose {
  double latitude_deg, longitude_deg, height_m; /* WGS84, height above the ellipsoid */
  double enu[3];                                /* metres east, north, up of the index's origin */
  double heading_deg, pitch_deg, roll_deg;
} cwloc_geo_pose;

/* What an index holds (see cwloc.hpp's IndexInfo). The strings live as long as the localizer.
 * The origin is that of the ENU frame of cwloc_geo_pose.enu; 0 unless georeferenced. */
typedef struct cwloc_index_info {
  const char* path;
  const char* format_version; /* "MAJOR.MINOR" */
  uint32_t num_images, num_points, num_views;
  int georeferenced; /* 1: results have geo poses and queries may have priors */
  double origin_latitude_deg, origin_longitude_deg, origin_height_m;
} cwloc_index_info;

/* How a frame of a stream got its pose (a tracker; docs/algorithm.md, "Sequences"). */
typedef enum cwloc_tracking_mode {
  CWLOC_TRACKED = 0,     /* matched near the pose predicted from the frames before it */
  CWLOC_RELOCALIZED = 1, /* localized from scratch: the first frame, or tracking failed */
  CWLOC_LOST = 2         /* neither gave a pose */
} cwloc_tracking_mode;

typedef struct cwloc_tracking {
  cwloc_tracking_mode mode;
  const char* predicted_from; /* the frame the prediction started from; "" without one */
  int has_prediction_error;   /* whether the next two are set */
  double prediction_error;    /* model units between the pose's centre and the prediction's */
  double prediction_error_deg;
  double seconds; /* the tracker's whole time on the frame */
} cwloc_tracking;

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
typedef struct cwloc_rig_result cwloc_rig_result;

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
 * frame's, may be NULL ("frame"). */
CWLOC_C_API cwloc_status cwloc_localize_rig(const cwloc_localizer* localizer,
                                            const cwloc_rig_image* images, size_t num_images,
                                            int unknown_scale, const char* name,
                                            const cwloc_options* options, cwloc_rig_result** out);
CWLOC_C_API void cwloc_rig_result_destroy(cwloc_rig_result* result);
CWLOC_C_API int cwloc_rig_result_success(const cwloc_rig_result* result);
CWLOC_C_API const char* cwloc_rig_result_failure_reason(const cwloc_rig_result* result);
/* rig_from_world (X_rig = R X_world + t), the rig's origin, and the scale (1 unless unknown). */
CWLOC_C_API void cwloc_rig_result_pose(const cwloc_rig_result* result, double rotation_wxyz[4],
                                       double translation[3], double center[3], double* scale);
CWLOC_C_API uint32_t cwloc_rig_result_num_inliers(const cwloc_rig_result* result);
CWLOC_C_API uint32_t cwloc_rig_result_num_images(const cwloc_rig_result* result);
/* Image i's cam_from_world (cam_from_rig * rig_from_world) and the rig's inliers in it;
 * CWLOC_ERROR_NOT_AVAILABLE when the rig was not localized. Any output may be NULL. */
CWLOC_C_API cwloc_status cwloc_rig_result_image_pose(const cwloc_rig_result* result, uint32_t i,
                                                     double rotation_wxyz[4], double translation[3],
                                                     uint32_t* num_inliers);
/* The rig pose's 6 x 6 covariance over (theta, C), row-major, and its 95 % position radius;
 * CWLOC_ERROR_NOT_AVAILABLE when the rig was not localized. Either output may be NULL. */
CWLOC_C_API cwloc_status cwloc_rig_result_covariance(const cwloc_rig_result* result,
                                                     double pose[36], double* position_radius95);
/* The frame's JSON record as cwloc-localize writes it. */
CWLOC_C_API const char* cwloc_rig_result_json(const cwloc_rig_result* result);

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

/* Results: read with these accessors, then destroy. Pointers they return live as long as the
 * result. */
CWLOC_C_API void cwloc_result_destroy(cwloc_result* result);
CWLOC_C_API int cwloc_result_success(const cwloc_result* result);
CWLOC_C_API const char* cwloc_result_failure_reason(const cwloc_result* result); /* "" if ok */
/* COLMAP's cam_from_world: rotation (w, x, y, z), translation; and the camera centre. */
CWLOC_C_API void cwloc_result_pose(const cwloc_result* result, double rotation_wxyz[4],
                                   double translation[3], double center[3]);
/* The camera as used (estimated when it was not known). */
CWLOC_C_API void cwloc_result_camera(const cwloc_result* result, cwloc_camera* camera);
/* A number of the result by its name in <cwloc/result_fields.inc>, which says what each one
 * counts ("num_inliers", "inlier_ratio", "forward_matches", "back_matches", "guided", ...; a
 * switch is 1 or 0). An unknown name is CWLOC_ERROR_INVALID_ARGUMENT. */
CWLOC_C_API cwloc_status cwloc_result_value(const cwloc_result* result, const char* name,
                                            double* value);
CWLOC_C_API uint32_t cwloc_result_num_features(const cwloc_result* result);
CWLOC_C_API uint32_t cwloc_result_num_correspondences(const cwloc_result* result);
CWLOC_C_API uint32_t cwloc_result_num_inliers(const cwloc_result* result);
/* Inlier i < num_inliers: the query feature, its pixel, the index's 3D point and its xyz.
 * Any output pointer may be NULL. */
CWLOC_C_API cwloc_status cwloc_result_inlier(const cwloc_result* result, uint32_t i,
                                             uint32_t* feature, float keypoint[2], uint32_t* point,
                                             double xyz[3]);
CWLOC_C_API uint32_t cwloc_result_num_ranked_images(const cwloc_result* result);
CWLOC_C_API cwloc_status cwloc_result_ranked_image(const cwloc_result* result, uint32_t i,
                                                   uint32_t* image_id, const char** name,
                                                   uint32_t* votes);
CWLOC_C_API void cwloc_result_times(const cwloc_result* result, cwloc_stage_times* times);
/* The camera on the globe; CWLOC_ERROR_NOT_AVAILABLE when the index is not georeferenced or
 * the query was not localized. */
CWLOC_C_API cwloc_status cwloc_result_geo_pose(const cwloc_result* result, cwloc_geo_pose* pose);
/* The position prior the query used (the options' or the photo's EXIF GPS) and how many
 * clusters had a model camera within it; CWLOC_ERROR_NOT_AVAILABLE without one. */
CWLOC_C_API cwloc_status cwloc_result_position_prior(const cwloc_result* result,
                                                     cwloc_position_prior* prior,
                                                     uint32_t* clusters_in_radius);
/* Degrees between the gravity prior and the localized pose's gravity; CWLOC_ERROR_NOT_AVAILABLE
 * without a gravity prior or when the query was not localized. */
CWLOC_C_API cwloc_status cwloc_result_gravity_error(const cwloc_result* result, double* degrees);
/* The pose's 6 x 6 covariance, row-major (the C++ PoseCovariance::pose) and its 95 % position
 * radius, model units; CWLOC_ERROR_NOT_AVAILABLE when the query was not localized. Either output
 * may be NULL. */
CWLOC_C_API cwloc_status cwloc_result_covariance(const cwloc_result* result, double pose[36],
                                                 double* position_radius95);
/* What the index's calibration (cwloc-index build --calibration-samples) multiplied the
 * covariance by: its rotation block by rotation_scale, its centre block by position_scale (the
 * cross terms by the root of both); CWLOC_ERROR_NOT_AVAILABLE when the query was not localized
 * or the index has no calibration for its calibration mode. Either output may be NULL. */
CWLOC_C_API cwloc_status cwloc_result_covariance_calibration(const cwloc_result* result,
                                                             double* rotation_scale,
                                                             double* position_scale);
/* A georeferenced index: the centre's 3 x 3 covariance in square metres in the local
 * east-north-up frame at the camera, row-major, and its 95 % radius in metres;
 * CWLOC_ERROR_NOT_AVAILABLE otherwise. Either output may be NULL. */
CWLOC_C_API cwloc_status cwloc_result_enu_covariance(const cwloc_result* result,
                                                     double enu_position[9],
                                                     double* position_radius95_m);
/* How a tracker's frame got its pose; CWLOC_ERROR_NOT_AVAILABLE for a query localized alone. */
CWLOC_C_API cwloc_status cwloc_result_tracking(const cwloc_result* result,
                                               cwloc_tracking* tracking);
/* The JSON record cwloc-localize writes for this query (schemas/localization-result.schema.json).
 */
CWLOC_C_API const char* cwloc_result_json(const cwloc_result* result);

#ifdef __cplusplus
}
#endif

#endif /* CWLOC_CWLOC_H_ */
