// libFuzzer target: a sweep spec's text through the whole strict loader
// (ParseJsonText, then SweepSpecFromJson with scenarios/sweeps/ as the
// spec's folder, so the shipped specs' "../default.json" resolves), which
// checks every grid point's scenario.
//
// The loader checks each point's whole scenario (about 6 ms a point under
// ASan): a 150-byte spec with 2000 points takes 12 s.
// Grids of more than kMaxFuzzPoints points are therefore skipped unless they
// exceed sim::kMaxSweepPoints, whose refusal comes before any point is
// built. The estimate below mirrors BuildGrid's count (values, cases or a
// range per parameter, times the seeds); what it cannot count it takes as 1
// and leaves to the loader.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "apps/sweep/sweep_spec.h"
#include "core/json_io.h"
#include "fuzz_support.h"

namespace {

using uavsim::core::Json;

constexpr double kMaxFuzzPoints = 64;

double CountOf(const Json& p) {
  if (!p.is_object()) return 1;
  for (const char* key : {"values", "cases"})
    if (p.contains(key) && p[key].is_array()) return std::max<double>(1, p[key].size());
  if (p.contains("range") && p["range"].is_object()) {
    const Json& r = p["range"];
    if (r.contains("from") && r.contains("to") && r.contains("step") && r["from"].is_number() &&
        r["to"].is_number() && r["step"].is_number()) {
      const double from = r["from"].get<double>(), to = r["to"].get<double>();
      const double step = r["step"].get<double>();
      if (step > 0 && to >= from) return std::floor((to - from) / step + 1e-9) + 1;
    }
  }
  return 1;
}

// An upper estimate of the grid's points (1 when the spec is not an object).
double GridPoints(const Json& spec) {
  if (!spec.is_object()) return 1;
  double n = 1;
  if (spec.contains("parameters") && spec["parameters"].is_array())
    for (const Json& p : spec["parameters"]) n *= CountOf(p);
  if (spec.contains("seeds")) {
    const Json& s = spec["seeds"];
    if (s.is_array()) n *= std::max<double>(1, s.size());
    if (s.is_object() && s.contains("count") && s["count"].is_number())
      n *= std::max(1.0, s["count"].get<double>());
  }
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace uavsim;
  fuzz::RunLoader(data, size, [](const std::string& text) {
    const Json doc = core::ParseJsonText(text, "fuzz.json");
    const double points = GridPoints(doc);
    if (points > kMaxFuzzPoints && points <= static_cast<double>(sim::kMaxSweepPoints)) return;
    const sim::SweepSpec spec =
        sim::SweepSpecFromJson(doc, "fuzz.json", UAVSIM_SCENARIOS_DIR "/sweeps");
    (void)spec.Axes();
    (void)spec.TableParameters();
  });
  return 0;
}
