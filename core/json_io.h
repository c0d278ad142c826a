// Strict, two-way JSON <-> config-struct mapping.
//
// Each config struct is described once, by a function template
//
//   template <class V> void Visit(V& v, LidarConfig& c) {
//     v("rate_hz", c.rate_hz, Rule::Positive(1e4));
//     v.Object("pose", c.pose);
//   }
//
// that JsonReader runs to fill the struct from a document (defaults are the
// struct's own member initialisers; absent keys keep them) and JsonWriter runs
// to write the resolved struct back (every default filled). The reader is
// strict: wrong types, out-of-range values, NaN/inf and keys nobody asked for
// are ConfigErrors that name the file and the JSON pointer, with "did you
// mean" for near-misses.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include "core/error.h"

namespace uavsim::core {

using Json = nlohmann::ordered_json;

// Closed or open numeric range; describes itself for error messages.
struct Rule {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;
  bool max_open = false;

  static Rule Any() { return {}; }
  static Rule Range(double lo, double hi) { return {lo, hi, false, false}; }
  static Rule Positive(double hi = std::numeric_limits<double>::infinity()) {
    return {0.0, hi, true, false};
  }
  static Rule NonNegative(double hi = std::numeric_limits<double>::infinity()) {
    return {0.0, hi, false, false};
  }
  static Rule Probability() { return {0.0, 1.0, false, false}; }

  bool Contains(double x) const;
  std::string Describe(bool integer) const;  // "a number in [0, 1]", "an integer > 0"
};

// A number as messages print it: shortest form, up to 12 significant digits.
std::string FormatNumber(double x);
// RFC 6901 escaping of one reference token.
std::string EscapePointerToken(const std::string& key);
// A short rendering of a JSON value for "got ..." in messages.
std::string DescribeValue(const Json& j);

// Reads a JSON file strictly: size limit, syntax errors with line and column,
// duplicate keys and excessive nesting are ConfigErrors naming `path`.
Json LoadJsonFile(const std::string& path);
// Same, for text already in memory; `name` is used in messages.
Json ParseJsonText(const std::string& text, const std::string& name);

class JsonReader {
 public:
  JsonReader(const Json& node, std::string file, std::string pointer);

  static constexpr bool kReading = true;

  void operator()(const char* key, double& v, Rule r = Rule::Any());
  void operator()(const char* key, int& v, Rule r = Rule::Any());
  void operator()(const char* key, std::int64_t& v, Rule r = Rule::Any());
  void operator()(const char* key, std::uint64_t& v);
  void operator()(const char* key, bool& v);
  void operator()(const char* key, std::string& v);
  void operator()(const char* key, std::optional<double>& v, Rule r = Rule::Any());  // null = unset
  void operator()(const char* key, Eigen::Vector3d& v, Rule r = Rule::Any());
  void operator()(const char* key, Eigen::Vector2d& v, Rule r = Rule::Any());
  void operator()(const char* key, std::vector<double>& v, Rule r = Rule::Any(),
                  std::size_t min_size = 0, std::size_t max_size = 1u << 20);
  void operator()(const char* key, std::vector<Eigen::Vector3d>& v, Rule r = Rule::Any(),
                  std::size_t min_size = 0, std::size_t max_size = 1u << 20);
  void operator()(const char* key, std::vector<std::string>& v,
                  const std::vector<std::string>& allowed = {});

  // A string naming one of `names`; error lists the allowed names.
  template <class E>
  void Enum(const char* key, E& v, const std::vector<std::pair<const char*, E>>& names) {
    const Json* j = Find(key);
    if (!j) return;
    if (j->is_string()) {
      for (const auto& [name, value] : names)
        if (*j == name) {
          v = value;
          return;
        }
    }
    std::string list;
    for (const auto& [name, value] : names)
      list += (list.empty() ? "\"" : ", \"") + std::string(name) + "\"";
    Fail(key, "one of " + list, *j);
  }

  // A nested object, filled by its own Visit.
  template <class T>
  void Object(const char* key, T& s) {
    const Json* j = Find(key);
    if (!j) return;
    if (!j->is_object()) Fail(key, "an object", *j);
    JsonReader child(*j, file_, Child(key));
    Visit(child, s);
    child.Finish();
  }

  // An array of objects. Present: replaces the default list; each element
  // starts from T{} (or from `make_default(i)`) and is filled by Visit.
  template <class T>
  void Array(const char* key, std::vector<T>& items, std::size_t min_size = 0,
             std::size_t max_size = 4096) {
    const Json* j = Find(key);
    if (!j) return;
    if (!j->is_array()) Fail(key, "an array", *j);
    CheckSize(key, j->size(), min_size, max_size);
    std::vector<T> out(j->size());
    for (std::size_t i = 0; i < j->size(); ++i) {
      const Json& e = (*j)[i];
      const std::string p = Child(key) + "/" + std::to_string(i);
      if (!e.is_object())
        throw ConfigError(file_, p, "expected an object, got " + DescribeValue(e));
      JsonReader child(e, file_, p);
      Visit(child, out[i]);
      child.Finish();
    }
    items = std::move(out);
  }

