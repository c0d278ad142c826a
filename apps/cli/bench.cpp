// `uavsim bench`: the hot paths and the paper's Table III.
#include <algorithm>
#include <functional>
#include <iostream>

#include "apps/bench/bench_beam.h"
#include "apps/bench/bench_camera.h"
#include "apps/bench/bench_events.h"
#include "apps/bench/bench_flops.h"
#include "apps/bench/bench_link.h"
#include "apps/bench/bench_noise.h"
#include "apps/bench/bench_pipeline.h"
#include "apps/bench/bench_radar.h"
#include "apps/bench/bench_raycast.h"
#include "apps/cli/cli.h"
#include "core/error.h"

namespace uavsim::cli {
using core::UsageError;

int RunBenchCommand(const ParsedArgs& a, int, char**) {
  if (a.positional.size() > 1)
    throw UsageError("uavsim bench: expected at most one target (see uavsim bench --help)");
  const std::string what = a.positional.empty() ? "all" : a.positional[0];
  const bool quiet = a.Has("--quiet");
  const std::vector<std::pair<std::string, std::function<int()>>> targets{
      {"raycast", [&] { return sim::BenchRaycast(quiet, std::cout); }},
      {"camera", [&] { return sim::BenchCamera(quiet, std::cout); }},
      {"radar", [&] { return sim::BenchRadar(quiet, std::cout); }},
      {"events", [&] { return sim::BenchEvents(quiet, std::cout); }},
      {"link", [&] { return sim::BenchLink(quiet, std::cout); }},
      {"beam", [&] { return sim::BenchBeam(quiet, std::cout); }},
      {"pipeline", [&] { return sim::BenchPipeline(quiet, std::cout); }},
      {"noise", [&] { return sim::BenchNoise(quiet, std::cout); }},
      {"flops", [&] { return sim::BenchFlops(quiet, std::cout); }},
  };
  int rc = kExitOk;
  bool found = false;
  for (const auto& [name, run] : targets) {
    if (what != "all" && what != name) continue;
    found = true;
    if (what == "all") std::cout << "== " << name << "\n";
    rc = std::max(rc, run());
  }
  if (!found)
    throw UsageError(
        "uavsim bench: unknown target '" + what +
        "' (raycast, camera, radar, events, link, beam, pipeline, noise, flops or all)");
  return rc;
}

}  // namespace uavsim::cli
