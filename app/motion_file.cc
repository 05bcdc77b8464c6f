#include "app/motion_file.h"

#include <fstream>
#include <sstream>
#include <variant>

#include "base/bounded_file.h"
#include "base/error.h"
#include "geo/geo_region.h"

namespace cwloc {

std::variant<FrameMotion, std::string> ParseMotion(const std::string& numbers,
                                                   std::string_view layout) {
  const auto v = ParseFiniteNumbers(numbers);
  if (!v || (v->size() != 7 && v->size() != 9))
    return "expected '" + std::string(layout) + "' (seven or nine numbers)";
  const bool sigmas = v->size() == 9;
  return MetricMotion({(*v)[0], (*v)[1], (*v)[2], (*v)[3]}, {(*v)[4], (*v)[5], (*v)[6]},
                      sigmas ? (*v)[7] : 0.0, sigmas ? (*v)[8] : 0.0);
}

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
    std::variant<FrameMotion, std::string> motion =
        ParseMotion(rest, "NAME QW QX QY QZ TX TY TZ [SIGMA_ROT_DEG SIGMA_POS]");
    if (const auto* problem = std::get_if<std::string>(&motion))
      throw InputError(where + ": " + *problem);
    if (!motions.emplace(name, MotionLine{std::get<FrameMotion>(motion), number}).second)
      throw InputError(where + ": a second motion for '" + name + "'");
  }
  return motions;
}

}  // namespace cwloc
