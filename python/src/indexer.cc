// cwloc.build_index: `cwloc-index build` from Python, with its flag names and its report.
#include <algorithm>
#include <filesystem>
#include <limits>
#include <new>
#include <string>

#include "base/error.h"
#include "indexer/build_option_table.h"
#include "indexer/index_build_flags.h"
#include "indexer/index_builder.h"
#include "python/src/bindings.h"

namespace cwloc::python {
namespace {

template <typename T>
T Whole(const std::string& name, py::handle value) {
  if (PyBool_Check(value.ptr()) || PyFloat_Check(value.ptr()) || !PyIndex_Check(value.ptr()))
    throw py::type_error("build_index: " + name + ": expected a whole number");
  const auto number = py::reinterpret_steal<py::int_>(PyNumber_Index(value.ptr()));
  if (number < py::int_(std::numeric_limits<T>::min()) ||
      number > py::int_(std::numeric_limits<T>::max()))
    throw py::value_error("build_index: " + name + "=" + std::string(py::repr(number)) +
                          ": out of range");
  return number.cast<T>();
}

bool Flag(const std::string& name, py::handle value) {
  if (!PyBool_Check(value.ptr()))
    throw py::type_error("build_index: " + name + ": expected True or False");
  return value.ptr() == Py_True;
}

// Each keyword is the `cwloc-index build` flag of the same name ('-' written '_'), one per line
// of the build option table (indexer/build_option_table.inc).
std::string KeywordOf(const BuildOptionSpec& spec) {
  std::string name(spec.flag);
  std::replace(name.begin(), name.end(), '-', '_');
  return name;
}

const BuildOptionSpec* FindKeyword(const std::string& name) {
  for (const BuildOptionSpec& spec : BuildOptionTable()) {
    if (KeywordOf(spec) == name) return &spec;
  }
  return nullptr;
}

// A keyword's value as the option's type; its range is ValidateBuildOptions' to check.
OptionValue FromPython(const BuildOptionSpec& spec, const std::string& name, py::handle value) {
  switch (spec.type) {
    case OptionTypeIndex<bool>():
      return Flag(name, value);
    case OptionTypeIndex<int32_t>():
      return Whole<int32_t>(name, value);
    case OptionTypeIndex<uint32_t>():
      return Whole<uint32_t>(name, value);
    case OptionTypeIndex<uint64_t>():
      return Whole<uint64_t>(name, value);
    case OptionTypeIndex<double>():
      return double(py::float_(py::reinterpret_borrow<py::object>(value)));
    case OptionTypeIndex<std::string>():
      return std::string(py::str(value));
    default:
      return std::filesystem::path(ToPath(value, name.c_str()));
  }
}

std::string Names() {
  std::string names;
  for (const BuildOptionSpec& spec : BuildOptionTable())
    names += (names.empty() ? "" : ", ") + KeywordOf(spec);
  return names;
}

py::object BuildIndexPy(py::handle model, py::handle database, py::handle output,
                        const py::kwargs& kwargs) {
  IndexBuildOptions options;
  IndexBuildFlags flags;
  options.model_dir = ToPath(model, "model");
  options.database_path = ToPath(database, "database");
  options.output_path = ToPath(output, "output");
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    const BuildOptionSpec* spec = FindKeyword(name);
    if (spec == nullptr)
      throw api::Error(api::ErrorCode::kInvalidArgument,
                       "build_index: unknown option '" + name + "' (one of " + Names() + ")");
    spec->set(FromPython(*spec, name, value), &options, &flags);
  }
  std::string report;
  {
    py::gil_scoped_release release;
    try {
      ValidateBuildOptions(options, flags);  // before anything is read, as the CLI does
      ApplyBuildFlags(flags, &options);
      report = BuildReportJson(options, BuildIndex(options)).dump();
    } catch (const InputError& e) {  // as libcwloc.so maps the pipeline's errors
      throw api::Error(api::ErrorCode::kBadInput, e.what());
    } catch (const std::bad_alloc&) {
      throw api::Error(api::ErrorCode::kOutOfMemory, "out of memory");
    } catch (const std::exception& e) {
      throw api::Error(api::ErrorCode::kInternal, std::string("internal error: ") + e.what());
    }
  }
  return py::module_::import("json").attr("loads")(report);
}

}  // namespace

void BindIndexer(py::module_& m) {
  static const std::string doc =
      "`cwloc-index build`: an index from a COLMAP sparse model folder and its database.db, "
      "written atomically to output. Keyword options are its flags with '-' written '_': " +
      Names() +
      ". Returns the report of `cwloc-index build --json` as a dict (output, file_bytes, "
      "bytes_per_view, counts, seconds, georeference). Runs without the GIL; bad input raises "
      "cwloc.BadInputError.";
  m.def("build_index", &BuildIndexPy, py::arg("model"), py::arg("database"), py::arg("output"),
        doc.c_str());
}

}  // namespace cwloc::python
