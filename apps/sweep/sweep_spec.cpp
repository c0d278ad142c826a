#include "apps/sweep/sweep_spec.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <set>

#include "core/interrupt.h"
#include "core/progress.h"

namespace uavsim::sim {
namespace {

namespace fs = std::filesystem;
using core::ConfigError;
using core::Json;

// Reading the spec: every error names the spec file and a pointer into it.
struct SpecReader {
  std::string file;

  [[noreturn]] void Fail(const std::string& at, const std::string& what) const {
    throw at.empty() ? ConfigError::AboutDocument(file, what) : ConfigError(file, at, what);
  }
  void Keys(const Json& j, const std::string& at, const std::set<std::string>& allowed) const {
    if (!j.is_object()) Fail(at, "expected an object, got " + core::DescribeValue(j));
    for (const auto& [k, v] : j.items())
      if (!allowed.count(k)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        Fail(at + "/" + core::EscapePointerToken(k), "unknown key (expected one of " + list + ")");
      }
  }
  std::string String(const Json& j, const std::string& at) const {
    if (!j.is_string() || j.get<std::string>().empty())
      Fail(at, "expected a non-empty string, got " + core::DescribeValue(j));
    return j.get<std::string>();
  }
  double Number(const Json& j, const std::string& at) const {
    if (!j.is_number()) Fail(at, "expected a number, got " + core::DescribeValue(j));
    return j.get<double>();
  }
  std::uint64_t Seed(const Json& j, const std::string& at) const {
    if (!j.is_number_unsigned() || j.get<std::uint64_t>() > (~0ull >> 1))
      Fail(at, "expected a seed (an integer from 0 to 2^63-1), got " + core::DescribeValue(j));
    return j.get<std::uint64_t>();
  }
  std::string Pointer(const Json& j, const std::string& at) const {
    const std::string p = String(j, at);
    if (p[0] != '/' || p == "/") Fail(at, "expected a JSON pointer such as /weather/rain_mm_h");
    if (p == "/seed") Fail(at, "the seed is swept by \"seeds\", not by a parameter");
    return p;
  }
};

// A number as labels and file names show it (shortest form).
std::string Label(const Json& v) {
  if (v.is_number()) return core::FormatNumber(v.get<double>());
  if (v.is_string()) return v.get<std::string>();
  return v.dump();
}

// "/weather/rain_mm_h" -> "rain_mm_h"
std::string Leaf(const std::string& pointer) { return pointer.substr(pointer.rfind('/') + 1); }

// "rain_mm_h" -> "rain (mm/h)", "fog_visibility_m" -> "fog visibility (m)".
std::string AxisLabelOfKey(const std::string& key) {
  static const std::pair<const char*, const char*> kUnits[] = {
      {"_mm_h", "mm/h"}, {"_mbps", "Mbit/s"}, {"_ghz", "GHz"}, {"_hz", "Hz"}, {"_ms", "ms"},
      {"_db", "dB"},     {"_deg", "deg"},     {"_mps", "m/s"}, {"_m", "m"},   {"_s", "s"}};
  std::string base = key, unit;
  for (const auto& [suffix, u] : kUnits) {
    const std::string sfx = suffix;
    if (key.size() > sfx.size() && key.compare(key.size() - sfx.size(), sfx.size(), sfx) == 0) {
      base = key.substr(0, key.size() - sfx.size());
      unit = u;
      break;
    }
  }
  std::replace(base.begin(), base.end(), '_', ' ');
  return unit.empty() ? base : base + " (" + unit + ")";
}

bool ValidName(const std::string& s) {
  return !s.empty() && s.size() <= 64 && std::all_of(s.begin(), s.end(), [](char c) {
    return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
  });
}

// Where a pointer set by the spec lives in the spec, to blame it for a
// scenario error at `scenario_pointer`.
struct Assignment {
  std::string pointer;       // into the scenario
  std::string spec_pointer;  // into the spec: the value
  std::string spec_key;      // into the spec: where the pointer is written
  // The spec location to blame for a scenario error at `error_at`: the
  // value when the scenario refuses the value or a part of it, else the
  // pointer (an unknown key on the way).
  std::string Blame(const std::string& error_at) const {
    return error_at == pointer || error_at.rfind(pointer + "/", 0) == 0 ? spec_pointer : spec_key;
  }
};

bool Covers(const std::string& set, const std::string& error_at) {
  return error_at == set || error_at.rfind(set + "/", 0) == 0 || set.rfind(error_at + "/", 0) == 0;
}

SweepParameter ReadParameter(const SpecReader& r, const Json& j, const std::string& at,
                             std::vector<std::vector<std::string>>& value_pointers) {
  r.Keys(j, at, {"name", "pointer", "values", "range", "cases", "axis_label"});
  SweepParameter p;
  if (!j.contains("name")) r.Fail(at, "missing \"name\" (a column name such as \"loss\")");
  p.name = r.String(j["name"], at + "/name");
  if (!ValidName(p.name))
    r.Fail(at + "/name", "expected letters, digits, '_' or '-' (it names columns and files)");
  const int forms = j.contains("values") + j.contains("range") + j.contains("cases");
  if (forms != 1) r.Fail(at, "expected exactly one of \"values\", \"range\" or \"cases\"");
  std::vector<std::string> spec_pointers;  // per value: where it is in the spec
  if (j.contains("cases")) {
    if (j.contains("pointer"))
      r.Fail(at + "/pointer", "a cases parameter names its pointers in each case's \"set\"");
    const Json& cases = j["cases"];
    if (!cases.is_array() || cases.empty())
      r.Fail(at + "/cases", "expected a non-empty array of {\"label\", \"set\"}");
    std::set<std::string> labels;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const std::string ci = at + "/cases/" + std::to_string(i);
      r.Keys(cases[i], ci, {"label", "set"});
      SweepValue v;
      if (!cases[i].contains("label")) r.Fail(ci, "missing \"label\"");
      v.label = r.String(cases[i]["label"], ci + "/label");
      if (!labels.insert(v.label).second) r.Fail(ci + "/label", "repeats an earlier case's label");
      const Json set = cases[i].value("set", Json::object());
      if (!set.is_object()) r.Fail(ci + "/set", "expected an object of \"/json/pointer\": value");
      for (const auto& [ptr, val] : set.items()) {
        r.Pointer(Json(ptr), ci + "/set/" + core::EscapePointerToken(ptr));
        v.set.emplace_back(ptr, val);
      }
      p.values.push_back(std::move(v));
      spec_pointers.push_back(ci + "/set");
    }
    p.axis_label = p.name;
  } else {
    if (!j.contains("pointer")) r.Fail(at, "missing \"pointer\" (the scenario value to vary)");
    p.pointer = r.Pointer(j["pointer"], at + "/pointer");
    std::vector<Json> values;
    if (j.contains("values")) {
      const Json& vs = j["values"];
      if (!vs.is_array() || vs.empty()) r.Fail(at + "/values", "expected a non-empty array");
      for (std::size_t i = 0; i < vs.size(); ++i) {
        values.push_back(vs[i]);
        spec_pointers.push_back(at + "/values/" + std::to_string(i));
      }
    } else {
      const std::string ra = at + "/range";
      r.Keys(j["range"], ra, {"from", "to", "step"});
      for (const char* k : {"from", "to", "step"})
        if (!j["range"].contains(k)) r.Fail(ra, std::string("missing \"") + k + "\"");
      const double from = r.Number(j["range"]["from"], ra + "/from");
      const double to = r.Number(j["range"]["to"], ra + "/to");
      const double step = r.Number(j["range"]["step"], ra + "/step");
      if (!(step > 0)) r.Fail(ra + "/step", "expected a number > 0");
      if (!(to >= from)) r.Fail(ra + "/to", "expected a number >= from");
      const double n = std::floor((to - from) / step + 1e-9) + 1;
      if (n > 10000) r.Fail(ra, "refused: " + core::FormatNumber(n) + " values (at most 10000)");
      for (int i = 0; i < static_cast<int>(n); ++i) {
        // Rounded to 12 significant digits: 0.1 * 3 is 0.3, not 0.30000000000000004.
        values.push_back(std::stod(core::FormatNumber(from + i * step)));
        spec_pointers.push_back(ra);
      }
    }
    std::set<std::string> seen;
    for (std::size_t i = 0; i < values.size(); ++i) {
      SweepValue v;
      v.label = Label(values[i]);
      if (!seen.insert(v.label).second)  // 0 and 0.0 are one value
        r.Fail(spec_pointers[i], "repeats an earlier value of this parameter");
      v.set.emplace_back(p.pointer, values[i]);
      p.values.push_back(std::move(v));
    }
    // "rain (mm/h)" for a key with a unit suffix, else the name and pointer.
    const std::string leaf_label = AxisLabelOfKey(Leaf(p.pointer));
    p.axis_label =
        leaf_label.find(" (") != std::string::npos ? leaf_label : p.name + " (" + p.pointer + ")";
  }
  if (j.contains("axis_label")) p.axis_label = r.String(j["axis_label"], at + "/axis_label");
  value_pointers.push_back(spec_pointers);
  return p;
}

std::vector<std::uint64_t> ReadSeeds(const SpecReader& r, const Json& j) {
  std::vector<std::uint64_t> seeds;
  if (j.is_array()) {
    if (j.empty()) r.Fail("/seeds", "expected at least one seed");
    for (std::size_t i = 0; i < j.size(); ++i) {
      seeds.push_back(r.Seed(j[i], "/seeds/" + std::to_string(i)));
      if (std::count(seeds.begin(), seeds.end(), seeds.back()) > 1)
        r.Fail("/seeds/" + std::to_string(i), "repeats an earlier seed");
    }
  } else if (j.is_object()) {
    r.Keys(j, "/seeds", {"from", "count"});
    if (!j.contains("from") || !j.contains("count"))
      r.Fail("/seeds", "expected {\"from\": first seed, \"count\": how many}");
    const std::uint64_t from = r.Seed(j["from"], "/seeds/from");
    const std::uint64_t count = r.Seed(j["count"], "/seeds/count");
    if (count < 1 || count > 10000) r.Fail("/seeds/count", "expected an integer from 1 to 10000");
    if (from > (~0ull >> 1) - count) r.Fail("/seeds/from", "the seeds would overflow");
    for (std::uint64_t i = 0; i < count; ++i) seeds.push_back(from + i);
  } else {
    r.Fail("/seeds",
           "expected an array of seeds or {\"from\", \"count\"}, got " + core::DescribeValue(j));
  }
  return seeds;
}

// The base scenario of a spec: a file (relative to the spec) or inline,
// and where its paths resolve.
struct BaseScenario {
  Json json;
  std::string file, dir;
};

BaseScenario ReadBaseScenario(const SpecReader& r, const Json& spec, const std::string& path,
                              const std::string& spec_dir) {
  if (!spec.contains("scenario")) r.Fail("", "missing \"scenario\" (a scenario file or object)");
  BaseScenario base{Json(), path, spec_dir};
  if (spec["scenario"].is_string()) {
    const fs::path p =
        (fs::path(spec_dir) / spec["scenario"].get<std::string>()).lexically_normal();
    std::error_code ec;
    if (!fs::is_regular_file(p, ec)) r.Fail("/scenario", "file not found: " + p.string());
    base.file = p.string();
    base.json = core::LoadJsonFile(base.file);
    base.dir = p.parent_path().empty() ? "." : p.parent_path().string();
  } else if (spec["scenario"].is_object()) {
    base.json = spec["scenario"];
  } else {
    r.Fail("/scenario", "expected a scenario file's path or a scenario object, got " +
                            core::DescribeValue(spec["scenario"]));
  }
  return base;
}

// Applies the spec's "set" to the base scenario; returns which spec
// location set each scenario pointer (the blame list).
std::vector<Assignment> ApplyFixedSets(const SpecReader& r, const Json& spec, Json& base) {
  std::vector<Assignment> fixed;
  if (!spec.contains("set")) return fixed;
  if (!spec["set"].is_object()) r.Fail("/set", "expected an object of \"/json/pointer\": value");
  for (const auto& [ptr, val] : spec["set"].items()) {
    const std::string at = "/set/" + core::EscapePointerToken(ptr);
    r.Pointer(Json(ptr), at);
    try {
      SetPointer(base, ptr, val);
    } catch (const ConfigError& e) {
      r.Fail(at, e.message());
    }
    fixed.push_back({ptr, at, at});
  }
  return fixed;
}

// The spec location to blame for a scenario error at `pointer`: the last
// assignment that covers it, else the base scenario.
std::string Blame(const std::vector<Assignment>& blame, const std::string& pointer) {
  std::string at = "/scenario";
  for (const Assignment& a : blame)
    if (Covers(a.pointer, pointer)) at = a.Blame(pointer);
  return at;
}

// One point's scenario document: the base scenario with the parameters'
// values at `index` and `seed` applied. `blame` (when given) receives which
// spec location set each scenario pointer; `what` names the point.
Json PointDocument(const SpecReader& r, const SweepSpec& out, const Json& base_json,
                   const std::vector<std::vector<std::string>>& value_pointers,
                   const SweepPointSpec& pt, std::vector<Assignment>* blame, std::string* what) {
  Json doc = base_json;
  if (what) *what = "point " + pt.id + " (";
  for (std::size_t k = 0; k < out.parameters.size(); ++k) {
    const SweepValue& v = out.parameters[k].values[pt.value_index[k]];
    if (what) *what += out.parameters[k].name + "=" + v.label + ", ";
    for (const auto& [ptr, val] : v.set) {
      const bool cases = out.parameters[k].pointer.empty();
      const std::string at =
          cases ? value_pointers[k][pt.value_index[k]] + "/" + core::EscapePointerToken(ptr)
                : value_pointers[k][pt.value_index[k]];
      const std::string key = cases ? at : "/parameters/" + std::to_string(k) + "/pointer";
      try {
        SetPointer(doc, ptr, val);
      } catch (const ConfigError& e) {
        r.Fail(key, "point " + pt.id + ": " + e.Located());
      }
      if (blame) blame->push_back({ptr, at, key});
    }
  }
  if (what) *what += "seed=" + std::to_string(pt.seed) + ")";
  doc["seed"] = pt.seed;
  return doc;
}

// One point of the grid: the parameters' values at `index` and `seed`,
// applied to the base scenario and checked (the scenario is not kept: a
// grid of many points would hold as many whole scenarios).
SweepPointSpec MakePoint(const SpecReader& r, const SweepSpec& out, const BaseScenario& base,
                         const std::vector<Assignment>& fixed,
                         const std::vector<std::vector<std::string>>& value_pointers,
                         const std::vector<int>& index, std::uint64_t seed, std::size_t point) {
  SweepPointSpec pt;
  char id[32];
  std::snprintf(id, sizeof id, "p%04zu", point);
  pt.id = id;
  pt.value_index = index;
  pt.seed = seed;
  std::vector<Assignment> blame = fixed;
  std::string what;
  const Json doc = PointDocument(r, out, base.json, value_pointers, pt, &blame, &what);
  try {
    ScenarioFromJson(doc, base.file, base.dir);
  } catch (const ConfigError& e) {
    r.Fail(Blame(blame, e.pointer()), what + ": " + e.Located());
  }
  return pt;
}

// The grid: the parameters' values as an odometer (last fastest), then the
// seeds; each point's scenario checked now, before anything runs.
void BuildGrid(const SpecReader& r, SweepSpec& out, const BaseScenario& base,
               const std::vector<Assignment>& fixed,
               const std::vector<std::vector<std::string>>& value_pointers, bool quiet) {
  double grid = static_cast<double>(out.seeds.size());
  for (const auto& p : out.parameters) grid *= static_cast<double>(p.values.size());
  if (grid > static_cast<double>(kMaxSweepPoints))
    r.Fail("/parameters", "refused: the grid has " + core::FormatNumber(grid) +
                              " points (at most " + std::to_string(kMaxSweepPoints) + ")");
  // About a millisecond a point: a large grid shows progress and stops on
  // Ctrl-C.
  core::Progress progress("checking the sweep's points", grid, "points", quiet || grid < 1000);
  std::vector<int> index(out.parameters.size(), 0);
  std::size_t point = 0;
  while (true) {
    for (std::uint64_t seed : out.seeds) {
      core::ThrowIfInterrupted();
      out.points.push_back(MakePoint(r, out, base, fixed, value_pointers, index, seed, point++));
      progress.Update(static_cast<double>(point));
    }
    int k = static_cast<int>(out.parameters.size()) - 1;
    while (k >= 0 && ++index[k] == static_cast<int>(out.parameters[k].values.size()))
      index[k--] = 0;
    if (k < 0) break;
  }
  progress.Finish();
}

std::string ReadSpecName(const SpecReader& r, const Json& spec, const std::string& path) {
  const std::string name =
      spec.contains("name") ? r.String(spec["name"], "/name") : fs::path(path).stem().string();
  if (!ValidName(name))
    r.Fail(spec.contains("name") ? "/name" : "",
           spec.contains("name")
               ? "expected letters, digits, '_' or '-' (it names the output folder)"
               : "the file name \"" + name +
                     "\" cannot name the output folder: give the spec a \"name\" of letters, "
                     "digits, '_' or '-'");
  return name;
}

}  // namespace

