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
namespace {

using core::UsageError;

const char* kHelp =
    "usage: uavsim bench [raycast|camera|radar|events|link|beam|pipeline|noise|flops|all] "
    "[--quiet]\n"
    "\n"
    "  raycast    Embree rtcIntersect1 throughput vs each sensor's rays per second in the\n"
    "             default city; the camera's packet speed-up; camera + LiDAR real-time factor\n"
    "  camera     the camera node per stereo frame, one thread: capture (cached, its noise,\n"
    "             uncached) and pre-processing with its steps (remap, MOG2, closing,\n"
    "             labelling, running means)\n"
    "  radar      FMCW radar frame: scatterers (with the static cache and without), IF-cube\n"
    "             synthesis, processing (one thread)\n"
    "  events     the event core: hold model (pop earliest, schedule one at a random delay)\n"
    "             with 1e3..1e6 pending events; events per second\n"
    "  link       messages per second through one uplink under the event core\n"
    "  beam       downlink beam evaluations per second (channel, steering, gain)\n"
    "  pipeline   IB-CC encode per frame (camera, LiDAR, radar) and edge inference per\n"
    "             window, one thread\n"
    "  noise      standard normals per second: counter-based Ziggurat vs RngStream::Normal\n"
    "  flops      the paper's Table III: MFLOPs per frame of each encoder (counted from the\n"
    "             layers' shapes, 2 FLOPs per multiply-add as in the paper) and of each\n"
    "             pre-processing step (an estimate from the algorithms' operation counts),\n"
    "             beside the paper's values; no timing\n"
    "  all        everything available (default)\n";

int Bench(const ParsedArgs& a, int, char**) {
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

std::string Help() { return kHelp; }

}  // namespace

Command BenchCommand() {
  return {"bench",
          "bench [raycast|camera|radar|events|link|beam|pipeline|noise|flops|all]",
          "measure the hot paths",
          {},
          Help,
          Bench};
}

}  // namespace uavsim::cli
