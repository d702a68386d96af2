// Reading checked values out of a parsed TOML file (plans, routes, fixtures): each failure is an
// InputError (exit 2) naming the file, the line and the dotted key.
#pragma once
#include <cmath>
#include <initializer_list>
#include <optional>
#include <string>
#include <toml++/toml.h>

#include "bench/io/message_text.hpp"
#include "common/input_error.hpp"
#include "common/sensor_model.hpp"

namespace calbench {

struct TomlReader {
  std::string file;

  [[noreturn]] void fail(const toml::node* n, const std::string& key, const std::string& msg) const {
    throw InputError(file, n ? n->source().begin.line : 0, key, msg);
  }
  [[noreturn]] void fail(const toml::table& t, const std::string& key, const std::string& msg) const {
    throw InputError(file, t.source().begin.line, key, msg);
  }

  // A finite number in [lo, hi]; `def` when the key is absent (missing key without one).
  double num(const toml::table& t, const std::string& prefix, const char* key, std::optional<double> def, double lo,
             double hi) const {
    const toml::node* n = t.get(key);
    const std::string k = prefix + key;
    if (!n) {
      if (def) return *def;
      fail(t, k, "missing key");
    }
    const auto v = n->value<double>();
    if (!v) fail(n, k, "expected a number");
    if (!std::isfinite(*v)) fail(n, k, "NaN or infinity is not allowed");
    if (*v < lo || *v > hi) fail(n, k, "out of range [" + number_text(lo) + ", " + number_text(hi) + "]");
    return *v;
  }

  std::string str(const toml::table& t, const std::string& prefix, const char* key, std::optional<std::string> def) const {
    const toml::node* n = t.get(key);
    if (!n) {
      if (def) return *def;
      fail(t, prefix + key, "missing key");
    }
    if (auto s = n->value<std::string>()) return *s;
    fail(n, prefix + key, "expected a string");
  }

  // An array of three finite numbers; `def` when the key is absent.
  Vec3 vec3(const toml::table& t, const std::string& prefix, const char* key, const Vec3& def) const {
    const toml::node* n = t.get(key);
    if (!n) return def;
    const toml::array* a = n->as_array();
    if (!a || a->size() != 3) fail(n, prefix + key, "expected an array of 3 numbers");
    Vec3 v;
    for (std::size_t i = 0; i < 3; ++i) {
      const auto d = (*a)[i].value<double>();
      if (!d || !std::isfinite(*d)) fail(n, prefix + key, "expected an array of 3 finite numbers");
      v(static_cast<int>(i)) = *d;
    }
    return v;
  }

  // Every key of t is one of `allowed` ("unknown key (typo?)" otherwise).
  void check_keys(const toml::table& t, const std::string& prefix, std::initializer_list<const char*> allowed) const {
    for (const auto& [k, v] : t) {
      bool ok = false;
      for (const char* a : allowed) ok = ok || k.str() == a;
      if (!ok) fail(&v, prefix + std::string(k.str()), "unknown key (typo?)");
    }
  }
};

}  // namespace calbench
