// cwloc.Localizer.localize_rig: several images localized as one generalized camera
// (docs/python.md, "Rigs and multi-frame queries"); results.cc binds cwloc.RigResult.
#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

template <size_t N>
std::array<double, N> Numbers(py::handle value, const std::string& what) {
  const std::vector<double> numbers = py::cast<std::vector<double>>(value);
  if (numbers.size() != N)
    throw py::value_error(what + ": expected " + std::to_string(N) + " numbers");
  std::array<double, N> out;
  std::copy(numbers.begin(), numbers.end(), out.begin());
  return out;
}

// A dict: name, and photo (a path) or keypoints and descriptors; camera (a Camera or 'MODEL W
// H PARAMS'); cam_from_rig, (rotation (w, x, y, z), translation).
api::RigImage ToRigImage(const py::dict& image, size_t i) {
  api::RigImage out;
  out.name = image.contains("name") ? py::cast<std::string>(image["name"])
                                    : "image " + std::to_string(i + 1);
  const std::string what = "images[" + std::to_string(i) + "]";
  if (image.contains("photo")) {
    out.photo_path = ToPath(image["photo"], (what + ".photo").c_str());
  } else if (image.contains("keypoints") && image.contains("descriptors")) {
    out.features = ToFeatures(image["keypoints"], image["descriptors"]);
  } else {
    throw py::value_error(what + ": give 'photo', or 'keypoints' and 'descriptors'");
  }
  if (image.contains("camera") && !image["camera"].is_none())
    out.camera = ToCamera(image["camera"], (what + ".camera").c_str());
  if (image.contains("cam_from_rig")) {
    const py::tuple pose = py::cast<py::tuple>(image["cam_from_rig"]);
    if (pose.size() != 2)
      throw py::value_error(what + ".cam_from_rig: expected (rotation_wxyz, translation)");
    out.cam_from_rig_rotation = Numbers<4>(pose[0], what + ".cam_from_rig rotation");
    out.cam_from_rig_translation = Numbers<3>(pose[1], what + ".cam_from_rig translation");
  }
  return out;
}

}  // namespace

Record<api::RigResult> LocalizeRig(const api::Localizer& localizer, const py::list& images_in,
                                   bool unknown_scale, const std::string& name,
                                   const py::kwargs& kwargs) {
  std::vector<api::RigImage> images;
  for (size_t i = 0; i < images_in.size(); ++i)
    images.push_back(ToRigImage(py::cast<py::dict>(images_in[i]), i));
  const api::Options options = ToOptions(kwargs);
  py::gil_scoped_release release;
  return {localizer.LocalizeRig(images, unknown_scale, options, name), options};
}

}  // namespace cwloc::python
