#pragma once

// The geometry of the generated city: a grid of blocks separated by streets, building facades
// on every block side, and where the street-level cameras stand. World frame: x east, y north,
// z up, metres. Blocks are solid for occlusion (as if infinitely tall).

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

namespace cwloc::synth {

struct LayoutOptions {
  int blocks_x = 2;
  int blocks_y = 2;
  double min_block_side = 40;  // metres
  double max_block_side = 90;
  double min_street_width = 12;
  double max_street_width = 24;
  double min_building_width = 8;
  double max_building_width = 24;
  double min_building_height = 8;
  double max_building_height = 30;
  // Mapping cameras walk along every block side: a view across the street every
  // `camera_spacing` metres and an oblique view from the near sidewalk every second station.
  double camera_spacing = 3;
};

struct Block {
  double x0, y0, x1, y1;  // footprint
};

// One building's face on one block side: a vertical rectangle.
struct Facade {
  uint32_t block = 0;
  int side = 0;               // 0 south, 1 east, 2 north, 3 west
  Eigen::Vector2d origin;     // ground-level corner where the facade starts
  Eigen::Vector2d direction;  // unit, along the facade: "right" for a viewer facing it
  Eigen::Vector2d normal;     // unit, outward (towards the street)
  double width = 0, height = 0;
  double street_width = 0;  // width of the street in front of it
  std::array<uint8_t, 3> color{};

  // The 3D point at facade coordinates (u along, v up, depth out of the wall).
  Eigen::Vector3d Point(double u, double v, double depth = 0) const {
    const Eigen::Vector2d g = origin + u * direction + depth * normal;
    return {g.x(), g.y(), v};
  }
};

// A camera pose: rotation and centre. COLMAP's camera axes: x right, y down, z forward.
struct CameraPose {
  Eigen::Matrix3d cam_from_world_rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  uint32_t facade = 0;  // the facade the camera was aimed at
};

// yaw: heading of the viewing direction in the ground plane (radians from +x towards +y);
// pitch: up positive; roll: about the viewing direction.
CameraPose MakeCameraPose(const Eigen::Vector3d& centre, double yaw, double pitch, double roll);

class Rng;

class CityLayout {
 public:
  CityLayout(const LayoutOptions& options, uint64_t seed);

  const LayoutOptions& options() const { return options_; }
  const std::vector<Block>& blocks() const { return blocks_; }
  const std::vector<Facade>& facades() const { return facades_; }
  double width() const { return column_edges_.back(); }  // extent in x, streets included
  double depth() const { return row_edges_.back(); }     // extent in y
  double FacadeLength() const;                           // sum of facade widths

  // Facades of blocks whose footprint comes within `radius` of `centre`.
  void FacadesNear(const Eigen::Vector2d& centre, double radius,
                   std::vector<uint32_t>* facade_ids) const;

  // True when the ground-plane segment a->b passes through the interior of a block other than
  // `except_block` (the block whose facade b lies on).
  bool SegmentBlocked(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                      uint32_t except_block) const;

  // Street-level mapping cameras along every block side, deterministic for the seed.
  std::vector<CameraPose> PlaceMappingCameras(uint64_t seed) const;

  // A random street-level camera aimed at some facade (a query candidate); `draw` picks a
  // different candidate for the same seed.
  CameraPose DrawQueryCamera(uint64_t seed, uint64_t draw) const;

  // The frames of one walk down a street, `step` metres apart (a camera path): along the
  // street in front of a facade drawn by length, back and forth between the city's edges,
  // looking at that side of the street and turning the head slowly (yaw +-35 degrees, pitch
  // 5-15, a little roll, a walker's bob).
  std::vector<CameraPose> WalkCameras(uint64_t seed, size_t frames, double step) const;

 private:
  // A facade drawn with probability proportional to its width (a place on the streets' length).
  uint32_t DrawFacadeByLength(Rng& rng) const;

  LayoutOptions options_;
  std::vector<Block> blocks_;
  std::vector<Facade> facades_;
  std::vector<std::array<uint32_t, 2>> block_facades_;  // [first, end) per block
  // Block footprints are the cells of a grid: column i spans [column_edges_[2i+1],
  // column_edges_[2i+2]] (streets in between), the same for rows.
  std::vector<double> column_edges_, row_edges_;
  std::vector<double> facade_cumulative_width_;  // for drawing a facade by length
};

}  // namespace cwloc::synth
