// The extension module cwloc._cwloc; python/cwloc/__init__.py re-exports it as cwloc.
#include "python/src/bindings.h"

PYBIND11_MODULE(_cwloc, m) {
  namespace python = cwloc::python;
  m.doc() = "cwloc: 6-DoF camera localization against COLMAP models (bindings of libcwloc.so)";
  python::BindErrors(m);
  python::BindCamera(m);
  python::BindOptions(m);
  python::BindResults(m);
  python::BindLocalizer(m);
  python::BindTracker(m);
#ifdef CWLOC_PYTHON_WITH_INDEXER
  python::BindIndexer(m);
#endif
  m.def("version", &cwloc::api::Version, "libcwloc's version, \"MAJOR.MINOR.PATCH\".");
  m.def(
      "apply_index_delta",
      [](pybind11::handle index, pybind11::handle delta, pybind11::handle output, int threads) {
        const std::string index_path = python::ToPath(index, "index"),
                          delta_path = python::ToPath(delta, "delta"),
                          output_path = python::ToPath(output, "output");
        pybind11::gil_scoped_release release;
        cwloc::api::ApplyIndexDelta(index_path, delta_path, output_path, threads);
      },
      pybind11::arg("index"), pybind11::arg("delta"), pybind11::arg("output"),
      pybind11::arg("threads") = 0,
      "`cwloc-index apply`: writes (atomically) the index a delta of `cwloc-index update --delta` "
      "makes of the index it was made for, bit for bit; cwloc.BadInputError, and nothing "
      "written, for a delta made for another index or a damaged file. Runs without the GIL.");
}
