// numpy arrays in: the checks that turn a wrong dtype or shape into TypeError / ValueError.
#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

std::string Shape(const py::array& a) {
  std::string text = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) text += (i ? ", " : "") + std::to_string(a.shape(i));
  return text + (a.ndim() == 1 ? ",)" : ")");
}

std::string DtypeName(const py::array& a) { return py::str(a.dtype()); }

py::array AsArray(py::handle value) {
  return py::reinterpret_steal<py::array>(
      py::module_::import("numpy").attr("asarray")(value).release());
}

}  // namespace

api::Features ToFeatures(py::handle keypoints_in, py::handle descriptors_in) {
  const py::array keypoints = AsArray(keypoints_in);
  const py::array descriptors = AsArray(descriptors_in);
  if (keypoints.dtype().kind() != 'f')
    throw py::type_error("keypoints: expected a float array (float32 or float64), got dtype " +
                         DtypeName(keypoints));
  if (keypoints.ndim() != 2 || keypoints.shape(1) != 2)
    throw py::value_error("keypoints: expected shape (N, 2), got " + Shape(keypoints));
  if (!descriptors.dtype().is(py::dtype::of<uint8_t>()))
    throw py::type_error(
        "descriptors: expected dtype uint8 (SIFT as COLMAP stores it), got dtype " +
        DtypeName(descriptors));
  if (descriptors.ndim() != 2 || descriptors.shape(1) != 128)
    throw py::value_error("descriptors: expected shape (N, 128), got " + Shape(descriptors));
  if (keypoints.shape(0) != descriptors.shape(0))
    throw py::value_error("keypoints and descriptors: " + std::to_string(keypoints.shape(0)) +
                          " keypoints but " + std::to_string(descriptors.shape(0)) +
                          " descriptors");
  using Floats = py::array_t<float, py::array::c_style | py::array::forcecast>;
  using Bytes = py::array_t<uint8_t, py::array::c_style>;
  const Floats xy = Floats::ensure(keypoints);
  const Bytes d = Bytes::ensure(descriptors);
  api::Features features;
  features.keypoints.assign(xy.data(), xy.data() + xy.size());
  features.descriptors.assign(d.data(), d.data() + d.size());
  return features;
}

GreyImage ToGreyImage(py::handle image_in) {
  py::array image = AsArray(image_in);
  if (!image.dtype().is(py::dtype::of<uint8_t>()))
    throw py::type_error("image: expected dtype uint8 (8-bit grey), got dtype " + DtypeName(image));
  if (image.ndim() != 2)
    throw py::value_error("image: expected shape (height, width), got " + Shape(image));
  // Rows may be padded (a camera's Y plane); pixels within a row must be adjacent.
  if (image.strides(1) != 1 || image.strides(0) < image.shape(1))
    image = py::array_t<uint8_t, py::array::c_style>::ensure(image);
  GreyImage grey;
  grey.pixels = static_cast<const uint8_t*>(image.data());
  grey.width = static_cast<uint32_t>(image.shape(1));
  grey.height = static_cast<uint32_t>(image.shape(0));
  grey.stride = static_cast<size_t>(image.strides(0));
  grey.owner = std::move(image);
  return grey;
}

}  // namespace cwloc::python
