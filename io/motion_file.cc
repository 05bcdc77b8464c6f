#include "io/motion_file.h"

#include <cmath>
#include <fstream>
#include <sstream>

#include "base/bounded_file.h"
#include "base/error.h"
#include "geo/geo_region.h"

namespace cwloc {

std::unordered_map<std::string, MotionLine> ReadMotionFile(const std::filesystem::path& path) {
  CheckInputFile(path, kMotionFile);
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the motion file");
  std::unordered_map<std::string, MotionLine> motions;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::string where = path.string() + ":" + std::to_string(number);
    std::istringstream fields(line);
    std::string name;
    if (!(fields >> name) || name[0] == '#') continue;
    std::string rest;
    std::getline(fields, rest);
    const auto v = ParseFiniteNumbers(rest);
    if (!v || (v->size() != 7 && v->size() != 9)) {
      throw InputError(where +
                       ": expected 'NAME QW QX QY QZ TX TY TZ [SIGMA_ROT_DEG SIGMA_POS]' (seven "
                       "or nine numbers)");
    }
    const Eigen::Quaterniond q((*v)[0], (*v)[1], (*v)[2], (*v)[3]);
    if (std::abs(q.norm() - 1.0) > 1e-3)
      throw InputError(where + ": the quaternion's length is " + std::to_string(q.norm()) +
                       ", not 1");
    FrameMotion motion;
    motion.relative = CameraPose(q.normalized(), Eigen::Vector3d((*v)[4], (*v)[5], (*v)[6]));
    motion.metric = true;
    if (v->size() == 9) {
      if (!((*v)[7] >= 0.0) || !((*v)[8] >= 0.0))
        throw InputError(where + ": a motion's sigmas are at least 0 (0: not known)");
      motion.sigma_rotation_deg = (*v)[7];
      motion.sigma_position = (*v)[8];
    }
    if (!motions.emplace(name, MotionLine{motion, number}).second)
      throw InputError(where + ": a second motion for '" + name + "'");
  }
  return motions;
}

}  // namespace cwloc
