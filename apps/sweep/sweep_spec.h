// A sweep specification: a base scenario, parameters that each set one JSON
// pointer of it (a list or range of values) or several at once (named
// cases), and replications as seeds. Its grid is the Cartesian product of
// the parameters' values times the seeds; every point is a whole scenario.
//
//   {
//     "name": "loss_weather",
//     "scenario": "../default.json",              (a path, or the scenario inline)
//     "set": { "/duration_s": 20 },               (overrides for every point)
//     "parameters": [
//       { "name": "loss", "pointer": "/links/default/loss/p", "values": [0, 0.2, 0.4],
//         "axis_label": "Packet loss probability" },
//       { "name": "rain", "pointer": "/weather/rain_mm_h",
//         "range": { "from": 0, "to": 50, "step": 25 } },
//       { "name": "weather", "cases": [ { "label": "clear", "set": {} },
//                                        { "label": "fog 300 m",
//                                          "set": { "/weather/fog_visibility_m": 300 } } ] }
//     ],
//     "seeds": [1, 2, 3]                           (or { "from": 1, "count": 3 })
//   }
//
// Loading is strict like a scenario's: unknown keys, wrong types, and every
// grid point's scenario are checked before anything runs; errors name the
// spec file and the spec's JSON pointer (and the point, for a value that is
// invalid in the scenario).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/json_io.h"
#include "results/sweep_report.h"
#include "sim/scenario.h"

namespace uavsim::sim {

// One value of a parameter: the assignments it makes, and how tables show it.
struct SweepValue {
  std::string label;
  std::vector<std::pair<std::string, core::Json>> set;  // JSON pointer -> value
};

struct SweepParameter {
  std::string name;
  std::string pointer;     // "" for a cases parameter
  std::string axis_label;  // for plots
  std::vector<SweepValue> values;
};

struct SweepPointSpec {
  std::string id;                // "p0000", ... in grid order
  std::vector<int> value_index;  // per parameter
  std::uint64_t seed = 0;
};

struct SweepSpec {
  std::string file;  // where it was read from
  std::string name;
  std::vector<SweepParameter> parameters;
  std::vector<std::uint64_t> seeds;
  std::vector<SweepPointSpec> points;  // parameters' values (last fastest), then seeds
  core::Json canonical;                // the spec with the base scenario inline (its "set" applied)
  core::Json base_resolved;            // the base scenario (with "set"), every default filled
  // With canonical["scenario"], the recipe PointScenario() follows: where
  // the base scenario was read (paths in it resolve against base_dir), and
  // per parameter the spec's JSON pointer to each of its values.
  std::string base_file, base_dir;
  std::vector<std::vector<std::string>> value_pointers;

  // Point i's scenario, rebuilt from the base and the point's values (every
  // point was checked at load; the scenarios are not kept, so a large grid
  // costs its recipe, not a whole scenario per point). Same result each call.
  Scenario PointScenario(std::size_t i) const;
  // What the tables and plots show (results/sweep_report.h).
  std::vector<results::SweepParameter> TableParameters() const;
  std::vector<results::SweepAxis> Axes() const;
};

// Refuses grids larger than this many points.
constexpr std::size_t kMaxSweepPoints = 100000;

// Throws core::ConfigError naming the file and the spec's JSON pointer, and
// core::Interrupted on a termination request while it checks the points
// (about a millisecond each; with !quiet, progress on a terminal).
SweepSpec LoadSweepSpec(const std::string& path, bool quiet = true);
// The same from a document already in memory: `file` names it in messages
// (and, without a "name", names the sweep by its stem); `base_dir` resolves a
// base scenario given as a path.
SweepSpec SweepSpecFromJson(const core::Json& spec, const std::string& file,
                            const std::string& base_dir, bool quiet = true);

}  // namespace uavsim::sim