SweepSpec LoadSweepSpec(const std::string& path, bool quiet) {
  const std::string dir = fs::path(path).parent_path().string();
  return SweepSpecFromJson(core::LoadJsonFile(path), path, dir.empty() ? "." : dir, quiet);
}

SweepSpec SweepSpecFromJson(const Json& spec, const std::string& path, const std::string& spec_dir,
                            bool quiet) {
  const SpecReader r{path};
  r.Keys(spec, "", {"name", "scenario", "set", "parameters", "seeds"});
  SweepSpec out;
  out.file = path;
  out.name = ReadSpecName(r, spec, path);
  BaseScenario base = ReadBaseScenario(r, spec, path, spec_dir);
  const std::vector<Assignment> fixed = ApplyFixedSets(r, spec, base.json);
  try {
    out.base_resolved = ResolvedJson(ScenarioFromJson(base.json, base.file, base.dir));
  } catch (const ConfigError& e) {
    r.Fail(Blame(fixed, e.pointer()), "the base scenario: " + std::string(e.what()));
  }

  std::vector<std::vector<std::string>> value_pointers;
  if (spec.contains("parameters")) {
    const Json& ps = spec["parameters"];
    if (!ps.is_array()) r.Fail("/parameters", "expected an array of parameters");
    std::set<std::string> names;
    for (std::size_t i = 0; i < ps.size(); ++i) {
      const std::string at = "/parameters/" + std::to_string(i);
      out.parameters.push_back(ReadParameter(r, ps[i], at, value_pointers));
      if (!names.insert(out.parameters.back().name).second)
        r.Fail(at + "/name", "repeats an earlier parameter's name");
    }
  }
  out.seeds = spec.contains("seeds")
                  ? ReadSeeds(r, spec["seeds"])
                  : std::vector<std::uint64_t>{out.base_resolved.at("seed").get<std::uint64_t>()};
  BuildGrid(r, out, base, fixed, value_pointers, quiet);
  out.base_file = base.file;
  out.base_dir = base.dir;
  out.value_pointers = std::move(value_pointers);

  out.canonical = spec;
  out.canonical["name"] = out.name;
  out.canonical["scenario"] = std::move(base.json);
  out.canonical.erase("set");
  out.canonical["seeds"] = out.seeds;
  return out;
}

