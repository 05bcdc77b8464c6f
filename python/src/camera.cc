// cwloc.Camera: api::Camera with its calibration as text, and hloc's intrinsics strings.
#include <cstdio>
#include <sstream>

#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

const char* CalibrationName(api::Calibration calibration) {
  switch (calibration) {
    case api::Calibration::kFocalPrior:
      return "focal_prior";
    case api::Calibration::kUnknown:
      return "unknown";
    default:
      return "known";
  }
}

api::Calibration ToCalibration(const std::string& name) {
  if (name == "known") return api::Calibration::kKnown;
  if (name == "focal_prior") return api::Calibration::kFocalPrior;
  if (name == "unknown") return api::Calibration::kUnknown;
  throw py::value_error("calibration '" + name + "': expected 'known', 'focal_prior' or 'unknown'");
}

api::Camera MakeCamera(std::string model, uint32_t width, uint32_t height,
                       std::vector<double> params, const std::string& calibration) {
  return api::Camera{std::move(model), width, height, std::move(params),
                     ToCalibration(calibration)};
}

// "MODEL W H P1 P2 ...", numbers printed so that they read back exactly.
std::string CameraText(const api::Camera& camera) {
  std::string text =
      camera.model + " " + std::to_string(camera.width) + " " + std::to_string(camera.height);
  for (const double p : camera.params) {
    char number[32];
    std::snprintf(number, sizeof(number), " %.17g", p);
    text += number;
  }
  return text;
}

}  // namespace

api::Camera ParseCamera(const std::string& text) {
  std::istringstream in(text);
  api::Camera camera;
  long long width = -1, height = -1;
  if (!(in >> camera.model >> width >> height) || width < 0 || height < 0 || width > UINT32_MAX ||
      height > UINT32_MAX)
    throw py::value_error("camera '" + text + "': expected 'MODEL WIDTH HEIGHT PARAMS...'");
  camera.width = static_cast<uint32_t>(width);
  camera.height = static_cast<uint32_t>(height);
  for (std::string word; in >> word;) {
    try {
      size_t used = 0;
      camera.params.push_back(std::stod(word, &used));
      if (used != word.size()) throw std::invalid_argument(word);
    } catch (const std::exception&) {
      throw py::value_error("camera '" + text + "': parameter '" + word + "' is not a number");
    }
  }
  return camera;
}

api::Camera ToCamera(py::handle camera, const char* what) {
  if (py::isinstance<api::Camera>(camera)) return camera.cast<api::Camera>();
  if (py::isinstance<py::str>(camera)) return ParseCamera(camera.cast<std::string>());
  throw py::type_error(std::string(what) +
                       ": expected a cwloc.Camera or 'MODEL W H PARAMS...', got " +
                       std::string(py::str(py::type::of(camera).attr("__name__"))));
}

void BindCamera(py::module_& m) {
  py::class_<api::Camera>(m, "Camera",
                          "A camera in COLMAP's terms: model name (SIMPLE_PINHOLE, PINHOLE, "
                          "SIMPLE_RADIAL, RADIAL, OPENCV, ...), image size and parameters in "
                          "COLMAP's order; calibration says what the pose stage may trust: "
                          "'known' (all fixed), 'focal_prior' (the focal length is a guess) or "
                          "'unknown' (only the size counts: the focal length is estimated).")
      .def(py::init(&MakeCamera), py::arg("model"), py::arg("width"), py::arg("height"),
           py::arg("params") = std::vector<double>{}, py::arg("calibration") = "known")
      .def_static(
          "from_string",
          [](const std::string& text, const std::string& calibration) {
            api::Camera camera = ParseCamera(text);
            camera.calibration = ToCalibration(calibration);
            return camera;
          },
          py::arg("text"), py::arg("calibration") = "known",
          "A camera from hloc's intrinsics text 'MODEL W H PARAMS...' (as cwloc-localize "
          "--camera takes it).")
      .def_static(
          "unknown",
          [](uint32_t width, uint32_t height) {
            return api::Camera{"", width, height, {}, api::Calibration::kUnknown};
          },
          py::arg("width"), py::arg("height"),
          "Only the image size: the focal length is estimated (P4Pf).")
      .def_readwrite("model", &api::Camera::model, "COLMAP camera model name")
      .def_readwrite("width", &api::Camera::width, "Image width, pixels")
      .def_readwrite("height", &api::Camera::height, "Image height, pixels")
      .def_readwrite("params", &api::Camera::params, "Parameters in COLMAP's order (a list)")
      .def_property(
          "calibration", [](const api::Camera& c) { return CalibrationName(c.calibration); },
          [](api::Camera& c, const std::string& name) { c.calibration = ToCalibration(name); },
          "'known', 'focal_prior' or 'unknown'")
      .def("__str__", &CameraText, "'MODEL W H PARAMS...', as hloc and cwloc-localize write it")
      .def("__repr__",
           [](const api::Camera& c) {
             return "cwloc.Camera.from_string('" + CameraText(c) + "', calibration='" +
                    CalibrationName(c.calibration) + "')";
           })
      .def(
          "__eq__",
          [](const api::Camera& a, const api::Camera& b) {
            return a.model == b.model && a.width == b.width && a.height == b.height &&
                   a.params == b.params && a.calibration == b.calibration;
          },
          py::is_operator());
}

}  // namespace cwloc::python
