#pragma once
// The pieces of the Python module cwloc, one file per topic; module.cc puts them together.
// Only conversions live here: every decision is libcwloc.so's (cwloc/cwloc.hpp).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>  // in every file: one conversion of std types everywhere

#include <algorithm>
#include <string>
#include <vector>

#include "cwloc/cwloc.hpp"
#include "cwloc/describe.h"

namespace cwloc::python {

namespace py = pybind11;

void BindErrors(py::module_& m);     // errors.cc
void BindCamera(py::module_& m);     // camera.cc
void BindOptions(py::module_& m);    // options.cc
void BindResults(py::module_& m);    // results.cc
void BindLocalizer(py::module_& m);  // localizer.cc
void BindTracker(py::module_& m);    // tracker.cc
void BindIndexer(py::module_& m);    // indexer.cc, in builds with the indexer

// A Camera, or hloc's "MODEL W H PARAMS..." text. Raises TypeError / ValueError.
api::Camera ToCamera(py::handle camera, const char* what);
api::Camera ParseCamera(const std::string& text);

// Keyword options (cwloc-localize's flags, '-' written '_') over `options=` when given.
api::Options ToOptions(const py::kwargs& kwargs);

// A result with the options it was made with, which its JSON record echoes: cwloc.Result and
// cwloc.RigResult.
template <typename T>
struct Record {
  T value;
  api::Options options;
};

// Localizer.localize_rig (rig.cc): a list of image dicts as one generalized camera.
Record<api::RigResult> LocalizeRig(const api::Localizer& localizer, const py::list& images,
                                   bool unknown_scale, const std::string& name,
                                   const py::kwargs& kwargs);

// A str or os.PathLike as a file path. Raises TypeError.
std::string ToPath(py::handle path, const char* what);

// Keypoints (N x 2, float) and descriptors (N x 128, uint8) as the API takes them.
api::Features ToFeatures(py::handle keypoints, py::handle descriptors);

// An 8-bit grey image (H x W uint8, rows of any stride) that `owner` keeps alive.
struct GreyImage {
  py::object owner;
  const uint8_t* pixels = nullptr;
  uint32_t width = 0, height = 0;
  size_t stride = 0;
};
GreyImage ToGreyImage(py::handle image);

// A numpy array of this shape holding a copy of `data`.
template <typename T>
py::array_t<T> Array(const T* data, std::vector<py::ssize_t> shape) {
  py::array_t<T> array(shape);
  std::copy_n(data, array.size(), array.mutable_data());
  return array;
}

}  // namespace cwloc::python
