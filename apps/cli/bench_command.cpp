// `uavsim bench` as typed: its usage, options and help (its body:
// apps/cli/bench.cpp; the command table: cli.h).
#include "apps/cli/cli.h"

namespace uavsim::cli {
namespace {

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

std::string Help() { return kHelp; }

}  // namespace

Command BenchCommand() {
  return {"bench",
          "bench [raycast|camera|radar|events|link|beam|pipeline|noise|flops|all]",
          "measure the hot paths",
          {},
          Help,
          RunBenchCommand};
}

}  // namespace uavsim::cli
