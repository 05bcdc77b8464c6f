// cwloc.build_index: `cwloc-index build` from Python, with its flag names and its report.
#include <functional>
#include <limits>
#include <map>
#include <new>

#include "format/base/error.h"
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

using Setter = std::function<void(py::handle, IndexBuildOptions*, IndexBuildFlags*)>;

// Each keyword is the `cwloc-index build` flag of the same name ('-' written '_').
const std::map<std::string, Setter>& Setters() {
  static const std::map<std::string, Setter> setters = {
      {"trees",
       [](py::handle v, IndexBuildOptions* o, IndexBuildFlags* f) {
         o->forest.num_trees = Whole<uint32_t>("trees", v);
         f->trees_given = true;
       }},
      {"leaf_size",
       [](py::handle v, IndexBuildOptions* o, IndexBuildFlags*) {
         o->forest.max_leaf_size = Whole<uint32_t>("leaf_size", v);
       }},
      {"seed", [](py::handle v, IndexBuildOptions* o,
                  IndexBuildFlags*) { o->seed = Whole<uint64_t>("seed", v); }},
      {"threads", [](py::handle v, IndexBuildOptions* o,
                     IndexBuildFlags*) { o->threads = Whole<int>("threads", v); }},
      {"keypoints", [](py::handle v, IndexBuildOptions* o,
                       IndexBuildFlags*) { o->keypoints = Flag("keypoints", v); }},
      {"compact", [](py::handle v, IndexBuildOptions*,
                     IndexBuildFlags* f) { f->compact = Flag("compact", v); }},
      {"code_bytes",
       [](py::handle v, IndexBuildOptions* o, IndexBuildFlags* f) {
         o->code_bytes = Whole<uint32_t>("code_bytes", v);
         f->code_bytes_given = true;
       }},
      {"clusters", [](py::handle v, IndexBuildOptions*,
                      IndexBuildFlags* f) { f->clusters = Whole<uint32_t>("clusters", v); }},
      {"cluster_file", [](py::handle v, IndexBuildOptions*,
                          IndexBuildFlags* f) { f->cluster_file = ToPath(v, "cluster_file"); }},
      {"georef", [](py::handle v, IndexBuildOptions* o,
                    IndexBuildFlags*) { o->georeferencing.georef_file = ToPath(v, "georef"); }},
      {"georef_images",
       [](py::handle v, IndexBuildOptions* o, IndexBuildFlags*) {
         o->georeferencing.images_dir = ToPath(v, "georef_images");
       }},
      {"model_frame", [](py::handle v, IndexBuildOptions* o,
                         IndexBuildFlags*) { o->georeferencing.model_frame = py::str(v); }},
      {"georef_sigma",
       [](py::handle v, IndexBuildOptions* o, IndexBuildFlags*) {
         o->georeferencing.fit.default_sigma_m = py::float_(py::reinterpret_borrow<py::object>(v));
       }},
  };
  return setters;
}

std::string Names() {
  std::string names;
  for (const auto& [name, setter] : Setters()) names += (names.empty() ? "" : ", ") + name;
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
    const auto setter = Setters().find(name);
    if (setter == Setters().end())
      throw api::Error(api::ErrorCode::kInvalidArgument,
                       "build_index: unknown option '" + name + "' (one of " + Names() + ")");
    setter->second(value, &options, &flags);
  }
  std::string report;
  {
    py::gil_scoped_release release;
    try {
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
  m.def("build_index", &BuildIndexPy, py::arg("model"), py::arg("database"), py::arg("output"),
        "`cwloc-index build`: an index from a COLMAP sparse model folder and its database.db, "
        "written atomically to output. Keyword options are its flags with '-' written '_': "
        "compact, seed, threads, keypoints, trees, leaf_size, code_bytes, clusters, "
        "cluster_file, georef, georef_images, model_frame, georef_sigma. Returns the report of "
        "`cwloc-index build --json` as a dict (output, file_bytes, bytes_per_view, counts, "
        "seconds, georeference). Runs without the GIL; bad input raises cwloc.BadInputError.");
}

}  // namespace cwloc::python
