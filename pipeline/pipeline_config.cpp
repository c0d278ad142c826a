#include "pipeline/pipeline_config.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

#include "core/json_io.h"
#include "pipeline/variants.h"

namespace uavsim::pipeline {

using core::Rule;

const std::vector<std::string>& KnownMethods() {
  static const std::vector<std::string> names{
      "uavloc",       "uavloc_anchored", "anchor_track", "ekf",      "uavloc_camera",
      "uavloc_lidar", "uavloc_radar",    "mtt",          "mtt_jpda", "uavloc_per_track"};
  return names;
}

bool RunsMultiTarget(const PipelineConfig& p) {
  return std::find(p.methods.begin(), p.methods.end(), "mtt") != p.methods.end() ||
         std::find(p.methods.begin(), p.methods.end(), "mtt_jpda") != p.methods.end() ||
         std::find(p.methods.begin(), p.methods.end(), "uavloc_per_track") != p.methods.end();
}

std::string ModalitySubsetName(int bits) {
  if (bits < 1 || bits > kModalitySubsets)
    throw std::invalid_argument("ModalitySubsetName: bits " + std::to_string(bits) +
                                " is not in [1, 7]");
  if (bits == kModalitySubsets) return "all";
  const char* const kNames[] = {"camera", "lidar", "radar"};
  std::string name;
  for (int m = 0; m < kModalityCount; ++m)
    if (bits & (1 << m)) name += (name.empty() ? "" : "+") + std::string(kNames[m]);
  return name;
}

std::optional<MethodName> ParseMethod(const std::string& name) {
  for (const char* fixed :
       {"anchor_track", "ekf", "uavloc_anchored", "mtt", "mtt_jpda", "uavloc_per_track"})
    if (name == fixed) return MethodName{"", kModalitySubsets};
  for (int m = 0; m < kModalityCount; ++m)
    if (name == "uavloc_" + ModalitySubsetName(1 << m)) return MethodName{"uavloc", 1 << m};
  std::string base = name;
  int bits = kModalitySubsets;
  if (const auto open = name.find('['); open != std::string::npos) {
    if (name.back() != ']') return std::nullopt;
    base = name.substr(0, open);
    const std::string subset = name.substr(open + 1, name.size() - open - 2);
    bits = 0;
    for (int b = 1; b <= kModalitySubsets; ++b)
      if (ModalitySubsetName(b) == subset) bits = b;
    if (bits == 0) return std::nullopt;
  }
  if (base == "uavloc") return MethodName{base, bits};
  for (const Variant& v : Variants())
    if (base == VariantMethod(v.name)) return MethodName{base, bits};
  return std::nullopt;
}

const ScriptedMethod* PipelineConfig::FindScripted(const std::string& name) const {
  for (const ScriptedMethod& s : scripted)
    if (s.name == name) return &s;
  return nullptr;
}

const HostedMethod* PipelineConfig::FindHosted(const std::string& name) const {
  for (const HostedMethod& h : hosted)
    if (h.name == name) return &h;
  return nullptr;
}

namespace {

// A scripted method's name: letters, digits and _ (it names columns and
// files), not a built-in method's or a variant's.
bool ValidScriptedName(const std::string& name) {
  if (name.empty() || name.size() > 64) return false;
  for (char ch : name)
    if (!(std::isalnum(static_cast<unsigned char>(ch)) || ch == '_')) return false;
  return !ParseMethod(name);
}

// A /pipeline/methods entry that is an object: a TorchScript method
// {"type": "torchscript", "name", "edge"} or a hosted one {"type": "python",
// "name", "history_windows"}. Returns its name.
std::string ReadMethodObject(const core::Json& e, const std::string& file, const std::string& p,
                             PipelineConfig& c) {
  std::string type = "torchscript", name;
  std::string edge;
  int history = 1;
  core::JsonReader r(e, file, p);
  r("type", type);
  r("name", name);
  r.Check(type == "torchscript" || type == "python", "type",
          "expected \"torchscript\" or \"python\", got \"" + type + "\"");
  r.Check(r.Has("name"), "name", "expected the method's name");
  r.Check(name.empty() || ValidScriptedName(name), "name",
          "expected letters, digits and _ (at most 64), not a built-in method's or a "
          "variant's name, got \"" +
              name + "\"");
  if (type == "python") {
    r("history_windows", history, Rule::Range(1, 10000));
    r.Finish();
    c.hosted.push_back({name, history});
    return name;
  }
  r("edge", edge);
  r.Check(!edge.empty(), "edge", "expected the path of the TorchScript file");
  r.Finish();
  c.scripted.push_back({name, edge});
  return name;
}

// /pipeline/methods: each entry a method's name or a TorchScript or hosted
// method's object; no name twice.
void ReadMethods(const core::Json& j, const std::string& file, const std::string& at,
                 PipelineConfig& c) {
  if (!j.is_array())
    throw core::ConfigError(
        file, at,
        "expected an array of strings (method names) or TorchScript method objects, got " +
            core::DescribeValue(j));
  if (j.size() > 256)
    throw core::ConfigError(file, at,
                            "expected at most 256 methods, got " + std::to_string(j.size()));
  c.methods.clear();
  c.scripted.clear();
  c.hosted.clear();
  for (std::size_t i = 0; i < j.size(); ++i) {
    const std::string p = at + "/" + std::to_string(i);
    const core::Json& e = j[i];
    std::string name;
    if (e.is_object()) {
      name = ReadMethodObject(e, file, p, c);
    } else if (e.is_string()) {
      name = e.get<std::string>();
      if (!ParseMethod(name))
        throw core::ConfigError(
            file, p,
            "expected one of \"uavloc\", \"uavloc_anchored\", \"anchor_track\", \"ekf\", "
            "\"uavloc_camera\", \"uavloc_lidar\", \"uavloc_radar\", a variant's method (" +
                VariantNames() +
                "; paper is uavloc), a learned one with a modality subset, e.g. "
                "uavloc[camera+lidar], or a TorchScript model {\"type\": \"torchscript\", "
                "\"name\": ..., \"edge\": FILE}; got \"" +
                name + "\"");
    } else {
      throw core::ConfigError(file, p,
                              "expected a method's name or a {\"type\": \"torchscript\", ...} "
                              "object, got " +
                                  core::DescribeValue(e));
    }
    if (std::find(c.methods.begin(), c.methods.end(), name) != c.methods.end())
      throw core::ConfigError(file, p, "duplicate entry \"" + name + "\"");
    c.methods.push_back(name);
  }
}

}  // namespace

template <class V>
void Visit(V& v, PipelineConfig& c) {
  v("model", c.model);
  v.Check(!c.model.empty(), "model", "expected \"default\" or the path of a trained model");
  v("window_s", c.window_s, Rule{0.0, 10.0, true, false});
  v("latent_dim", c.latent_dim, Rule::Range(1, 4096));
  v.Check(c.latent_dim == 4 || c.latent_dim == 8 || c.latent_dim == 16 || c.latent_dim == 32 ||
              c.latent_dim == 64,
          "latent_dim",
          "expected one of 4, 8, 16, 32, 64 (paper Sec. VI), got " + std::to_string(c.latent_dim));
  v("late_allowance_s", c.late_allowance_s, Rule::NonNegative(10.0));
  if constexpr (V::kReading) {
    if (const core::Json* j = v.Raw("methods")) ReadMethods(*j, v.file(), v.Child("methods"), c);
  } else {
    core::Json list = core::Json::array();
    for (const std::string& name : c.methods)
      if (const ScriptedMethod* s = c.FindScripted(name))
        list.push_back({{"type", "torchscript"}, {"name", s->name}, {"edge", s->edge}});
      else if (const HostedMethod* h = c.FindHosted(name))
        list.push_back(
            {{"type", "python"}, {"name", h->name}, {"history_windows", h->history_windows}});
      else
        list.push_back(name);
    v.Raw("methods", std::move(list));
  }
  v("uavloc_wait_for_track", c.uavloc_wait_for_track);
  v.Object("preprocess", c.preprocess);
  v.Object("ekf", c.ekf);
}
UAVSIM_INSTANTIATE_VISIT(PipelineConfig);

}  // namespace uavsim::pipeline
