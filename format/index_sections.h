#pragma once

// Element layouts of the index sections (format 1.x). Each is trivially copyable, fixed-width,
// little-endian, and read in place from the mapping; docs/format.md is the byte-level spec.

#include <cstddef>
#include <cstdint>
#include <type_traits>

namespace cwloc {

inline constexpr int kDescriptorBytes = 128;
inline constexpr int kMaxCameraParams = 16;
inline constexpr uint32_t kNoNeighborView = 0xFFFFFFFFu;

// CAMS: one per camera of the model.
struct IndexCamera {
  uint32_t camera_id;  // COLMAP's id
  int32_t model_id;    // COLMAP's camera model id
  uint32_t width;
  uint32_t height;
  uint32_t num_params;              // the model's parameter count, <= kMaxCameraParams
  uint32_t reserved;                // zero
  double params[kMaxCameraParams];  // COLMAP's order; unused entries zero
};
static_assert(sizeof(IndexCamera) == 152 && std::is_trivially_copyable_v<IndexCamera>);

// IMGS: one per model image, ordered by image_id; its views are DESC rows
// [first_view, first_view + num_views), so one image's views are contiguous.
struct IndexImage {
  uint32_t image_id;                  // COLMAP's id
  uint32_t camera_index;              // row in CAMS
  uint32_t name_offset;               // bytes into STRS
  uint32_t name_size;                 // bytes, no terminator
  double cam_from_world_rotation[4];  // quaternion w, x, y, z
  double cam_from_world_translation[3];
  uint32_t first_view;
  uint32_t num_views;
  uint32_t cluster;   // cluster id in [0, manifest.clustering.num_clusters)
  uint32_t reserved;  // zero
};
static_assert(sizeof(IndexImage) == 88 && std::is_trivially_copyable_v<IndexImage>);
static_assert(offsetof(IndexImage, first_view) == 72);

// PNTS: one per 3D point with at least one indexed view; TRKS holds its views
// [first_track, first_track + track_length).
struct IndexPoint {
  double xyz[3];
  uint32_t first_track;
  uint32_t track_length;
};
static_assert(sizeof(IndexPoint) == 32 && std::is_trivially_copyable_v<IndexPoint>);

// PORG and PNTF (format 1.2, a compact index, instead of PNTS): point p lies at
// origin + offsets[p].offset, in doubles; floats keep 1 mm over a 10 km model even when its
// frame is ECEF. A point's track ends where the next one's starts (the last: at TRKS's end).
struct IndexPointOrigin {
  double xyz[3];
};
static_assert(sizeof(IndexPointOrigin) == 24 && std::is_trivially_copyable_v<IndexPointOrigin>);

struct IndexPointOffset {
  float offset[3];
  uint32_t first_track;
};
static_assert(sizeof(IndexPointOffset) == 16 && std::is_trivially_copyable_v<IndexPointOffset>);

// VKXY: the view's keypoint in its model image (COLMAP pixel convention).
struct ViewKeypoint {
  float x;
  float y;
};
static_assert(sizeof(ViewKeypoint) == 8);

// PRGB (optional, format 1.4): a point's colour as COLMAP's points3D store it (8-bit R, G, B).
struct PointColor {
  uint8_t rgb[3];
};
static_assert(sizeof(PointColor) == 3 && alignof(PointColor) == 1);

// CVED: an edge of the co-visibility graph; CVOF[i]..CVOF[i+1] are image i's edges,
// sorted by image index.
struct CovisibilityEdge {
  uint32_t image_index;    // row in IMGS
  uint32_t shared_points;  // 3D points both images see
};
static_assert(sizeof(CovisibilityEdge) == 8);

// GEOR (optional, format 1.1): where the model lies on the globe. One element:
// enu = scale * R(rotation) * model + translation, ENU at the WGS84 origin (docs/geo.md).
struct IndexGeoreference {
  double origin_latitude_deg;
  double origin_longitude_deg;
  double origin_height_m;  // above the ellipsoid
  double scale;
  double rotation[4];  // quaternion w, x, y, z
  double translation[3];
  double rms_residual_m;      // of the fit over its inliers; 0 for a given model frame
  uint32_t source;            // GeoreferenceSource
  uint32_t num_observations;  // positions the fit used (0 for a given model frame)
  uint32_t num_inliers;
  uint32_t reserved[5];  // zero
};
static_assert(sizeof(IndexGeoreference) == 128 && std::is_trivially_copyable_v<IndexGeoreference>);
static_assert(offsetof(IndexGeoreference, source) == 96);

enum class GeoreferenceSource : uint32_t {
  kFile = 1,       // --georef FILE
  kExifGps = 2,    // --georef-images DIR
  kEcefModel = 3,  // --model-frame ecef
  kEnuModel = 4,   // --model-frame enu:LAT,LON,H
};

// PCAL (optional, format 1.3): how far the pose covariance is from the truth on this model,
// measured when the index was built by localizing model images with their observations left
// out (docs/algorithm.md, "Pose uncertainty"). Entry m is the query calibration mode m (0 a
// known camera, 1 a focal prior, 2 an unknown focal length); a scale of 0 means the mode was
// not measured, and the localizer then reports the covariance unscaled.
struct IndexCovarianceCalibration {
  float rotation_scale[3];  // multiplies the covariance's rotation block
  float position_scale[3];  // multiplies its centre block (the cross terms take the root of both)
  uint32_t localized[3];    // samples localized in each mode, of `sampled` (gross failures not)
  uint32_t sampled;         // model images left out and localized
  uint32_t reserved[6];     // zero
};
static_assert(sizeof(IndexCovarianceCalibration) == 64 &&
              std::is_trivially_copyable_v<IndexCovarianceCalibration>);
static_assert(offsetof(IndexCovarianceCalibration, sampled) == 36);

}  // namespace cwloc
