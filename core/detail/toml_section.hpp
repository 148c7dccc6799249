#pragma once
// The reader of one table of a configuration file (core/config.cpp): each
// accessor checks a key's type and range and throws InputError
// "FILE:LINE: key '[section] name': expected ..., got ..."; the keys it was
// asked for are remembered, so that finish() can name the unknown ones. Plus
// the range rules the readers share.
//
// Internal to core (toml++ is a private dependency of floesim_core).

#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <functional>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "core/error.hpp"

namespace floesim::detail {

// Reads the keys of one TOML table, remembering which were used so that the
// rest can be reported as unknown.
class Section {
public:
  Section(const toml::table* table, std::string name, const std::string& file)
      : table_(table), name_(std::move(name)), file_(file) {}

  bool present() const { return table_ != nullptr; }
  bool has(const std::string& key) const { return table_ && table_->get(key) != nullptr; }

  [[noreturn]] void fail(const std::string& key, const std::string& what) const {
    const toml::node* n = table_ ? table_->get(key) : nullptr;
    const long line = n ? static_cast<long>(n->source().begin.line)
                        : (table_ ? static_cast<long>(table_->source().begin.line) : 0);
    throw InputError(where(file_, line, qualified(key), what));
  }
  std::string qualified(const std::string& key) const {
    return name_.empty() ? key : "[" + name_ + "] " + key;
  }

  const toml::node* node(const std::string& key) {
    used_.insert(key);
    return table_ ? table_->get(key) : nullptr;
  }

  double number(const std::string& key, double def, const std::function<bool(double)>& ok = {},
                const std::string& expected = "a number") {
    const toml::node* n = node(key);
    if (!n) return def;
    double v = to_double(key, *n, expected);
    if (ok && !ok(v)) fail(key, "expected " + expected + ", got " + format(v));
    return v;
  }
  long long integer(const std::string& key, long long def, const std::function<bool(long long)>& ok,
                    const std::string& expected) {
    const toml::node* n = node(key);
    if (!n) return def;
    if (!n->is_integer()) fail(key, "expected " + expected + " (an integer), got " + type_name(*n));
    const long long v = n->as_integer()->get();
    if (ok && !ok(v)) fail(key, "expected " + expected + ", got " + std::to_string(v));
    return v;
  }
  bool boolean(const std::string& key, bool def) {
    const toml::node* n = node(key);
    if (!n) return def;
    if (!n->is_boolean()) fail(key, "expected true or false, got " + type_name(*n));
    return n->as_boolean()->get();
  }
  std::string string(const std::string& key, const std::string& def) {
    const toml::node* n = node(key);
    if (!n) return def;
    if (!n->is_string()) fail(key, "expected a string, got " + type_name(*n));
    return n->as_string()->get();
  }
  template <class E>
  E choice(const std::string& key, E def, const std::vector<std::pair<std::string, E>>& options) {
    const toml::node* n = node(key);
    if (!n) return def;
    std::string list;
    for (auto& [s, e] : options) list += (list.empty() ? "" : " | ") + ("\"" + s + "\"");
    if (!n->is_string()) fail(key, "expected one of " + list + ", got " + type_name(*n));
    const std::string v = n->as_string()->get();
    for (auto& [s, e] : options)
      if (s == v) return e;
    fail(key, "expected one of " + list + ", got \"" + v + "\"");
  }
  std::vector<double> numbers(const std::string& key, std::size_t count, const std::string& what) {
    const toml::node* n = node(key);
    const toml::array* a = n ? n->as_array() : nullptr;
    if (!a || (count && a->size() != count))
      fail(key, "expected " + what + ", got " + (n ? describe(*n) : std::string("nothing")));
    std::vector<double> v;
    for (const toml::node& e : *a) v.push_back(to_double(key, e, what));
    return v;
  }
  std::array<double, 2> pair(const std::string& key, std::array<double, 2> def,
                             const std::string& what = "an array of 2 numbers") {
    if (!has(key)) { node(key); return def; }
    auto v = numbers(key, 2, what);
    for (double x : v)
      if (!std::isfinite(x)) fail(key, "expected finite numbers");
    return {v[0], v[1]};
  }
  std::vector<std::array<double, 2>> points(const std::string& key, const std::string& what) {
    const toml::node* n = node(key);
    if (!n) return {};
    const toml::array* a = n->as_array();
    if (!a) fail(key, "expected " + what + ", got " + type_name(*n));
    std::vector<std::array<double, 2>> out;
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::array* p = (*a)[i].as_array();
      if (!p || p->size() != 2)
        fail(key, "expected " + what + "; entry " + std::to_string(i) + " is " + describe((*a)[i]));
      out.push_back({to_double(key, (*p)[0], what), to_double(key, (*p)[1], what)});
    }
    return out;
  }
  const toml::table* table(const std::string& key) {
    const toml::node* n = node(key);
    if (!n) return nullptr;
    if (!n->is_table()) fail(key, "expected a table ([" + (name_.empty() ? key : name_ + "." + key) + "])");
    return n->as_table();
  }
  const toml::array* table_array(const std::string& key) {
    const toml::node* n = node(key);
    if (!n) return nullptr;
    if (!n->is_array_of_tables())
      fail(key, "expected an array of tables ([[" + (name_.empty() ? key : name_ + "." + key) + "]])");
    return n->as_array();
  }
  long line() const { return table_ ? static_cast<long>(table_->source().begin.line) : 0; }

  // Any key not read by now is unknown.
  void finish() const {
    if (!table_) return;
    for (auto&& [k, v] : *table_) {
      const std::string key(k.str());
      if (!used_.count(key)) {
        std::string known;
        for (const auto& u : used_) known += (known.empty() ? "" : ", ") + u;
        fail(key, "unknown key (known keys here: " + known + ")");
      }
    }
  }

private:
  double to_double(const std::string& key, const toml::node& n, const std::string& expected) const {
    if (n.is_integer()) return static_cast<double>(n.as_integer()->get());
    if (n.is_floating_point()) return n.as_floating_point()->get();
    fail(key, "expected " + expected + ", got " + type_name(n));
  }
  static std::string type_name(const toml::node& n) {
    switch (n.type()) {
      case toml::node_type::string: return "a string";
      case toml::node_type::integer: return "an integer";
      case toml::node_type::floating_point: return "a number";
      case toml::node_type::boolean: return "a boolean";
      case toml::node_type::array: return "an array";
      case toml::node_type::table: return "a table";
      default: return "a date/time";
    }
  }
  static std::string describe(const toml::node& n) {
    if (const toml::array* a = n.as_array()) return "an array of " + std::to_string(a->size());
    return type_name(n);
  }
  static std::string format(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }

  const toml::table* table_;
  std::string name_;
  const std::string& file_;
  std::set<std::string> used_;
};

inline const auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
inline const auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
inline const auto finite = [](double v) { return std::isfinite(v); };
inline const auto unit_interval = [](double v) { return v >= 0.0 && v <= 1.0; };

}  // namespace floesim::detail
