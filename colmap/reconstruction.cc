#include "colmap/reconstruction.h"

namespace cwloc::colmap {
namespace {

using Vec3 = std::array<double, 3>;
using Quat = std::array<double, 4>;  // w, x, y, z

Vec3 Cross(const Vec3& a, const Vec3& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

// v' = v + 2w (u x v) + 2 u x (u x v) for a unit quaternion (w, u).
Vec3 Rotate(const Quat& q, const Vec3& v) {
  const Vec3 u = {q[1], q[2], q[3]};
  const Vec3 uv = Cross(u, v);
  const Vec3 uuv = Cross(u, uv);
  return {v[0] + 2 * (q[0] * uv[0] + uuv[0]), v[1] + 2 * (q[0] * uv[1] + uuv[1]),
          v[2] + 2 * (q[0] * uv[2] + uuv[2])};
}

// Hamilton product a * b: rotate by b, then by a.
Quat Multiply(const Quat& a, const Quat& b) {
  return {a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
          a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
          a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
          a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0]};
}

}  // namespace

Rigid3d operator*(const Rigid3d& c_from_b, const Rigid3d& b_from_a) {
  Rigid3d c_from_a;
  c_from_a.rotation = Multiply(c_from_b.rotation, b_from_a.rotation);
  const Vec3 t = Rotate(c_from_b.rotation, b_from_a.translation);
  for (int i = 0; i < 3; ++i) c_from_a.translation[i] = t[i] + c_from_b.translation[i];
  return c_from_a;
}

Rigid3d Inverse(const Rigid3d& b_from_a) {
  Rigid3d a_from_b;
  const Quat& q = b_from_a.rotation;
  a_from_b.rotation = {q[0], -q[1], -q[2], -q[3]};
  const Vec3 t = Rotate(a_from_b.rotation, b_from_a.translation);
  a_from_b.translation = {-t[0], -t[1], -t[2]};
  return a_from_b;
}

std::array<double, 3> operator*(const Rigid3d& b_from_a, const std::array<double, 3>& x_in_a) {
  const Vec3 r = Rotate(b_from_a.rotation, x_in_a);
  return {r[0] + b_from_a.translation[0], r[1] + b_from_a.translation[1],
          r[2] + b_from_a.translation[2]};
}

size_t Reconstruction::NumObservations() const {
  size_t total = 0;
  for (const auto& [id, point] : points3D) total += point.track.size();
  return total;
}

}  // namespace cwloc::colmap