Scenario SweepSpec::PointScenario(std::size_t i) const {
  const SpecReader r{file};
  return ScenarioFromJson(PointDocument(r, *this, canonical.at("scenario"), value_pointers,
                                        points.at(i), nullptr, nullptr),
                          base_file, base_dir);
}

std::vector<results::SweepParameter> SweepSpec::TableParameters() const {
  std::vector<results::SweepParameter> t;
  for (const SweepParameter& p : parameters) {
    results::SweepParameter q;
    q.name = p.name;
    for (const SweepValue& v : p.values) q.labels.push_back(v.label);
    t.push_back(std::move(q));
  }
  return t;
}

std::vector<results::SweepAxis> SweepSpec::Axes() const {
  std::vector<results::SweepAxis> axes;
  const auto finish = [&](results::SweepAxis a) {
    if (a.x_of_value.size() < 2) return;
    double lo = a.x_of_value.front().second, hi = lo;
    for (const auto& [i, x] : a.x_of_value) lo = std::min(lo, x), hi = std::max(hi, x);
    a.log_x = lo > 0 && hi / lo >= 20;
    std::sort(a.x_of_value.begin(), a.x_of_value.end(),
              [](const auto& u, const auto& v) { return u.second < v.second; });
    axes.push_back(std::move(a));
  };
  const Json& resolved_base = base_resolved;
  for (std::size_t k = 0; k < parameters.size(); ++k) {
    const SweepParameter& p = parameters[k];
    if (!p.pointer.empty()) {
      // RMSE against the parameter itself, when its values are numbers.
      results::SweepAxis a;
      a.stem = "vs_" + p.name;
      a.x_label = p.axis_label;
      a.parameter = static_cast<int>(k);
      bool numeric = true;
      for (std::size_t i = 0; i < p.values.size(); ++i) {
        const Json& v = p.values[i].set.front().second;
        numeric = numeric && v.is_number();
        if (v.is_number()) a.x_of_value.emplace_back(static_cast<int>(i), v.get<double>());
      }
      if (numeric) finish(std::move(a));
      continue;
    }
    // Cases: for each pointer some case sets to a number, the curve over
    // the cases that set only it (and the cases that set nothing, at the
    // base value), e.g. RMSE vs rain rate over clear, rain 10, rain 50.
    std::vector<std::string> pointers;
    for (const SweepValue& v : p.values)
      for (const auto& [ptr, val] : v.set)
        if (val.is_number() && std::find(pointers.begin(), pointers.end(), ptr) == pointers.end())
          pointers.push_back(ptr);
    for (const std::string& ptr : pointers) {
      results::SweepAxis a;
      a.stem = "vs_" + Leaf(ptr);
      a.x_label = AxisLabelOfKey(Leaf(ptr));
      a.parameter = static_cast<int>(k);
      for (std::size_t i = 0; i < p.values.size(); ++i) {
        const auto& set = p.values[i].set;
        if (set.size() == 1 && set[0].first == ptr && set[0].second.is_number()) {
          a.x_of_value.emplace_back(static_cast<int>(i), set[0].second.get<double>());
        } else if (set.empty()) {
          const Json::json_pointer jp(ptr);
          if (resolved_base.contains(jp) && resolved_base.at(jp).is_number())
            a.x_of_value.emplace_back(static_cast<int>(i), resolved_base.at(jp).get<double>());
        }
      }
      finish(std::move(a));
    }
  }
  return axes;
}

}  // namespace uavsim::sim
