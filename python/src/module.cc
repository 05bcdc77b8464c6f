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
  python::BindRig(m);
#ifdef CWLOC_PYTHON_WITH_INDEXER
  python::BindIndexer(m);
#endif
  m.def("version", &cwloc::api::Version, "libcwloc's version, \"MAJOR.MINOR.PATCH\".");
}
