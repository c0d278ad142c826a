// `uavsim run`: one scenario end to end into its run directory.
#include <unistd.h>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iostream>

#include "apps/cli/cli.h"
#include "core/error.h"
#include "sim/edge_server.h"
#include "sim/run.h"
#include "sim/run_cost.h"
#include "sim/scenario.h"

namespace uavsim::cli {
namespace {

using core::UsageError;

// Where the time went, on a terminal: the three largest parts of the
// run's profile_s (metrics.json has them all).
void PrintTopParts(const sim::RunSummary& summary) {
  std::vector<std::pair<std::string, double>> parts = summary.profile_s;
  std::stable_sort(parts.begin(), parts.end(),
                   [](const auto& a, const auto& b) { return a.second > b.second; });
  if (parts.empty() || summary.wall_s <= 0.0) return;
  std::printf("time:");
  for (std::size_t i = 0; i < parts.size() && i < 3; ++i)
    std::printf("%s %s %.1f s (%.0f %%)", i ? "," : "", parts[i].first.c_str(), parts[i].second,
                100.0 * parts[i].second / summary.wall_s);
  std::printf(" (profile_s in metrics.json)\n");
}

}  // namespace

int RunRunCommand(const ParsedArgs& a, int, char**) {
  Verbose() = a.Has("--verbose");
  const std::string& file = OneScenario("run", a);
  std::vector<std::string> overrides = Overrides(a);
  if (auto seed = a.Value("--seed")) {
    if (seed->empty() || seed->find_first_not_of("0123456789") != std::string::npos ||
        seed->size() > 19)
      throw UsageError("uavsim run: --seed expects a non-negative integer, got '" + *seed + "'");
    overrides.push_back("/seed=" + *seed);
  }
  if (auto d = a.Value("--duration")) {
    char* end = nullptr;
    const double v = std::strtod(d->c_str(), &end);
    if (d->empty() || *end != '\0' || !(v > 0))
      throw UsageError("uavsim run: --duration expects a positive number of seconds, got '" + *d +
                       "'");
    overrides.push_back("/duration_s=" + *d);
  }
  sim::RunOptions o;
  o.quiet = a.Has("--quiet");
  o.force = a.Has("--force");
  o.scenario_file = file;
  o.record = RecordList("run", a);
  o.trace_dir = a.Value("--trace").value_or("");
  o.replay_dir = a.Value("--replay").value_or("");
  if (a.Has("--trace") && o.trace_dir.empty())
    throw UsageError("uavsim run: --trace expects a folder");
  if (a.Has("--replay") && o.replay_dir.empty())
    throw UsageError("uavsim run: --replay expects a folder");
  if (!o.replay_dir.empty() && !o.trace_dir.empty())
    throw UsageError(
        "uavsim run: --trace and --replay: give one (a replay senses nothing to trace)");
  if (!o.replay_dir.empty() && !o.record.empty())
    throw UsageError("uavsim run: --replay and --record: a trace holds no sensor frames to record");
  const sim::Scenario s = sim::LoadScenario(file, overrides);
  sim::CheckTrainedModel(s, file, a.Has("--quiet"));  // what validate checks, first
  o.out_dir = a.Value("--out").value_or("runs/" + s.name + "-s" + std::to_string(s.seed));
  sim::RequireRoomToRecord(s, o.record, o.out_dir, "uavsim run");
  const auto summary = sim::RunScenario(s, o);
  if (!o.quiet) {
    std::printf("%s: %g s simulated in %.3f s (%.3gx real time); truth.csv %zu rows; frames",
                o.out_dir.c_str(), summary.sim_s, summary.wall_s,
                summary.wall_s > 0 ? summary.sim_s / summary.wall_s : 0.0, summary.truth_rows);
    for (const auto& [m, n] : summary.frames)
      std::printf(" %s %llu", m.c_str(), static_cast<unsigned long long>(n));
    std::printf("\n");
    if (!summary.rmse_m.empty()) {
      std::printf("RMSE (m):");
      for (const auto& [method, rmse] : summary.rmse_m) {
        if (rmse)
          std::printf(" %s %.3f", method.c_str(), *rmse);
        else
          std::printf(" %s n/a", method.c_str());
      }
      std::printf("\n");
    }
    if (!summary.rmse_common_m.empty()) {
      std::printf("RMSE (m) over the %llu windows every method estimated:",
                  static_cast<unsigned long long>(summary.common_windows));
      for (const auto& [method, rmse] : summary.rmse_common_m)
        std::printf(" %s %.3f", method.c_str(), rmse);
      std::printf("\n");
    }
    if (::isatty(STDOUT_FILENO)) PrintTopParts(summary);
  }
  return kExitOk;
}

}  // namespace uavsim::cli
