// cwloc.Error and its subclasses, one per api::ErrorCode, raised with the library's message.
#include <Python.h>

#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

// Kept for the process' lifetime: the translator may run until the interpreter exits.
PyObject* g_error = nullptr;
PyObject* g_by_code[5] = {};

PyObject* NewError(py::module_& m, const char* name, const char* doc, PyObject* bases) {
  const std::string qualified = std::string("cwloc.") + name;
  PyObject* type = PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases, nullptr);
  if (type == nullptr) throw py::error_already_set();
  m.add_object(name, py::handle(type));
  return type;
}

void AddSubclass(py::module_& m, api::ErrorCode code, const char* name, const char* doc,
                 PyObject* other_base) {
  py::tuple bases = other_base ? py::make_tuple(py::handle(g_error), py::handle(other_base))
                               : py::make_tuple(py::handle(g_error));
  g_by_code[static_cast<int>(code)] = NewError(m, name, doc, bases.ptr());
}

}  // namespace

void BindErrors(py::module_& m) {
  py::enum_<api::ErrorCode>(m, "ErrorCode", "What went wrong: the C API's cwloc_status codes.")
      .value("INVALID_ARGUMENT", api::ErrorCode::kInvalidArgument,
             "An argument the caller got wrong (option, camera, prior)")
      .value("BAD_INPUT", api::ErrorCode::kBadInput,
             "A file or buffer that cannot be used (corrupt index, broken photo)")
      .value("OUT_OF_MEMORY", api::ErrorCode::kOutOfMemory, "Out of memory")
      .value("INTERNAL", api::ErrorCode::kInternal, "A bug: please report it");

  py::tuple runtime = py::make_tuple(py::handle(PyExc_RuntimeError));
  g_error = NewError(m, "Error",
                     "Raised by every cwloc call that fails; str() is the library's message and "
                     ".code its ErrorCode. A query that does not localize is no error.",
                     runtime.ptr());
  AddSubclass(m, api::ErrorCode::kInvalidArgument, "InvalidArgumentError",
              "An argument the caller got wrong: an option, a camera, a prior (also ValueError).",
              PyExc_ValueError);
  AddSubclass(m, api::ErrorCode::kBadInput, "BadInputError",
              "A file or buffer that cannot be used: a missing or corrupt index, a broken photo.",
              nullptr);
  AddSubclass(m, api::ErrorCode::kOutOfMemory, "OutOfMemoryError",
              "The library ran out of memory (also MemoryError).", PyExc_MemoryError);
  AddSubclass(m, api::ErrorCode::kInternal, "InternalError", "A bug in cwloc: please report it.",
              nullptr);

  py::register_exception_translator([](std::exception_ptr thrown) {
    if (!thrown) return;
    try {
      std::rethrow_exception(thrown);
    } catch (const api::Error& e) {
      const int code = static_cast<int>(e.code());
      PyObject* type = (code >= 1 && code <= 4) ? g_by_code[code] : g_error;
      py::object error = py::reinterpret_borrow<py::object>(type)(e.what());
      error.attr("code") = e.code();
      PyErr_SetObject(type, error.ptr());
    }
  });
}

}  // namespace cwloc::python
