#pragma once
// Python classes made from the result types' descriptions (results/describe.h): one read-only
// property per described field, with its help and unit as the docstring; numbers as Python
// numbers, lists of numbers as numpy arrays (a matrix where the field has rows), an enum as its
// name, an absent value as None, a list of objects as a list, or (FieldInfo::columns) as one
// array per field. python/cwloc/__init__.pyi's result classes are written from the same
// descriptions (tools/stubs/).
#include <string>
#include <typeinfo>

#include "python/src/bindings.h"

namespace cwloc::python {

// The docstring of a field: its help, then its unit.
inline std::string FieldDoc(const FieldInfo& info) {
  std::string doc(info.help);
  if (!info.unit.empty()) doc += (doc.empty() ? "" : "; ") + std::string(info.unit);
  return doc;
}

template <Described T>
void BindDescribed(py::module_& m);

// Every described class bound, with its fields' names, stub types and docstrings, in the order
// bound: what cwloc._cwloc._described_classes() hands tools/stubs/update_stubs.py and the stub
// test.
struct DescribedField {
  std::string name, type, doc;  // the attribute, its stub type and docstring
  std::string json;             // its key in the JSON record, "" when left out
  double json_scale = 1;
  bool conditional = false;  // the record writes it only when its owner says (a pose: on success)
};
struct DescribedClass {
  std::string name, help;
  std::vector<DescribedField> fields;
};
std::vector<DescribedClass>& DescribedClasses();  // results.cc

// The stub type of a numpy array of V, or of V's elements (a std::array).
template <typename V>
std::string NumpyArrayType() {
  if constexpr (IsStdArray<V>::value) {
    return NumpyArrayType<typename V::value_type>();
  } else {
    return std::string("npt.NDArray[np.") +
           (std::is_same_v<V, double>  ? "float64"
            : std::is_same_v<V, float> ? "float32"
            : std::is_signed_v<V>      ? "int32"
                                       : "uint32") +
           "]";
  }
}

// A field's type as __init__.pyi writes it.
template <typename T>
std::string PythonType(const FieldInfo& info) {
  if constexpr (IsOptional<T>::value) {
    return "Optional[" + PythonType<typename T::value_type>(info) + "]";
  } else if constexpr (Described<T>) {
    return std::string(Description<T>::name);
  } else if constexpr (std::is_same_v<T, bool>) {
    return "bool";
  } else if constexpr (NamedEnum<T>) {
    std::string names;
    for (const std::string_view name : EnumNames<T>::names)
      names += (names.empty() ? "'" : ", '") + std::string(name) + "'";
    return "Literal[" + names + "]";
  } else if constexpr (std::is_same_v<T, std::string>) {
    return "str";
  } else if constexpr (std::is_integral_v<T>) {
    return "int";
  } else if constexpr (std::is_floating_point_v<T>) {
    return "float";
  } else if constexpr (IsStdArray<T>::value) {
    return NumpyArrayType<T>();
  } else if constexpr (DescribedList<T>) {
    const std::string name(Description<typename T::value_type>::name);
    return info.columns ? name + "s" : "list[" + name + "]";
  } else {
    static_assert(IsVector<T>::value, "a described field of a type Python cannot take");
    return "list[" + PythonType<typename T::value_type>(info) + "]";
  }
}

// Records T's class for the stubs, once.
template <Described T>
void RecordDescribedClass(const std::string& name) {
  DescribedClass& record = DescribedClasses().emplace_back();
  record.name = name;
  record.help = std::string(Description<T>::help);
  ForEachField<T>([&](const auto& field) {
    using V = typename std::decay_t<decltype(field)>::value_type;
    record.fields.push_back({std::string(field.info.name), PythonType<V>(field.info),
                             FieldDoc(field.info), std::string(field.info.json),
                             field.info.json_scale, field.written != nullptr});
  });
}

// A list of described objects as one array per field (Description<T>::name + "s").
template <Described T>
struct Columns {
  std::vector<T> rows;
};

template <typename T>
py::object ToPython(const T& value, const FieldInfo& info);

// A column: numbers as an array (N,), fixed-size lists of numbers as (N, k), anything else as a
// list.
template <Described T, typename Owner, typename V>
py::object Column(const std::vector<T>& rows, V Owner::*member, const FieldInfo& info) {
  if constexpr (Numeric<V>) {
    py::array_t<V> column(static_cast<py::ssize_t>(rows.size()));
    for (size_t i = 0; i < rows.size(); ++i) column.mutable_at(i) = rows[i].*member;
    return column;
  } else if constexpr (NumericArray<V>) {
    constexpr auto k = static_cast<py::ssize_t>(std::tuple_size_v<V>);
    py::array_t<typename V::value_type> column({static_cast<py::ssize_t>(rows.size()), k});
    for (size_t i = 0; i < rows.size(); ++i)
      for (py::ssize_t j = 0; j < k; ++j) column.mutable_at(i, j) = (rows[i].*member)[j];
    return column;
  } else {
    py::list column;
    for (const T& row : rows) column.append(ToPython(row.*member, info));
    return column;
  }
}

// A column's type as __init__.pyi writes it.
template <typename V>
std::string ColumnType(const FieldInfo& info) {
  if constexpr (Numeric<V> || NumericArray<V>) return NumpyArrayType<V>();
  return "list[" + PythonType<V>(info) + "]";
}

template <Described T>
void BindColumns(py::module_& m) {
  if (py::detail::get_type_info(typeid(Columns<T>))) return;
  const std::string name = std::string(Description<T>::name) + "s";
  py::class_<Columns<T>> cls(m, name.c_str(),
                             ("Rows of " + std::string(Description<T>::name) +
                              ", one array per field: " + std::string(Description<T>::help))
                                 .c_str());
  ForEachField<T>([&](const auto& field) {
    const auto member = field.member;
    cls.def_property_readonly(
        std::string(field.info.name).c_str(),
        [member, info = field.info](const Columns<T>& c) { return Column(c.rows, member, info); },
        FieldDoc(field.info).c_str());
  });
  cls.def("__len__", [](const Columns<T>& c) { return c.rows.size(); });
  DescribedClass& record = DescribedClasses().emplace_back();
  record.name = name;
  record.help = "Rows of " + std::string(Description<T>::name) + ", one array per field";
  ForEachField<T>([&](const auto& field) {
    using V = typename std::decay_t<decltype(field)>::value_type;
    record.fields.push_back({std::string(field.info.name), ColumnType<V>(field.info),
                             FieldDoc(field.info), "", 1, false});
  });
}

template <typename T>
py::object ToPython(const T& value, const FieldInfo& info) {
  if constexpr (IsOptional<T>::value) {
    return value ? ToPython(*value, info) : py::none();
  } else if constexpr (Described<T>) {
    return py::cast(value);
  } else if constexpr (NamedEnum<T>) {
    return py::str(std::string(NameOf(value)));
  } else if constexpr (NumericArray<T>) {
    using V = typename T::value_type;
    if (info.rows > 0) {
      const py::ssize_t rows = info.rows, columns = value.size() / info.rows;
      return Array<V>(value.data(), {rows, columns});
    }
    return Array<V>(value.data(), {static_cast<py::ssize_t>(value.size())});
  } else if constexpr (DescribedList<T>) {
    if (info.columns) return py::cast(Columns<typename T::value_type>{value});
    return py::cast(value);
  } else {
    return py::cast(value);  // numbers, text, lists of numbers and of text
  }
}

// Registers the classes a field of type T needs (its described types, their columns).
template <typename T>
void BindFieldTypes(py::module_& m, const FieldInfo& info) {
  if constexpr (IsOptional<T>::value) {
    BindFieldTypes<typename T::value_type>(m, info);
  } else if constexpr (Described<T>) {
    BindDescribed<T>(m);
  } else if constexpr (DescribedList<T>) {
    if (info.columns)
      BindColumns<typename T::value_type>(m);
    else
      BindDescribed<typename T::value_type>(m);
  }
}

// T's described fields as read-only properties of `cls`, a class of T or of a Holder whose
// `get(holder)` is the T.
template <Described T, typename Class, typename Get>
void DefineFields(py::module_& m, Class& cls, Get get) {
  ForEachField<T>([&](const auto& field) {
    using V = typename std::decay_t<decltype(field)>::value_type;
    BindFieldTypes<V>(m, field.info);
    const auto member = field.member;
    const FieldInfo info = field.info;
    cls.def_property_readonly(
        std::string(info.name).c_str(),
        [member, info, get](const typename Class::type& holder) {
          return ToPython(get(holder).*member, info);
        },
        FieldDoc(info).c_str());
  });
}

// to_dict(): {field: value} of T's attributes.
template <Described T>
void DefineToDict(py::class_<T>& cls) {
  cls.def(
      "to_dict",
      [](const T& value) {
        py::dict out;
        ForEachField<T>([&](const auto& field) {
          out[py::str(std::string(field.info.name))] = ToPython(value.*field.member, field.info);
        });
        return out;
      },
      "{field: value} of its attributes");
}

// The Python class of T, once: Description<T>::name, its help, its fields.
template <Described T>
void BindDescribed(py::module_& m) {
  if (py::detail::get_type_info(typeid(T))) return;
  py::class_<T> cls(m, std::string(Description<T>::name).c_str(),
                    std::string(Description<T>::help).c_str());
  RecordDescribedClass<T>(std::string(Description<T>::name));
  DefineFields<T>(m, cls, [](const T& value) -> const T& { return value; });
  DefineToDict(cls);
}

// A value of V from Python, as a writable field takes it (an enum by its name).
template <typename V>
V FromPython(py::handle value, const FieldInfo& info) {
  if constexpr (NamedEnum<V>) {
    const std::string name = py::cast<std::string>(value);
    const auto& names = EnumNames<V>::names;
    for (size_t i = 0; i < names.size(); ++i)
      if (names[i] == name) return static_cast<V>(i);
    std::string expected;
    for (const std::string_view n : names)
      expected += (expected.empty() ? "'" : ", '") + std::string(n) + "'";
    throw py::value_error(std::string(info.name) + " '" + name + "': expected " + expected);
  } else if constexpr (IsOptional<V>::value) {
    if (value.is_none()) return std::nullopt;
    return FromPython<typename V::value_type>(value, info);
  } else {
    return py::cast<V>(value);
  }
}

// T's described fields as read-write properties of an input class the caller binds (its
// constructor and methods are its own).
template <Described T>
void DefineWritableFields(py::class_<T>& cls) {
  RecordDescribedClass<T>(std::string(Description<T>::name));
  ForEachField<T>([&](const auto& field) {
    using V = typename std::decay_t<decltype(field)>::value_type;
    const auto member = field.member;
    const FieldInfo info = field.info;
    cls.def_property(
        std::string(info.name).c_str(),
        [member, info](const T& value) { return ToPython(value.*member, info); },
        [member, info](T& value, py::handle input) { value.*member = FromPython<V>(input, info); },
        FieldDoc(info).c_str());
  });
  DefineToDict(cls);
}

}  // namespace cwloc::python
