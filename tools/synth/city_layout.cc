#include "tools/synth/city_layout.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include "base/angles.h"
#include "tools/synth/sift_descriptors.h"

namespace cwloc::synth {
namespace {

// Random draws each in their own statement, in the order GCC made them (arguments right to
// left): the order of arguments and of operands is unspecified, and clang's differs.

// Stream tags so that different uses of the same id never share random numbers.
enum Stream : uint64_t {
  kGridStream = 1,
  kFacadeStream,
  kMappingStream,
  kQueryStream,
  kWalkStream
};

// Alternating street and block widths: edges[2i+1]..edges[2i+2] is block i.
std::vector<double> MakeEdges(int blocks, const LayoutOptions& o, Rng& rng) {
  std::vector<double> edges{0};
  for (int i = 0; i < blocks; ++i) {
    edges.push_back(edges.back() + rng.Uniform(o.min_street_width, o.max_street_width));
    edges.push_back(edges.back() + rng.Uniform(o.min_block_side, o.max_block_side));
  }
  edges.push_back(edges.back() + rng.Uniform(o.min_street_width, o.max_street_width));
  return edges;
}

// Index range [first, last] of the blocks along one axis that overlap [lo, hi].
std::array<int, 2> BlockRange(const std::vector<double>& edges, double lo, double hi) {
  const int blocks = int(edges.size() - 2) / 2;
  int first = 0, last = blocks - 1;
  while (first < blocks && edges[2 * first + 2] < lo) ++first;
  while (last >= 0 && edges[2 * last + 1] > hi) --last;
  return {first, last};
}

double Heading(const Eigen::Vector2d& v) { return std::atan2(v.y(), v.x()); }

}  // namespace

CameraPose MakeCameraPose(const Eigen::Vector3d& centre, double yaw, double pitch, double roll) {
  const Eigen::Vector3d forward(std::cos(pitch) * std::cos(yaw), std::cos(pitch) * std::sin(yaw),
                                std::sin(pitch));
  const Eigen::Vector3d right0(std::sin(yaw), -std::cos(yaw), 0);
  const Eigen::Vector3d down0 = forward.cross(right0);
  const Eigen::Vector3d right = std::cos(roll) * right0 + std::sin(roll) * down0;
  const Eigen::Vector3d down = forward.cross(right);
  CameraPose pose;
  pose.cam_from_world_rotation.row(0) = right.transpose();
  pose.cam_from_world_rotation.row(1) = down.transpose();
  pose.cam_from_world_rotation.row(2) = forward.transpose();
  pose.centre = centre;
  return pose;
}

CityLayout::CityLayout(const LayoutOptions& options, uint64_t seed) : options_(options) {
  Rng grid_rng(Rng::Seed(seed, kGridStream));
  column_edges_ = MakeEdges(options.blocks_x, options, grid_rng);
  row_edges_ = MakeEdges(options.blocks_y, options, grid_rng);
  for (int j = 0; j < options.blocks_y; ++j) {
    for (int i = 0; i < options.blocks_x; ++i) {
      const uint32_t block_id = uint32_t(blocks_.size());
      const Block b{column_edges_[2 * i + 1], row_edges_[2 * j + 1], column_edges_[2 * i + 2],
                    row_edges_[2 * j + 2]};
      blocks_.push_back(b);
      // Sides counter-clockwise, so that `direction` is "right" for a viewer in the street.
      const Eigen::Vector2d corners[4] = {{b.x0, b.y0}, {b.x1, b.y0}, {b.x1, b.y1}, {b.x0, b.y1}};
      const double street[4] = {row_edges_[2 * j + 1] - row_edges_[2 * j],
                                column_edges_[2 * i + 3] - column_edges_[2 * i + 2],
                                row_edges_[2 * j + 3] - row_edges_[2 * j + 2],
                                column_edges_[2 * i + 1] - column_edges_[2 * i]};
      const uint32_t first = uint32_t(facades_.size());
      Rng rng(Rng::Seed(seed, kFacadeStream, block_id));
      for (int side = 0; side < 4; ++side) {
        const Eigen::Vector2d a = corners[side], c = corners[(side + 1) % 4];
        const double length = (c - a).norm();
        const Eigen::Vector2d dir = (c - a) / length;
        const Eigen::Vector2d normal(dir.y(), -dir.x());
        // Split the side into buildings; a remainder too narrow for a building joins the last.
        double u = 0;
        while (u < length - 1e-9) {
          double w = rng.Uniform(options.min_building_width, options.max_building_width);
          if (length - u - w < options.min_building_width) w = length - u;
          Facade f;
          f.block = block_id;
          f.side = side;
          f.origin = a + u * dir;
          f.direction = dir;
          f.normal = normal;
          f.width = w;
          f.height = rng.Uniform(options.min_building_height, options.max_building_height);
          f.street_width = street[side];
          for (uint8_t& ch : f.color) ch = uint8_t(90 + rng.Below(140));
          facades_.push_back(f);
          u += w;
        }
      }
      block_facades_.push_back({first, uint32_t(facades_.size())});
    }
  }
  facade_cumulative_width_.reserve(facades_.size());
  double total = 0;
  for (const Facade& f : facades_) facade_cumulative_width_.push_back(total += f.width);
}

double CityLayout::FacadeLength() const {
  return facade_cumulative_width_.empty() ? 0 : facade_cumulative_width_.back();
}

void CityLayout::FacadesNear(const Eigen::Vector2d& centre, double radius,
                             std::vector<uint32_t>* facade_ids) const {
  facade_ids->clear();
  const auto cols = BlockRange(column_edges_, centre.x() - radius, centre.x() + radius);
  const auto rows = BlockRange(row_edges_, centre.y() - radius, centre.y() + radius);
  for (int j = rows[0]; j <= rows[1]; ++j) {
    for (int i = cols[0]; i <= cols[1]; ++i) {
      const auto [first, end] = block_facades_[size_t(j) * options_.blocks_x + i];
      for (uint32_t f = first; f < end; ++f) facade_ids->push_back(f);
    }
  }
}

bool CityLayout::SegmentBlocked(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                uint32_t except_block) const {
  const auto cols = BlockRange(column_edges_, std::min(a.x(), b.x()), std::max(a.x(), b.x()));
  const auto rows = BlockRange(row_edges_, std::min(a.y(), b.y()), std::max(a.y(), b.y()));
  const Eigen::Vector2d d = b - a;
  for (int j = rows[0]; j <= rows[1]; ++j) {
    for (int i = cols[0]; i <= cols[1]; ++i) {
      const uint32_t id = uint32_t(j * options_.blocks_x + i);
      if (id == except_block) continue;
      const Block& k = blocks_[id];
      // Slab test against the open rectangle.
      double t0 = 0, t1 = 1;
      bool outside = false;
      for (int axis = 0; axis < 2 && !outside; ++axis) {
        const double lo = axis == 0 ? k.x0 : k.y0, hi = axis == 0 ? k.x1 : k.y1;
        if (std::abs(d[axis]) < 1e-12) {
          outside = a[axis] <= lo || a[axis] >= hi;
        } else {
          double ta = (lo - a[axis]) / d[axis], tb = (hi - a[axis]) / d[axis];
          if (ta > tb) std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
        }
      }
      if (!outside && t1 - t0 > 1e-9) return true;
    }
  }
  return false;
}

std::vector<CameraPose> CityLayout::PlaceMappingCameras(uint64_t seed) const {
  std::vector<CameraPose> cameras;
  for (uint32_t id = 0; id < facades_.size(); ++id) {
    const Facade& f = facades_[id];
    Rng rng(Rng::Seed(seed, kMappingStream, id));
    const double facing = Heading(-f.normal);
    int station = 0;
    for (double u = 0.5 * options_.camera_spacing; u < f.width;
         u += options_.camera_spacing, ++station) {
      // Across the street, from the far sidewalk.
      {
        const double offset = std::max(2.0, f.street_width - rng.Uniform(1.5, 3.0));
        const Eigen::Vector2d g =
            f.origin + (u + 0.3 * rng.Gaussian()) * f.direction + offset * f.normal;
        const double roll = 1.5 * kDegree * rng.Gaussian();
        const double pitch = rng.Uniform(5, 20) * kDegree;
        const double yaw = facing + rng.Uniform(-30, 30) * kDegree;
        const double height = rng.Uniform(1.5, 1.8);
        CameraPose pose = MakeCameraPose({g.x(), g.y(), height}, yaw, pitch, roll);
        pose.facade = id;
        cameras.push_back(pose);
      }
      // Along the street from the near sidewalk, every second station.
      if (station % 2 == 1) {
        const double offset = rng.Uniform(3.0, std::min(6.0, f.street_width - 1.0));
        const Eigen::Vector2d g = f.origin + u * f.direction + offset * f.normal;
        const double turn_size = rng.Uniform(30, 55) * kDegree;
        const double turn = turn_size * (rng.Uniform() < 0.5 ? -1 : 1);
        const double roll = 1.5 * kDegree * rng.Gaussian();
        const double pitch = rng.Uniform(5, 25) * kDegree;
        const double height = rng.Uniform(1.5, 1.8);
        CameraPose pose = MakeCameraPose({g.x(), g.y(), height}, facing + turn, pitch, roll);
        pose.facade = id;
        cameras.push_back(pose);
      }
    }
  }
  return cameras;
}

uint32_t CityLayout::DrawFacadeByLength(Rng& rng) const {
  const double at = rng.Uniform(0, FacadeLength());
  const size_t id =
      std::upper_bound(facade_cumulative_width_.begin(), facade_cumulative_width_.end(), at) -
      facade_cumulative_width_.begin();
  return uint32_t(std::min(id, facades_.size() - 1));
}

std::vector<CameraPose> CityLayout::WalkCameras(uint64_t seed, size_t frames, double step) const {
  Rng rng(Rng::Seed(seed, kWalkStream));
  const uint32_t id = DrawFacadeByLength(rng);
  const Facade& f = facades_[id];
  const double offset = rng.Uniform(2.0, f.street_width - 1.5);
  const Eigen::Vector2d start =
      f.origin + rng.Uniform(0, f.width) * f.direction + offset * f.normal;
  // The street's stretch inside the city, 1 m from its edges: the walk turns back there.
  double lowest = -std::numeric_limits<double>::infinity();
  double highest = std::numeric_limits<double>::infinity();
  const double extent[2] = {width(), depth()};
  for (int axis = 0; axis < 2; ++axis) {
    if (std::abs(f.direction[axis]) < 1e-9) continue;
    const double a = (1.0 - start[axis]) / f.direction[axis];
    const double b = (extent[axis] - 1.0 - start[axis]) / f.direction[axis];
    lowest = std::max(lowest, std::min(a, b));
    highest = std::min(highest, std::max(a, b));
  }
  const double span = std::max(highest - lowest, 1e-9);
  const double facing = Heading(-f.normal);
  constexpr double kTurn = 2.0 * std::numbers::pi;  // radians
  std::vector<CameraPose> cameras;
  cameras.reserve(frames);
  for (size_t k = 0; k < frames; ++k) {
    // Back and forth: the distance walked folded into [lowest, highest].
    const double walked = std::fmod(-lowest + double(k) * step, 2.0 * span);
    const double along = lowest + (walked <= span ? walked : 2.0 * span - walked);
    const Eigen::Vector2d g = start + along * f.direction;
    const double t = double(k);
    const double yaw = facing + 35 * kDegree * std::sin(kTurn * t / 60.0);
    const double pitch = (10 + 5 * std::sin(kTurn * t / 45.0)) * kDegree;
    const double roll = 2 * kDegree * std::sin(kTurn * t / 23.0);
    const double height = 1.6 + 0.03 * std::sin(kTurn * t / 7.0);
    CameraPose pose = MakeCameraPose({g.x(), g.y(), height}, yaw, pitch, roll);
    pose.facade = id;
    cameras.push_back(pose);
  }
  return cameras;
}

CameraPose CityLayout::DrawQueryCamera(uint64_t seed, uint64_t draw) const {
  Rng rng(Rng::Seed(seed, kQueryStream, draw));
  const uint32_t id = DrawFacadeByLength(rng);
  const Facade& f = facades_[id];
  const double u = rng.Uniform(0, f.width);
  const double offset = rng.Uniform(2.0, f.street_width - 1.5);
  const Eigen::Vector2d g = f.origin + u * f.direction + offset * f.normal;
  const double roll = 3 * kDegree * rng.Gaussian();
  const double pitch = rng.Uniform(-5, 25) * kDegree;
  const double yaw = Heading(-f.normal) + rng.Uniform(-60, 60) * kDegree;
  const double height = rng.Uniform(1.4, 1.9);
  CameraPose pose = MakeCameraPose({g.x(), g.y(), height}, yaw, pitch, roll);
  pose.facade = id;
  return pose;
}

}  // namespace cwloc::synth
