// Results as typed objects, made from their descriptions (described.h): cwloc.Result and
// cwloc.RigResult hold the options they were made with, for their JSON record.
#include "python/src/described.h"

namespace cwloc::python {

std::vector<DescribedClass>& DescribedClasses() {
  static std::vector<DescribedClass> classes;
  return classes;
}

namespace {

// R of a unit quaternion (w, x, y, z), as Eigen's toRotationMatrix computes it.
py::array_t<double> RotationMatrix(const std::array<double, 4>& q) {
  const double w = q[0], x = q[1], y = q[2], z = q[3];
  const double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                       2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                       2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
  return Array(r, {3, 3});
}

// The record's class: T's fields, and its JSON record (with the options) as text and as a dict.
template <typename T>
py::class_<Record<T>> BindRecord(py::module_& m) {
  using R = Record<T>;
  const std::string name(Description<T>::name);
  py::class_<R> cls(m, name.c_str(), std::string(Description<T>::help).c_str());
  RecordDescribedClass<T>(name);
  DefineFields<T>(m, cls, [](const R& record) -> const T& { return record.value; });
  cls.def_property_readonly(
         "json", [](const R& r) { return api::ToJson(r.value, r.options); },
         "The JSON record cwloc-localize writes for it (schemas/localization-result.schema.json)")
      .def(
          "to_dict",
          [](const R& r) {
            return py::module_::import("json").attr("loads")(api::ToJson(r.value, r.options));
          },
          "The JSON record as a dict");
  return cls;
}

}  // namespace

void BindResults(py::module_& m) {
  BindRecord<api::Result>(m)
      .def_property_readonly(
          "cam_from_world",
          [](const Record<api::Result>& r) { return RotationMatrix(r.value.rotation); },
          "float64 (3, 3): the rotation matrix of rotation")
      .def("__repr__", [](const Record<api::Result>& r) {
        return r.value.success
                   ? "cwloc.Result(success, " + std::to_string(r.value.num_inliers) + " inliers)"
                   : "cwloc.Result(failed: " + r.value.failure_reason + ")";
      });
  BindRecord<api::RigResult>(m).def("__repr__", [](const Record<api::RigResult>& r) {
    return r.value.success
               ? "cwloc.RigResult(success, " + std::to_string(r.value.rig.num_inliers) + " inliers)"
               : "cwloc.RigResult(failed: " + r.value.failure_reason + ")";
  });
  m.def(
      "_described_classes",
      [] {
        py::list classes;
        for (const DescribedClass& c : DescribedClasses()) {
          py::list fields;
          for (const DescribedField& f : c.fields)
            fields.append(
                py::make_tuple(f.name, f.type, f.doc, f.json, f.json_scale, f.conditional));
          classes.append(py::make_tuple(c.name, c.help, fields));
        }
        return classes;
      },
      "Every class made from a description: (name, help, [(field, stub type, doc, JSON key, "
      "JSON scale, written only under a condition)]), for tools/stubs/update_stubs.py and "
      "tests/python/test_results.py");

  py::class_<api::IndexInfo>(m, "IndexInfo", "An opened index.")
      .def_readonly("path", &api::IndexInfo::path, "The file")
      .def_readonly("format_version", &api::IndexInfo::format_version, "'MAJOR.MINOR'")
      .def_readonly("num_images", &api::IndexInfo::num_images, "Model images")
      .def_readonly("num_points", &api::IndexInfo::num_points, "3D points")
      .def_readonly("num_views", &api::IndexInfo::num_views, "Observations, one descriptor each")
      .def_readonly("georeferenced", &api::IndexInfo::georeferenced,
                    "Whether results have a GeoPose and queries may have priors")
      .def_readonly("origin_latitude_deg", &api::IndexInfo::origin_latitude_deg, "ENU origin")
      .def_readonly("origin_longitude_deg", &api::IndexInfo::origin_longitude_deg, "ENU origin")
      .def_readonly("origin_height_m", &api::IndexInfo::origin_height_m, "ENU origin")
      .def("__repr__", [](const api::IndexInfo& i) {
        return "cwloc.IndexInfo('" + i.path + "', format " + i.format_version + ", " +
               std::to_string(i.num_images) + " images, " + std::to_string(i.num_points) +
               " points, " + std::to_string(i.num_views) + " views)";
      });
}

}  // namespace cwloc::python
