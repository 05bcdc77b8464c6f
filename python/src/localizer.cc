// cwloc.Localizer: inputs become C++ objects with the GIL held, then the query runs without it,
// so that threads localize in parallel on one Localizer.
#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

using api::Localizer;
using Result = Record<api::Result>;

bool IsBytesLike(py::handle value) {
  return PyBytes_Check(value.ptr()) || PyByteArray_Check(value.ptr()) ||
         PyMemoryView_Check(value.ptr());
}

std::optional<api::Camera> OptionalCamera(py::handle camera) {
  if (camera.is_none()) return std::nullopt;
  return ToCamera(camera, "camera");
}

Localizer Open(py::handle path, bool verify) {
  const std::string file = ToPath(path, "index");
  py::gil_scoped_release release;
  return Localizer::Open(file, verify);
}

Result LocalizePhoto(const Localizer& localizer, py::handle photo, py::handle camera_in,
                     const py::kwargs& kwargs) {
  const std::optional<api::Camera> camera = OptionalCamera(camera_in);
  const api::Options options = ToOptions(kwargs);
  if (IsBytesLike(photo)) {
    // The buffer stays exported (a bytearray cannot be resized) until the query is done.
    const py::buffer_info bytes = py::reinterpret_borrow<py::buffer>(
                                      py::memoryview(py::reinterpret_borrow<py::object>(photo)))
                                      .request();
    if (bytes.itemsize != 1 || bytes.ndim != 1 || bytes.strides[0] != 1)
      throw py::value_error("photo: expected contiguous bytes");
    py::gil_scoped_release release;
    return Result{localizer.LocalizeEncodedPhoto(static_cast<const uint8_t*>(bytes.ptr),
                                                 static_cast<size_t>(bytes.size), camera, options),
                  options};
  }
  const std::string path = ToPath(photo, "photo");
  py::gil_scoped_release release;
  return Result{localizer.LocalizePhoto(path, camera, options), options};
}

Result LocalizeFeatures(const Localizer& localizer, py::handle keypoints, py::handle descriptors,
                        py::handle camera_in, const py::kwargs& kwargs) {
  const api::Features features = ToFeatures(keypoints, descriptors);
  const api::Camera camera = ToCamera(camera_in, "camera");
  const api::Options options = ToOptions(kwargs);
  py::gil_scoped_release release;
  return Result{localizer.Localize(features, camera, options), options};
}

Result LocalizeGrey(const Localizer& localizer, py::handle image, py::handle camera_in,
                    const py::kwargs& kwargs) {
  const GreyImage grey = ToGreyImage(image);
  const api::Camera camera = ToCamera(camera_in, "camera");
  const api::Options options = ToOptions(kwargs);
  py::gil_scoped_release release;
  return Result{localizer.LocalizeGreyImage(grey.pixels, grey.width, grey.height, grey.stride,
                                            camera, options),
                options};
}

// (keypoints float32 (N, 2), descriptors uint8 (N, 128)) of a COLMAP text feature file.
py::tuple ReadFeatureFile(py::handle path_in) {
  const std::string path = ToPath(path_in, "path");
  api::Features features;
  {
    py::gil_scoped_release release;
    features = api::ReadFeatureFile(path);
  }
  const auto n = static_cast<py::ssize_t>(features.descriptors.size() / 128);
  return py::make_tuple(Array(features.keypoints.data(), {n, 2}),
                        Array(features.descriptors.data(), {n, 128}));
}

}  // namespace

std::string ToPath(py::handle path, const char* what) {
  if (!py::isinstance<py::str>(path) && !py::hasattr(path, "__fspath__"))
    throw py::type_error(std::string(what) + ": expected a str or os.PathLike, got " +
                         std::string(py::str(py::type::of(path).attr("__name__"))));
  return py::module_::import("os").attr("fsdecode")(path).cast<std::string>();
}

void BindLocalizer(py::module_& m) {
  static constexpr char kOptionsDoc[] =
      " Keyword options are cwloc-localize's flags with '-' written '_' (nb=4, "
      "max_features=6000; see default_options()), prior_position=(lat, lon, radius_m[, "
      "height_m]), prior_gravity=(x, y, z) and options=Options(...) as their base. Runs "
      "without the GIL.";
  py::class_<Localizer>(m, "Localizer",
                        "An opened index (memory-mapped, read-only). Every localize_* may run on "
                        "any number of threads at once; a query that does not localize returns "
                        "a Result with success False, bad input raises cwloc.Error.")
      .def(py::init(&Open), py::arg("path"), py::arg("verify") = false,
           "Same as Localizer.open(path, verify).")
      .def_static("open", &Open, py::arg("path"), py::arg("verify") = false,
                  "Opens an index file; verify also checks every checksum and stored index "
                  "(reads the whole file).")
      .def("info", &Localizer::Info, "IndexInfo: path, format, counts, georeference.")
      .def("localize_photo", &LocalizePhoto, py::arg("photo"), py::arg("camera") = py::none(),
           (std::string("Localizes a JPEG or PNG photo: a path (str, os.PathLike) or its bytes "
                        "(bytes, bytearray, memoryview). Without a camera the EXIF focal length "
                        "is the prior, else the focal length is estimated; a camera is a Camera "
                        "or 'MODEL W H PARAMS...' of the photo's size.") +
            kOptionsDoc)
               .c_str())
      .def("localize_features", &LocalizeFeatures, py::arg("keypoints"), py::arg("descriptors"),
           py::arg("camera"),
           (std::string("Localizes SIFT features: keypoints float (N, 2) in COLMAP's pixel "
                        "convention, descriptors uint8 (N, 128) as COLMAP stores them; camera a "
                        "Camera or 'MODEL W H PARAMS...' (Camera.unknown(w, h): only the size).") +
            kOptionsDoc)
               .c_str())
      .def("localize_grey", &LocalizeGrey, py::arg("image"), py::arg("camera"),
           (std::string("Localizes an 8-bit grey image: uint8 (height, width), rows of any "
                        "stride (a camera's Y plane); camera of its size.") +
            kOptionsDoc)
               .c_str())
      .def("localize_rig", &LocalizeRig, py::arg("images"), py::arg("unknown_scale") = false,
           py::arg("name") = "frame",
           (std::string("Localizes several images as one generalized camera (cwloc-localize "
                        "--frames) and returns a RigResult: images is a list of dicts with "
                        "'name', 'photo' (a path) or 'keypoints' and 'descriptors', 'camera' "
                        "(known or a focal prior; a photo without one uses its EXIF focal "
                        "length) and 'cam_from_rig' = ((w, x, y, z), (tx, ty, tz)), X_cam = R "
                        "X_rig + t; the first image is the reference camera. unknown_scale: the "
                        "translations are known up to one scale, which is estimated.") +
            kOptionsDoc)
               .c_str());
  m.def("read_feature_file", &ReadFeatureFile, py::arg("path"),
        "(keypoints float32 (N, 2), descriptors uint8 (N, 128)) of COLMAP's text feature file "
        "('N 128', then 'X Y SCALE ORIENTATION D1 ... D128' lines), as cwloc-localize --features "
        "reads it.");
}

}  // namespace cwloc::python
