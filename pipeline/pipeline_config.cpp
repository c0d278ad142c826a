#include "pipeline/pipeline_config.h"

#include <stdexcept>

#include "pipeline/training/variants.h"
#include "sim/core/json_io.h"

namespace uavsim::pipeline {

using core::Rule;

const std::vector<std::string>& KnownMethods() {
  static const std::vector<std::string> names{"uavloc",      "uavloc_anchored", "anchor_track",
                                              "ekf",         "uavloc_camera",   "uavloc_lidar",
                                              "uavloc_radar"};
  return names;
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
  for (const char* fixed : {"anchor_track", "ekf", "uavloc_anchored"})
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
  v("methods", c.methods);
  if constexpr (V::kReading)
    for (std::size_t i = 0; i < c.methods.size(); ++i)
      if (!ParseMethod(c.methods[i]))
        throw core::ConfigError(
            v.file(), v.Child("methods") + "/" + std::to_string(i),
            "expected one of \"uavloc\", \"uavloc_anchored\", \"anchor_track\", \"ekf\", "
            "\"uavloc_camera\", \"uavloc_lidar\", \"uavloc_radar\", a variant's method (" +
                VariantNames() +
                "; paper is uavloc), or a learned one with a modality subset, e.g. "
                "uavloc[camera+lidar]; got \"" +
                c.methods[i] + "\"");
  v("uavloc_wait_for_track", c.uavloc_wait_for_track);
  v.Object("preprocess", c.preprocess);
  v.Object("ekf", c.ekf);
}
UAVSIM_INSTANTIATE_VISIT(PipelineConfig);

}  // namespace uavsim::pipeline
