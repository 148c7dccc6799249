// Configurations between TOML and Python: a TOML text becomes nested dicts and
// lists (tables, arrays), Python values go back to TOML text, and a text is
// checked by the same reader as `floesim run` (core/config.hpp), which returns
// the resolved configuration or raises InputError naming the key.
#include <toml++/toml.h>

#include <cstdint>
#include <sstream>
#include <string>

#include "core/config.hpp"
#include "core/error.hpp"
#include "python/bindings.hpp"

namespace py = pybind11;

namespace floesim::python {

namespace {

py::object to_python(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::table: {
      py::dict d;
      for (auto&& [k, v] : *n.as_table()) d[py::str(std::string(k.str()))] = to_python(v);
      return d;
    }
    case toml::node_type::array: {
      py::list l;
      for (const toml::node& e : *n.as_array()) l.append(to_python(e));
      return l;
    }
    case toml::node_type::string: return py::str(n.as_string()->get());
    case toml::node_type::integer: return py::int_(n.as_integer()->get());
    case toml::node_type::floating_point: return py::float_(n.as_floating_point()->get());
    case toml::node_type::boolean: return py::bool_(n.as_boolean()->get());
    default:
      // Dates and times: no floesim key takes one.
      throw InputError("line " + std::to_string(n.source().begin.line) +
                       ": a date or time value, which no floesim key takes");
  }
}

toml::table to_table(py::handle value, const std::string& where);
toml::array to_array(py::handle value, const std::string& where);

[[noreturn]] void refuse(py::handle value, const std::string& where) {
  const std::string type = py::str(py::type::of(value).attr("__name__"));
  throw InputError("key '" + where + "': a value of type " + type +
                   " cannot go into a configuration (expected a number, string, boolean, list or dict)");
}

// Calls put(x) with the TOML value of a Python value: bool, int, float, str,
// dict (table), sequence (array); NumPy scalars and arrays through tolist().
template <class Put>
void put_value(py::handle v, const std::string& where, Put&& put) {
  try {
    if (py::isinstance<py::bool_>(v)) put(v.cast<bool>());
    else if (py::isinstance<py::int_>(v)) put(v.cast<std::int64_t>());
    else if (py::isinstance<py::float_>(v)) put(v.cast<double>());
    else if (py::isinstance<py::str>(v)) put(v.cast<std::string>());
    else if (py::isinstance<py::dict>(v)) put(to_table(v, where));
    else if (py::hasattr(v, "tolist")) put_value(v.attr("tolist")(), where, put);
    else if (py::isinstance<py::sequence>(v) && !py::isinstance<py::bytes>(v)) put(to_array(v, where));
    else refuse(v, where);
  } catch (const py::cast_error&) {
    throw InputError("key '" + where + "': " + std::string(py::str(py::repr(v))) +
                     " does not fit a TOML integer (64 bits)");
  }
}

toml::table to_table(py::handle value, const std::string& where) {
  toml::table t;
  for (auto [k, v] : py::reinterpret_borrow<py::dict>(value)) {
    if (!py::isinstance<py::str>(k))
      throw InputError("key '" + where + "': table keys must be strings, got " + std::string(py::str(py::repr(k))));
    const std::string key = k.cast<std::string>();
    put_value(v, where.empty() ? key : where + "." + key, [&](auto&& x) { t.insert_or_assign(key, std::move(x)); });
  }
  return t;
}

toml::array to_array(py::handle value, const std::string& where) {
  toml::array a;
  for (py::handle v : py::reinterpret_borrow<py::sequence>(value))
    put_value(v, where, [&](auto&& x) { a.push_back(std::move(x)); });
  return a;
}

}  // namespace

void bind_config(py::module_& m) {
  m.def(
      "toml_to_dict",
      [](const std::string& text, const std::string& name) {
        try {
          return to_python(toml::parse(text, name));
        } catch (const toml::parse_error& e) {
          throw InputError(where(name, static_cast<long>(e.source().begin.line), "",
                                 "not valid TOML: " + std::string(e.description())));
        }
      },
      py::arg("text"), py::arg("name") = "<string>",
      "A TOML text as nested dicts (tables) and lists (arrays). Raises InputError for invalid TOML.");
  m.def(
      "dict_to_toml",
      [](const py::dict& d) {
        std::ostringstream s;
        s << to_table(d, "");
        return s.str();
      },
      py::arg("document"), "Nested dicts and lists as a TOML text (the inverse of toml_to_dict).");
  m.def(
      "check_config",
      [](const std::string& text, const std::string& name, const std::string& base_dir) {
        return resolved_toml(parse_config(text, name, base_dir));
      },
      py::arg("text"), py::arg("name"), py::arg("base_dir"),
      "Checks a configuration as `floesim run` does and returns the resolved TOML "
      "(every key with its value in force). Raises InputError naming the key.");
}

}  // namespace floesim::python
