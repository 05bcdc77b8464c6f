// cwloc.Localizer.localize_rig and cwloc.RigResult: several images localized as one
// generalized camera (docs/python.md, "Rigs and multi-frame queries").
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

api::RigResult LocalizeRig(const api::Localizer& localizer, const py::list& images_in,
                           bool unknown_scale, const std::string& name, const py::kwargs& kwargs) {
  std::vector<api::RigImage> images;
  for (size_t i = 0; i < images_in.size(); ++i)
    images.push_back(ToRigImage(py::cast<py::dict>(images_in[i]), i));
  const api::Options options = ToOptions(kwargs);
  py::gil_scoped_release release;
  return localizer.LocalizeRig(images, unknown_scale, options, name);
}

namespace {

template <size_t N>
py::array_t<double> Vector(const std::array<double, N>& values) {
  return Array(values.data(), {static_cast<py::ssize_t>(N)});
}

}  // namespace

void BindRig(py::module_& m) {
  using I = api::RigImageResult;
  py::class_<I>(m, "RigImageResult", "One image of a rig frame's answer.")
      .def_readonly("name", &I::name)
      .def_readonly("posed", &I::posed, "Whether the rig was localized (the pose below is set)")
      .def_property_readonly(
          "rotation", [](const I& r) { return Vector(r.rotation); },
          "float64 (4,): cam_from_world's quaternion w, x, y, z")
      .def_property_readonly(
          "translation", [](const I& r) { return Vector(r.translation); },
          "float64 (3,): cam_from_world's translation")
      .def_property_readonly(
          "center", [](const I& r) { return Vector(r.center); },
          "float64 (3,): the camera centre, model frame")
      .def_readonly("num_inliers", &I::num_inliers, "The rig's inliers in this image")
      .def_readonly("camera", &I::camera, "The camera used: a focal prior refined with the rig");
  using R = api::RigResult;
  py::class_<R>(m, "RigResult",
                "A rig frame's answer: rig_from_world (X_rig = R X_world + t) and every image's "
                "cam_from_world = cam_from_rig * rig_from_world.")
      .def_readonly("success", &R::success)
      .def_readonly("failure_reason", &R::failure_reason)
      .def_property_readonly(
          "rotation", [](const R& r) { return Vector(r.rotation); },
          "float64 (4,): rig_from_world's quaternion w, x, y, z")
      .def_property_readonly(
          "translation", [](const R& r) { return Vector(r.translation); },
          "float64 (3,): rig_from_world's translation")
      .def_property_readonly(
          "center", [](const R& r) { return Vector(r.center); },
          "float64 (3,): the rig's origin, model frame")
      .def_readonly("scale", &R::scale, "Model units per cam_from_rig translation unit")
      .def_readonly("scale_std", &R::scale_std, "With an unknown scale, its standard deviation")
      .def_readonly("num_inliers", &R::num_inliers, "RANSAC inliers over all images")
      .def_readonly("correspondences", &R::correspondences, "Pooled 2D-3D pairs")
      .def_readonly("covariance", &R::covariance,
                    "PoseCovariance of the rig pose over (theta, C), or None")
      .def_readonly("geo", &R::geo, "The reference camera on the globe, or None")
      .def_readonly("images", &R::images, "RigImageResult per image, the reference first")
      .def_readonly("json", &R::json, "The JSON record cwloc-localize --frames writes")
      .def(
          "to_dict", [](const R& r) { return py::module_::import("json").attr("loads")(r.json); },
          "json.loads(json)");
}

}  // namespace cwloc::python
