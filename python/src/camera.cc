// cwloc.Camera: api::Camera with its calibration as text, and hloc's intrinsics strings.
#include <cstdio>
#include <sstream>

#include "python/src/described.h"

namespace cwloc::python {
namespace {

// The calibration of that name (cwloc/camera.h's, as the JSON spells it); "focal_prior" as
// earlier versions spelt it.
api::Calibration ToCalibration(const std::string& name) {
  const FieldInfo calibration = Info("calibration");
  return FromPython<api::Calibration>(py::str(name == "focal_prior" ? "focal-prior" : name),
                                      calibration);
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
  // A result's camera, to localize the next query with.
  if (py::isinstance<api::ResultCamera>(camera)) return camera.cast<api::ResultCamera>();
  if (py::isinstance<api::CameraUsed>(camera)) return camera.cast<api::CameraUsed>();
  if (py::isinstance<py::str>(camera)) return ParseCamera(camera.cast<std::string>());
  throw py::type_error(std::string(what) +
                       ": expected a cwloc.Camera or 'MODEL W H PARAMS...', got " +
                       std::string(py::str(py::type::of(camera).attr("__name__"))));
}

void BindCamera(py::module_& m) {
  py::class_<api::Camera> camera(m, "Camera",
                                 "A camera in COLMAP's terms: model name (SIMPLE_PINHOLE, PINHOLE, "
                                 "SIMPLE_RADIAL, RADIAL, OPENCV, ...), image size and parameters "
                                 "in COLMAP's order; calibration says what the pose stage may "
                                 "trust: 'known' (all fixed), 'focal-prior' (the focal length is a "
                                 "guess) or 'unknown' (only the size counts: the focal length is "
                                 "estimated).");
  DefineWritableFields(camera);
  camera
      .def(py::init(&MakeCamera), py::arg("model"), py::arg("width"), py::arg("height"),
           py::arg("params") = std::vector<double>{}, py::arg("calibration") = "known")
      .def_static(
          "from_string",
          [](const std::string& text, const std::string& calibration) {
            api::Camera parsed = ParseCamera(text);
            parsed.calibration = ToCalibration(calibration);
            return parsed;
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
      .def("__str__", &CameraText, "'MODEL W H PARAMS...', as hloc and cwloc-localize write it")
      .def("__repr__",
           [](const api::Camera& c) {
             return "cwloc.Camera.from_string('" + CameraText(c) + "', calibration='" +
                    std::string(NameOf(c.calibration)) + "')";
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