  // An object used as a name -> struct map. Entries merge over the defaults:
  // a name already present is filled over its default value, a new name
  // starts from T{}.
  template <class T>
  void Map(const char* key, std::map<std::string, T>& m) {
    const Json* j = Find(key);
    if (!j) return;
    if (!j->is_object()) Fail(key, "an object", *j);
    for (auto it = j->begin(); it != j->end(); ++it) {
      const std::string p = Child(key) + "/" + EscapePointerToken(it.key());
      if (it.key().empty()) throw ConfigError(file_, p, "expected a non-empty name");
      if (!it.value().is_object())
        throw ConfigError(file_, p, "expected an object, got " + DescribeValue(it.value()));
      T& item = m[it.key()];
      JsonReader child(it.value(), file_, p);
      Visit(child, item);
      child.Finish();
    }
  }

  // A cross-field rule: a failure is reported at `key` (or at this object if
  // key is empty) by Finish, after unknown keys, so a misspelt key is named
  // rather than the rule it broke. The first failure wins.
  void Check(bool ok, const char* key, const std::string& message);

  // Throws for keys present in the object but never asked for, then for the
  // first failed Check.
  void Finish() const;

  const std::string& file() const { return file_; }
  const std::string& pointer() const { return pointer_; }
  std::string Child(const char* key) const;
  bool Has(const char* key) const;
  // The value at `key` as it is (null when absent), for a field whose
  // entries take more than one form (pipeline_config.cpp: methods); the key
  // counts as asked.
  const Json* Raw(const char* key) { return Find(key); }

  [[noreturn]] void Fail(const char* key, const std::string& expected, const Json& got) const;

 private:
  const Json* Find(const char* key);
  double ReadNumber(const char* key, const Json& j, Rule r, bool integer,
                    const std::string& at) const;
  void CheckSize(const char* key, std::size_t n, std::size_t min_size, std::size_t max_size) const;

  const Json& node_;
  std::string file_;
  std::string pointer_;
  std::set<std::string> asked_;
  std::optional<ConfigError> deferred_;
};

class JsonWriter {
 public:
  explicit JsonWriter(Json& out) : out_(out) {}

  static constexpr bool kReading = false;

  template <class T, class... Rest>
  void operator()(const char* key, const T& v, Rest&&...) {
    out_[key] = ToJsonValue(v);
  }

  template <class E>
  void Enum(const char* key, E& v, const std::vector<std::pair<const char*, E>>& names) {
    for (const auto& [name, value] : names)
      if (v == value) out_[key] = name;
  }

  template <class T>
  void Object(const char* key, T& s) {
    Json child = Json::object();
    JsonWriter w(child);
    Visit(w, s);
    out_[key] = std::move(child);
  }

  template <class T>
  void Array(const char* key, std::vector<T>& items, std::size_t = 0, std::size_t = 0) {
    Json arr = Json::array();
    for (auto& item : items) {
      Json child = Json::object();
      JsonWriter w(child);
      Visit(w, item);
      arr.push_back(std::move(child));
    }
    out_[key] = std::move(arr);
  }

  template <class T>
  void Map(const char* key, std::map<std::string, T>& m) {
    Json obj = Json::object();
    for (auto& [name, item] : m) {
      Json child = Json::object();
      JsonWriter w(child);
      Visit(w, item);
      obj[name] = std::move(child);
    }
    out_[key] = std::move(obj);
  }

  void Check(bool, const char*, const std::string&) const {}
  bool Has(const char*) const { return true; }
  // Writes `j` at `key` as it is (the writing side of JsonReader::Raw).
  void Raw(const char* key, Json j) { out_[key] = std::move(j); }

 private:
  static Json ToJsonValue(double v) { return v; }
  static Json ToJsonValue(int v) { return v; }
  static Json ToJsonValue(std::int64_t v) { return v; }
  static Json ToJsonValue(std::uint64_t v) { return v; }
  static Json ToJsonValue(bool v) { return v; }
  static Json ToJsonValue(const std::string& v) { return v; }
  static Json ToJsonValue(const std::optional<double>& v) { return v ? Json(*v) : Json(nullptr); }
  static Json ToJsonValue(const Eigen::Vector3d& v) { return Json::array({v.x(), v.y(), v.z()}); }
  static Json ToJsonValue(const Eigen::Vector2d& v) { return Json::array({v.x(), v.y()}); }
  static Json ToJsonValue(const std::vector<double>& v) { return Json(v); }
  static Json ToJsonValue(const std::vector<std::string>& v) { return Json(v); }
  static Json ToJsonValue(const std::vector<Eigen::Vector3d>& v) {
    Json a = Json::array();
    for (const auto& p : v) a.push_back(ToJsonValue(p));
    return a;
  }

  Json& out_;
};

// Whole-struct helpers.
template <class T>
Json ToJson(const T& config) {
  T copy = config;
  Json out = Json::object();
  JsonWriter w(out);
  Visit(w, copy);
  return out;
}

template <class T>
void FromJson(const Json& j, const std::string& file, const std::string& pointer, T& config) {
  if (!j.is_object())
    throw ConfigError(file, pointer, "expected an object, got " + DescribeValue(j));
  JsonReader r(j, file, pointer);
  Visit(r, config);
  r.Finish();
}

// Explicit instantiation of a struct's Visit for both directions; use in the
// .cpp that defines the template.
#define UAVSIM_INSTANTIATE_VISIT(Type)                     \
  template void Visit(::uavsim::core::JsonReader&, Type&); \
  template void Visit(::uavsim::core::JsonWriter&, Type&)

}  // namespace uavsim::core
