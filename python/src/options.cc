// Options: keyword arguments named as cwloc-localize's flags ('-' written '_'), each set through
// api::Options::Set so that names, ranges and messages come from the library's option table.
#include <cmath>
#include <optional>

#include "python/src/described.h"

namespace cwloc::python {
namespace {

std::string TypeName(py::handle value) { return py::str(py::type::of(value).attr("__name__")); }

// The flag of a keyword: nb_max -> nb-max.
std::string Flag(std::string name) {
  std::replace(name.begin(), name.end(), '_', '-');
  return name;
}

std::string Keyword(std::string flag) {
  std::replace(flag.begin(), flag.end(), '-', '_');
  return flag;
}

// bool and str as text, whole numbers as text (exact for 64-bit seeds), other numbers as double.
void SetOption(api::Options* options, const std::string& keyword, py::handle value) {
  const std::string flag = Flag(keyword);
  if (PyBool_Check(value.ptr())) {
    options->Set(flag, std::string(value.ptr() == Py_True ? "true" : "false"));
  } else if (py::isinstance<py::str>(value)) {
    options->Set(flag, value.cast<std::string>());
  } else if (!PyFloat_Check(value.ptr()) && PyIndex_Check(value.ptr())) {
    options->Set(
        flag, std::string(py::str(py::reinterpret_steal<py::object>(PyNumber_Index(value.ptr())))));
  } else if (PyFloat_Check(value.ptr()) || py::hasattr(value, "__float__")) {
    options->Set(flag, py::float_(py::reinterpret_borrow<py::object>(value)).cast<double>());
  } else {
    throw py::type_error("option " + keyword + ": expected a bool, a number or a str, got " +
                         TypeName(value));
  }
}

std::vector<double> Numbers(py::handle value, const char* what) {
  if (py::isinstance<py::str>(value) || !py::isinstance<py::sequence>(value))
    throw py::type_error(std::string(what) + ": expected a sequence of numbers, got " +
                         TypeName(value));
  std::vector<double> numbers;
  for (py::handle item : py::reinterpret_borrow<py::sequence>(value)) {
    if (!PyFloat_Check(item.ptr()) && !PyIndex_Check(item.ptr()) && !py::hasattr(item, "__float__"))
      throw py::type_error(std::string(what) + ": expected numbers, got " + TypeName(item));
    numbers.push_back(py::float_(py::reinterpret_borrow<py::object>(item)).cast<double>());
  }
  return numbers;
}

// (latitude_deg, longitude_deg, radius_m[, height_m]) or a PositionPrior; None for none.
std::optional<api::PositionPrior> ToPositionPrior(py::handle value) {
  if (value.is_none()) return std::nullopt;
  if (py::isinstance<api::PositionPrior>(value)) return value.cast<api::PositionPrior>();
  const std::vector<double> n = Numbers(value, "prior_position");
  if (n.size() != 3 && n.size() != 4)
    throw py::value_error("prior_position: expected (lat, lon, radius_m[, height_m]), got " +
                          std::to_string(n.size()) + " numbers");
  api::PositionPrior prior;
  prior.latitude_deg = n[0];
  prior.longitude_deg = n[1];
  prior.radius_m = n[2];
  if (n.size() == 4) prior.height_m = n[3];
  return prior;
}

std::optional<std::array<double, 3>> ToGravity(py::handle value) {
  if (value.is_none()) return std::nullopt;
  const std::vector<double> n =
      Numbers(py::module_::import("numpy").attr("ravel")(value).attr("tolist")(), "prior_gravity");
  if (n.size() != 3)
    throw py::value_error("prior_gravity: expected (x, y, z), got " + std::to_string(n.size()) +
                          " numbers");
  return std::array<double, 3>{n[0], n[1], n[2]};
}

void Apply(const py::kwargs& kwargs, api::Options* options) {
  for (const auto& [key, value] : kwargs) {
    const std::string name = py::str(key);
    if (name == "options") continue;
    if (name == "prior_position") {
      options->position_prior = ToPositionPrior(value);
    } else if (name == "prior_gravity") {
      options->gravity = ToGravity(value);
    } else {
      SetOption(options, name, value);
    }
  }
}

py::dict ToDict(const api::Options& o) {
  py::dict out;
#define CWLOC_OPTION(field, type, flag, ...) out[py::str(Keyword(flag))] = py::cast(o.field);
#include "cwloc/options.inc"
#undef CWLOC_OPTION
  return out;
}

py::object PositionPriorOrNone(const std::optional<api::PositionPrior>& prior) {
  return prior ? py::cast(*prior) : py::none();
}

}  // namespace

api::Options ToOptions(const py::kwargs& kwargs) {
  api::Options options;
  if (kwargs.contains("options")) {
    py::object base = kwargs["options"];
    if (!py::isinstance<api::Options>(base))
      throw py::type_error("options: expected a cwloc.Options, got " + TypeName(base));
    options = base.cast<api::Options>();
  }
  Apply(kwargs, &options);
  return options;
}

void BindOptions(py::module_& m) {
  py::class_<api::PositionPrior> prior(
      m, "PositionPrior",
      "A GPS fix: the query was taken within radius_m of this WGS84 position (horizontally "
      "when height_m is None; height above the ellipsoid). Needs a georeferenced index.");
  DefineWritableFields(prior);
  prior
      .def(py::init(
               [](double latitude, double longitude, double radius, std::optional<double> height) {
                 api::PositionPrior made;
                 made.latitude_deg = latitude;
                 made.longitude_deg = longitude;
                 made.radius_m = radius;
                 made.height_m = height;
                 return made;
               }),
           py::arg("latitude_deg"), py::arg("longitude_deg"), py::arg("radius_m"),
           py::arg("height_m") = py::none())
      .def("__repr__", [](const api::PositionPrior& p) {
        return "cwloc.PositionPrior(" +
               std::string(
                   py::repr(py::make_tuple(p.latitude_deg, p.longitude_deg, p.radius_m,
                                           p.height_m ? py::cast(*p.height_m) : py::none()))) +
               ")";
      });

  py::class_<api::Options> options(
      m, "Options",
      "The knobs of cwloc-localize with its defaults. Options(**kwargs) and set() take the "
      "flag names with '-' written '_' (nb=4, max_features=6000) and check each value as the "
      "CLI does; the attributes are the C++ API's fields (docs/api.md).");
  options
      .def(py::init([](const py::kwargs& kwargs) { return ToOptions(kwargs); }),
           "Defaults, then each keyword as set() takes it.")
      .def(
          "set",
          [](api::Options& o, const std::string& name, py::handle value) {
            py::dict one;
            one[py::str(name)] = value;
            Apply(py::kwargs(one), &o);
          },
          py::arg("name"), py::arg("value"),
          "Sets one option by its flag name ('nb', 'max_image_size' or 'max-image-size'), or "
          "prior_position / prior_gravity; raises InvalidArgumentError with the CLI's message.")
      .def("to_dict", &ToDict, "Every option of the table: {keyword: value}.")
      .def_property(
          "position_prior",
          [](const api::Options& o) { return PositionPriorOrNone(o.position_prior); },
          [](api::Options& o, py::handle value) { o.position_prior = ToPositionPrior(value); },
          "--prior-position: a PositionPrior or None")
      .def_property(
          "gravity",
          [](const api::Options& o) -> py::object {
            return o.gravity ? py::object(Array(o.gravity->data(), {3})) : py::none();
          },
          [](api::Options& o, py::handle value) { o.gravity = ToGravity(value); },
          "--prior-gravity: gravity's direction in the camera frame (x right, y down, z "
          "forward), or None")
      .def("__repr__", [](const api::Options& o) {
        return "cwloc.Options(" + std::string(py::repr(ToDict(o))) + ")";
      });
#define CWLOC_OPTION(field, type, flag, target, range, help) \
  options.def_readwrite(#field, &api::Options::field, "--" flag ": " help);
#include "cwloc/options.inc"
#undef CWLOC_OPTION

  m.def(
      "default_options", [] { return ToDict(api::Options()); },
      "cwloc-localize's defaults: {keyword: value} for every option of the table.");
}

}  // namespace cwloc::python
